// match_lab.glsl -- CIE L*a*b* and the Lab maps of colour matching on the
// GPU (docs/gpu.md, "Colour matching on the device"): src/synth/colour_lab.c's
// lab_pixel, rgb_pixel, cube_root and lab_map_at, their operations in their
// order, every result `precise` (no contraction into FMA, no reassociation),
// comparisons written as the C code's ternaries (a NaN takes the second
// operand): so lavapipe gives the CPU's bits. The image is one float array
// over bindings 0-7 (gpu/synth_gpu.h: float f in buffer f / cap at f % cap).
// The including shader declares Ints pi[], Floats pf[], Img0..Img7 and
// Pattern pat[].

float img_read(int f)
{
    int cap = pi[BTF_MP_CAP];
    int b = f / cap;
    int i = f - b * cap;
    if (b < 4)
        return b == 0 ? img0[i] : b == 1 ? img1[i] : b == 2 ? img2[i] : img3[i];
    return b == 4 ? img4[i] : b == 5 ? img5[i] : b == 6 ? img6[i] : img7[i];
}

// Pixel p of the image, multiplied by the structure layer's pattern as
// btf__structure_apply_row (src/model/structure_map.c).
vec3 pixel_read(int x, int y)
{
    int f = pi[BTF_MP_OFF] + 3 * (y * pi[BTF_MP_WIDTH] + x);
    precise vec3 c = vec3(img_read(f), img_read(f + 1), img_read(f + 2));
    int ch = pi[BTF_MP_PCH];
    if (ch > 0) {
        int q = ((y % pi[BTF_MP_PH]) * pi[BTF_MP_PW] + x % pi[BTF_MP_PW]) * ch;
        precise float r = c.x * pat[q];
        precise float g = c.y * pat[q + (ch == 3 ? 1 : 0)];
        precise float b = c.z * pat[q + (ch == 3 ? 2 : 0)];
        c = vec3(r, g, b);
    }
    return c;
}

float cube_root(float t)
{
    precise float third = pf[BTF_MF_CONST + 4];
    precise float fi = float(floatBitsToInt(t)) * third;
    float r = intBitsToFloat(pi[BTF_MP_MAGIC] - int(fi));
    for (int k = 0; k < 3; k++) {
        precise float r3 = r * r * r;
        precise float nr = r * (4.0 - t * r3) * third;
        r = nr;
    }
    precise float root = t * (r * r);
    return root;
}

float lab_f(float t)
{
    float t0 = pf[BTF_MF_CONST];
    precise float linear = pf[BTF_MF_CONST + 1] * t + pf[BTF_MF_CONST + 2];
    float root = cube_root(t > t0 ? t : t0);
    return t > t0 ? root : linear;
}

float lab_f_inv(float f)
{
    precise float linear = (f - pf[BTF_MF_CONST + 2]) * pf[BTF_MF_CONST + 9];
    precise float cube = f * f * f;
    return f > pf[BTF_MF_CONST + 3] ? cube : linear;
}

float to_xyz(int i, int k)
{
    return pf[BTF_MF_TO_XYZ + 3 * i + k];
}

float to_rgb(int k, int i)
{
    return pf[BTF_MF_TO_RGB + 3 * k + i];
}

vec3 lab_pixel(vec3 rgb)
{
    float v[3];
    float lmax = pf[BTF_MF_CONST + 5];
    for (int k = 0; k < 3; k++) {
        precise float s = rgb[k] * pf[BTF_MF_SCALE];
        s = s > 0.0 ? s : 0.0;
        v[k] = s < lmax ? s : lmax;
    }
    float f[3];
    for (int i = 0; i < 3; i++) {
        precise float x = to_xyz(i, 0) * v[0] + to_xyz(i, 1) * v[1] + to_xyz(i, 2) * v[2];
        f[i] = lab_f(x);
    }
    precise float l = 116.0 * f[1] - 16.0;
    precise float a = 500.0 * (f[0] - f[1]);
    precise float b = 200.0 * (f[1] - f[2]);
    return vec3(l, a, b);
}

vec3 rgb_pixel(vec3 lab)
{
    precise float fy = (lab.x + 16.0) * pf[BTF_MF_CONST + 6];
    precise float fx = fy + lab.y * pf[BTF_MF_CONST + 7];
    precise float fz = fy - lab.z * pf[BTF_MF_CONST + 8];
    float xyz[3] = float[3](lab_f_inv(fx), lab_f_inv(fy), lab_f_inv(fz));
    float o[3];
    for (int k = 0; k < 3; k++) {
        precise float v = (to_rgb(k, 0) * xyz[0] + to_rgb(k, 1) * xyz[1] + to_rgb(k, 2) * xyz[2]) *
                          pf[BTF_MF_INV];
        float lo = pf[BTF_MF_LO + k], hi = pf[BTF_MF_HI + k];
        v = v > lo ? v : lo;
        o[k] = v < hi ? v : hi;
    }
    return vec3(o[0], o[1], o[2]);
}

// Channel c's map at v (lab_map_at).
float map_at(int c, float v)
{
    int m = BTF_MF_MAPS + c * BTF_MF_MAP_FLOATS;
    precise float t = (v - pf[m]) * pf[m + 1];
    t = t > 0.0 ? t : 0.0;
    t = t < float(BTF_MATCH_SEGS) ? t : float(BTF_MATCH_SEGS);
    int i = int(t);
    i = i < BTF_MATCH_SEGS - 1 ? i : BTF_MATCH_SEGS - 1;
    precise float r = pf[m + 2 + i] + (t - float(i)) * pf[m + 2 + BTF_MATCH_SEGS + 1 + i];
    return r;
}
