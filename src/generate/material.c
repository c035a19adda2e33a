/*
 * material.c — procedural materials and the images a BTF measurement of them
 * records.
 *
 * A material is a periodic height field h(u, w) in texel units (so every image
 * tiles seamlessly), an albedo texture, normals derived from h, and the
 * parameters of one reflectance model: Lambertian + a Blinn-Phong lobe, the
 * lobe optionally weighted by Fresnel-Schlick for a dielectric coat.
 *
 *   leather  cellular (Worley F2-F1) pebbles separated by creases plus fractal
 *            value noise: bumpy, irregular, mostly diffuse, brown with
 *            per-pebble and large-scale variation, dark creases.
 *   fabric   a plain weave: warp threads (columns) and weft threads (rows) of
 *            elliptical cross-section going over and under each other, with
 *            twisted-yarn ridges and deep gaps between threads: strong masking
 *            and self-shadowing, two thread colours.
 *   wood     lacquered wood: nearly flat; growth rings and fibre streaks in the
 *            albedo (domain-warped ring function), small pores; a glossy coat
 *            (sharp lobe whose strength follows Fresnel).
 *
 * Every random choice comes from a counter-based hash (splitmix64 finaliser)
 * of the seed, a per-feature salt and lattice coordinates, so a material is a
 * pure function of (name, size, seed) and of nothing else.
 *
 * Axis convention. Texture/image coordinates: u = column (x right), w = row
 * (y down in the image), row 0 at the top, and image row y is texture row y.
 * Directions (theta from the normal z, phi from +x towards +y) and the stored
 * normals use the camera frame a photometric-stereo user expects: x right,
 * y UP in the image (the row index grows towards -y), z towards the camera.
 * So a light at phi = 90 lights the image from its top edge, and a normal
 * tilted towards the top of the image has n.y > 0. A texture step (du, dw)
 * is the world step (du, -dw).
 *
 * Rendering (the rectified image of one (view, light) pair). For every texel
 * (x, y) of the reference plane z = 0 the view ray through (x, y, 0) is
 * marched down through the height field (bilinear, wrapping) from its top to
 * its bottom; the first crossing, refined by one secant step, is the visible
 * point (masking, parallax: raised points appear shifted away from the
 * camera). That point is shaded
 *     ambient*albedo + vis * (kd * albedo * max(0, n.l) + ks * (n.h)^shininess)
 * with vis the light's visibility: a march from the surface point towards the
 * light, soft at the edge (the light is a disc of radius ~2.3 degrees), and, for a
 * coat, ks = specular * F(v.h) / F(1) and kd = 1 - F(v.h) (Schlick), else
 * ks = specular and kd = 1. The lobe needs n.l > 0 and fades in over
 * n.l < 0.1, so light at grazing incidence brings no highlight.
 * The view march depends only on the view and the shadow march only on the
 * light, so both are precomputed maps (src/core/core.h) that a generator builds
 * once per direction; btf_material_render just builds both and combines them.
 * A view map holds 32 bytes per texel (hit point, normal, albedo), a light
 * map 4.
 */
#include <stdio.h>
#include "core/core.h"
#include "generate/material.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAT_PI 3.14159265358979323846
#define MAT_MAX_SIZE 16384       /* keeps size*size*3 well inside int */
#define MARCH_STEP 0.5f          /* horizontal march step, texels */
#define MARCH_MAX_THETA 88.0     /* grazing rays are marched as 88 degrees:
                                    at 90 a ray would never reach the surface */
#define LIGHT_HALF_WIDTH 0.04f   /* tan of the light's angular radius: shadow
                                    edges are soft over about 4.6 degrees */

/* ------------------------------------------------------------------ hashing */

static uint64_t mix64(uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* A uniform number in [0, 1) for lattice point (i, j) of feature `salt`. */
static double hash01(uint64_t seed, uint32_t salt, int64_t i, int64_t j)
{
    uint64_t h = mix64(seed ^ mix64((uint64_t)salt));
    h = mix64(h ^ (uint64_t)i);
    h = mix64(h ^ ((uint64_t)j * 0xD1B54A32D192ED03ull));
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

static int wrap_int(int64_t i, int n)
{
    int64_t r = i % n;
    return (int)(r < 0 ? r + n : r);
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

static double smoothstep(double e0, double e1, double x)
{
    double t = clampd((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

static double fract(double x)
{
    return x - floor(x);
}

/* ---------------------------------------------------------- periodic noise */

/* The noise context: every function below is periodic over a tile of n x n
 * texels, because lattices have an integer number of cells across it. */
typedef struct noise {
    uint64_t seed;
    int n;
} noise;

/* Value noise in [-1, 1] on a px x py lattice across the tile. */
static double value_noise(const noise *ns, uint32_t salt, int px, int py, double x, double y)
{
    double gx = x * px / ns->n, gy = y * py / ns->n;
    double fx0 = floor(gx), fy0 = floor(gy);
    double fx = gx - fx0, fy = gy - fy0;
    int i0 = wrap_int((int64_t)fx0, px), j0 = wrap_int((int64_t)fy0, py);
    int i1 = i0 + 1 == px ? 0 : i0 + 1, j1 = j0 + 1 == py ? 0 : j0 + 1;
    /* Quintic fade: continuous slope, so normals have no lattice creases. */
    double sx = fx * fx * fx * (fx * (fx * 6 - 15) + 10);
    double sy = fy * fy * fy * (fy * (fy * 6 - 15) + 10);
    double a = hash01(ns->seed, salt, i0, j0), b = hash01(ns->seed, salt, i1, j0);
    double c = hash01(ns->seed, salt, i0, j1), d = hash01(ns->seed, salt, i1, j1);
    double v = (a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy;
    return 2.0 * v - 1.0;
}

/* Fractal sum of `octaves` value noises, lattice doubling per octave; [-1, 1]. */
static double fbm(const noise *ns, uint32_t salt, int px, int py, int octaves, double x,
                  double y)
{
    double sum = 0, amp = 1, norm = 0;
    for (int o = 0; o < octaves; o++) {
        sum += amp * value_noise(ns, salt + (uint32_t)o, px << o, py << o, x, y);
        norm += amp;
        amp *= 0.5;
    }
    return sum / norm;
}

/* Periodic cellular noise on q x q jittered feature points: distances (in
 * cell units) to the nearest and second nearest point, and the nearest's id. */
typedef struct cell_hit {
    double f1, f2;
    int id;
} cell_hit;

static cell_hit worley(const noise *ns, uint32_t salt, int q, double x, double y)
{
    double gx = x * q / ns->n, gy = y * q / ns->n;
    double cx = floor(gx), cy = floor(gy);
    cell_hit r = {1e9, 1e9, 0};
    for (int dj = -1; dj <= 1; dj++) {
        for (int di = -1; di <= 1; di++) {
            int i = wrap_int((int64_t)cx + di, q), j = wrap_int((int64_t)cy + dj, q);
            /* Jitter kept off the cell border so pebbles keep a sane size. */
            double px = cx + di + 0.1 + 0.8 * hash01(ns->seed, salt, i, j);
            double py = cy + dj + 0.1 + 0.8 * hash01(ns->seed, salt + 1, i, j);
            double d = sqrt((px - gx) * (px - gx) + (py - gy) * (py - gy));
            if (d < r.f1) {
                r.f2 = r.f1;
                r.f1 = d;
                r.id = j * q + i;
            } else if (d < r.f2) {
                r.f2 = d;
            }
        }
    }
    return r;
}

/* Cells across the tile for a feature of about `texels`: at least one. */
static int cells_across(int n, double texels)
{
    long c = lround(n / texels);
    return c < 1 ? 1 : (int)c;
}

/* ---------------------------------------------------------------- materials */

typedef void (*material_fn)(btf_material *m, const noise *ns);

static void set_rgb(float *p, double r, double g, double b)
{
    p[0] = (float)r;
    p[1] = (float)g;
    p[2] = (float)b;
}

/* Leather: pebbles (Worley F2 - F1 is 0 on the border between two cells, so a
 * smoothstep of it raises the cell interiors and leaves creases between
 * them), domed a little, plus fractal micro-relief and a broad undulation. */
static void make_leather(btf_material *m, const noise *ns)
{
    int n = m->size, q = cells_across(n, 12.0);
    int pm = cells_across(n, 4.0), pb = cells_across(n, 48.0);
    for (int row = 0; row < n; row++) {
        for (int col = 0; col < n; col++) {
            double x = col + 0.5, y = row + 0.5;
            cell_hit c = worley(ns, 10, q, x, y);
            double pebble = smoothstep(0.0, 0.45, c.f2 - c.f1);
            double dome = 1.0 - clampd(c.f1 * c.f1, 0.0, 1.0);
            double micro = fbm(ns, 20, pm, pm, 3, x, y);
            double broad = fbm(ns, 30, pb, pb, 2, x, y);
            size_t k = (size_t)row * n + col;
            m->height[k] = (float)(1.6 * (pebble * (0.75 + 0.25 * dome) + 0.15 * micro +
                                          0.35 * broad));
            double tint = 0.9 + 0.2 * hash01(ns->seed, 40, c.id, 0);
            double stain = 1.0 + 0.25 * fbm(ns, 50, pb * 2, pb * 2, 3, x, y);
            double crease = 0.5 + 0.5 * pebble; /* dirt and shade in the creases */
            double s = tint * stain * crease;
            set_rgb(m->albedo + 3 * k, 0.34 * s * (1.0 + 0.06 * micro), 0.18 * s,
                    0.085 * s * (1.0 - 0.06 * micro));
        }
    }
    m->specular = 0.06f;
    m->shininess = 18.0f;
    m->fresnel0 = 0.0f;
    m->ambient = 0.06f;
}

/* Height of one thread of the weave at cross-thread offset c (in pitches,
 * [-0.5, 0.5)) and along-thread position t (in pitches): an ellipse of half
 * width `half` riding on a centre line that goes over (+amp) and under (-amp)
 * the crossing threads, with diagonal ridges of the yarn's twist. -1e9 where
 * the thread is absent (the gap between two threads). */
static double thread_height(double c, double t, int over_phase, double half, double amp,
                            double radius)
{
    if (fabs(c) >= half)
        return -1e9;
    double centre = amp * cos(MAT_PI * (t - 0.5 + over_phase));
    double e = sqrt(1.0 - (c / half) * (c / half));
    double twist = 0.08 * radius * e * cos(2.0 * MAT_PI * (3.0 * t + 1.2 * c));
    return centre + radius * e + twist;
}

/* Fabric: plain weave. Warp thread i (a column of the image) passes over weft
 * thread j (a row) where i + j is even. The tile holds an even number of
 * threads each way so the over-under pattern is periodic. */
static void make_fabric(btf_material *m, const noise *ns)
{
    int n = m->size, k2 = 2 * cells_across(n, 16.0); /* threads across */
    double pitch = (double)n / k2;
    double half = 0.43, amp = 0.12 * pitch, radius = 0.28 * pitch;
    double floor_h = -(amp + 0.3 * radius);
    static const double warp_rgb[3] = {0.10, 0.16, 0.42}, weft_rgb[3] = {0.62, 0.48, 0.22};
    int streak = cells_across(n, 1.5);
    for (int row = 0; row < n; row++) {
        for (int col = 0; col < n; col++) {
            double x = col + 0.5, y = row + 0.5;
            double fx = x / pitch, fy = y / pitch;
            double fi = floor(fx), fj = floor(fy);
            int i = wrap_int((int64_t)fi, k2), j = wrap_int((int64_t)fj, k2);
            double cx = fx - fi - 0.5, cy = fy - fj - 0.5;
            double hw = thread_height(cx, fy, i, half, amp, radius);
            double hf = thread_height(cy, fx, j + 1, half, amp, radius);
            double h = floor_h, rgb[3];
            size_t k = (size_t)row * n + col;
            if (hw >= hf && hw > floor_h) {
                /* Fibres run along the thread: noise stretched along y. */
                double f = 0.85 + 0.3 * (0.5 + 0.5 * value_noise(ns, 60, streak, k2, x, y));
                double tint = (0.9 + 0.2 * hash01(ns->seed, 61, i, 0)) * f;
                for (int c = 0; c < 3; c++)
                    rgb[c] = warp_rgb[c] * tint;
                h = hw;
            } else if (hf > floor_h) {
                double f = 0.85 + 0.3 * (0.5 + 0.5 * value_noise(ns, 62, k2, streak, x, y));
                double tint = (0.9 + 0.2 * hash01(ns->seed, 63, j, 0)) * f;
                for (int c = 0; c < 3; c++)
                    rgb[c] = weft_rgb[c] * tint;
                h = hf;
            } else {
                /* Through a gap: the back of the cloth, dark. */
                for (int c = 0; c < 3; c++)
                    rgb[c] = 0.25 * (warp_rgb[c] + weft_rgb[c]) * 0.5;
            }
            m->height[k] = (float)h;
            set_rgb(m->albedo + 3 * k, rgb[0], rgb[1], rgb[2]);
        }
    }
    m->specular = 0.04f;
    m->shininess = 10.0f;
    m->fresnel0 = 0.0f;
    m->ambient = 0.05f;
}

/* Wood: growth rings run along x; the ring coordinate is y warped by a sine
 * and fractal noise (both periodic), and its fractional part darkens towards
 * the latewood, resetting sharply at the ring boundary. Fibre streaks are
 * noise stretched along x; pores are sparse short dashes, more in earlywood.
 * The lacquer levels the relief almost flat. */
static void make_wood(btf_material *m, const noise *ns)
{
    int n = m->size, rings = cells_across(n, 16.0);
    int streak_y = cells_across(n, 1.5), pore_x = cells_across(n, 9.0);
    int pore_y = cells_across(n, 2.0);
    double phase = 2.0 * MAT_PI * hash01(ns->seed, 70, 0, 0);
    for (int row = 0; row < n; row++) {
        for (int col = 0; col < n; col++) {
            double x = col + 0.5, y = row + 0.5;
            double warp = 0.3 * sin(2.0 * MAT_PI * x / n + phase) + 0.6 * fbm(ns, 71, 2, 2, 3, x, y);
            double yw = y + warp * n / rings; /* y along the grain; periodic */
            double t = fract(yw * rings / n);
            double late = pow(smoothstep(0.3, 0.97, t), 1.5);
            /* Fibres follow the grain: noise long along x, short across. */
            double streak = value_noise(ns, 75, 3, streak_y, x, yw);
            double gx = x * pore_x / n, gy = yw * pore_y / n;
            double fi = floor(gx), fj = floor(gy);
            int pi = wrap_int((int64_t)fi, pore_x), pj = wrap_int((int64_t)fj, pore_y);
            double pore = 0.0;
            if (hash01(ns->seed, 76, pi, pj) < 0.04 + 0.12 * (1.0 - late)) {
                double ex = (gx - fi - 0.5) / 0.4, ey = (gy - fj - 0.5) / 0.45;
                double d = ex * ex + ey * ey;
                pore = d < 1.0 ? 1.0 - d : 0.0;
            }
            size_t k = (size_t)row * n + col;
            /* The lacquer fills the pores and levels the fibres: tiny relief. */
            m->height[k] = (float)(0.05 * streak - 0.08 * pore + 0.04 * late);
            double s = (1.0 + 0.12 * streak) * (1.0 - 0.5 * pore);
            set_rgb(m->albedo + 3 * k, (0.62 + (0.30 - 0.62) * late) * s,
                    (0.40 + (0.15 - 0.40) * late) * s, (0.20 + (0.06 - 0.20) * late) * s);
        }
    }
    m->specular = 0.15f; /* lobe peak at normal incidence; grows with Fresnel */
    m->shininess = 250.0f;
    m->fresnel0 = 0.04f;
    m->ambient = 0.03f;
}

typedef struct material_entry {
    const char *name;
    material_fn make;
} material_entry;

static const material_entry materials[] = {
    {"leather", make_leather},
    {"fabric", make_fabric},
    {"wood", make_wood},
};
#define N_MATERIALS (sizeof materials / sizeof materials[0])

static const char *const material_names[N_MATERIALS + 1] = {"leather", "fabric", "wood", NULL};

const char *const *btf_material_names(void)
{
    return material_names;
}

void btf_material_normals_from_height(btf_material *m)
{
    int n = m->size;
    for (int row = 0; row < n; row++) {
        int up = row == 0 ? n - 1 : row - 1, down = row + 1 == n ? 0 : row + 1;
        for (int col = 0; col < n; col++) {
            int left = col == 0 ? n - 1 : col - 1, right = col + 1 == n ? 0 : col + 1;
            double gx = 0.5 * ((double)m->height[(size_t)row * n + right] -
                               m->height[(size_t)row * n + left]);
            /* World +y is up the image, towards the previous row. */
            double gy = 0.5 * ((double)m->height[(size_t)up * n + col] -
                               m->height[(size_t)down * n + col]);
            double len = sqrt(gx * gx + gy * gy + 1.0);
            float *p = m->normal + 3 * ((size_t)row * n + col);
            set_rgb(p, -gx / len, -gy / len, 1.0 / len);
        }
    }
}

/* Zero mean height: the reference plane z = 0 then sits in the middle of the
 * relief, so parallax shifts the image as much one way as the other. */
static void centre_height(btf_material *m)
{
    size_t count = (size_t)m->size * m->size;
    double sum = 0;
    for (size_t k = 0; k < count; k++)
        sum += m->height[k];
    float mean = (float)(sum / (double)count);
    for (size_t k = 0; k < count; k++)
        m->height[k] -= mean;
}

int btf_material_make(const char *name, int size, uint64_t seed, btf_material *m,
                      btf_error *err)
{
    if (!m)
        return btf_fail(err, BTF_E_ARG, "material: no output given");
    memset(m, 0, sizeof *m);
    if (!name)
        return btf_fail(err, BTF_E_ARG, "material: no name given");
    const material_entry *e = NULL;
    for (size_t i = 0; i < N_MATERIALS; i++)
        if (!strcmp(name, materials[i].name))
            e = &materials[i];
    if (!e)
        return btf_fail(err, BTF_E_ARG, "unknown material '%s' (expected leather, fabric or wood)",
                        name);
    if (size < 1 || size > MAT_MAX_SIZE)
        return btf_fail(err, BTF_E_ARG, "material %s: size %d out of range 1..%d", name, size,
                        MAT_MAX_SIZE);
    size_t count = (size_t)size * size;
    float *block = btf_alloc(count * 7, sizeof(float), err);
    if (!block)
        return BTF_E_NOMEM;
    snprintf(m->name, sizeof m->name, "%s", name);
    m->size = size;
    m->height = block;
    m->normal = block + count;
    m->albedo = block + 4 * count;
    noise ns = {seed, size};
    e->make(m, &ns);
    centre_height(m);
    btf_material_normals_from_height(m);
    return BTF_OK;
}

void btf_material_free(btf_material *m)
{
    if (!m)
        return;
    /* make() allocates one block; height is its start. */
    free(m->height);
    memset(m, 0, sizeof *m);
}

/* ------------------------------------------------------------ checking input */

static int check_material(const btf_material *m, btf_error *err)
{
    if (!m || !m->height || !m->normal || !m->albedo)
        return btf_fail(err, BTF_E_ARG, "material: not made (NULL arrays)");
    if (m->size < 1 || m->size > MAT_MAX_SIZE)
        return btf_fail(err, BTF_E_ARG, "material %s: size %d out of range 1..%d", m->name,
                        m->size, MAT_MAX_SIZE);
    if (!isfinite(m->specular) || !isfinite(m->shininess) || !isfinite(m->fresnel0) ||
        !isfinite(m->ambient) || m->shininess < 0 || m->fresnel0 < 0 || m->fresnel0 > 1)
        return btf_fail(err, BTF_E_ARG,
                        "material %s: reflectance parameters not finite or out of range "
                        "(shininess >= 0, fresnel0 in [0, 1])",
                        m->name);
    return BTF_OK;
}

static int check_dir(const char *what, btf_dir d, btf_error *err)
{
    if (!(d.theta >= 0.0 && d.theta <= 90.0) || !isfinite(d.phi))
        return btf_fail(err, BTF_E_ARG, "%s direction (theta %g, phi %g): theta must be in "
                        "[0, 90] degrees and phi finite", what, d.theta, d.phi);
    return BTF_OK;
}

static void dir_vec(btf_dir d, float v[3])
{
    double dv[3];
    btf_dir_to_vec(d, dv);
    for (int c = 0; c < 3; c++)
        v[c] = (float)dv[c];
}

/* ------------------------------------------------------------ height marching */

/* The height field with a wrap table, so a march can sample anywhere within
 * `pad` texels outside the tile without a modulo per sample. */
typedef struct field {
    const float *h;
    int n, pad;
    int *wrap;   /* wrap[k] = (k - pad) mod n, for k in [0, n + 2 pad + 2) */
    float lo, hi;
} field;

static int field_init(field *f, const btf_material *m, double reach, btf_error *err)
{
    size_t count = (size_t)m->size * m->size;
    f->h = m->height;
    f->n = m->size;
    f->lo = f->hi = m->height[0];
    for (size_t k = 0; k < count; k++) {
        float v = m->height[k];
        if (!isfinite(v))
            return btf_fail(err, BTF_E_DATA, "material %s: height at texel %zu is not finite",
                            m->name, k);
        f->lo = v < f->lo ? v : f->lo;
        f->hi = v > f->hi ? v : f->hi;
    }
    double span = reach * fmax(fabs((double)f->lo), fabs((double)f->hi)) * 2.0 + 3.0;
    if (span > (double)(1 << 24))
        return btf_fail(err, BTF_E_ARG, "material %s: relief (%g..%g texels) too deep to march",
                        m->name, f->lo, f->hi);
    f->pad = (int)ceil(span);
    int len = f->n + 2 * f->pad + 2;
    f->wrap = btf_alloc((size_t)len, sizeof(int), err);
    if (!f->wrap)
        return BTF_E_NOMEM;
    for (int k = 0; k < len; k++)
        f->wrap[k] = wrap_int((int64_t)k - f->pad, f->n);
    return BTF_OK;
}

/* Bilinear height at (u, w); u, w within pad texels of the tile. */
static inline float field_at(const field *f, float u, float w)
{
    float uu = u + (float)f->pad, ww = w + (float)f->pad;
    int iu = (int)uu, iw = (int)ww;
    float fu = uu - (float)iu, fw = ww - (float)iw;
    const float *r0 = f->h + (size_t)f->wrap[iw] * f->n;
    const float *r1 = f->h + (size_t)f->wrap[iw + 1] * f->n;
    int c0 = f->wrap[iu], c1 = f->wrap[iu + 1];
    float a = r0[c0] + (r0[c1] - r0[c0]) * fu;
    float b = r1[c0] + (r1[c1] - r1[c0]) * fu;
    return a + (b - a) * fw;
}

/* tan(theta), capped where the march would become endless. */
static double march_tan(double theta)
{
    return tan(fmin(theta, MARCH_MAX_THETA) * (MAT_PI / 180.0));
}

/* Bilinear weights and wrapped corner indices of (u, w) in [0, n). */
typedef struct bilerp {
    size_t k00, k01, k10, k11;
    float fu, fw;
} bilerp;

static inline bilerp bilerp_at(int n, float u, float w)
{
    int c0 = (int)u, r0 = (int)w;
    c0 = c0 >= n ? n - 1 : c0;
    r0 = r0 >= n ? n - 1 : r0;
    int c1 = c0 + 1 == n ? 0 : c0 + 1, r1 = r0 + 1 == n ? 0 : r0 + 1;
    bilerp b = {(size_t)r0 * n + c0, (size_t)r0 * n + c1, (size_t)r1 * n + c0,
                (size_t)r1 * n + c1, u - (float)c0, w - (float)r0};
    return b;
}

static inline float bilerp_get(const bilerp *b, const float *a, int stride, int c)
{
    float p = a[b->k00 * stride + c] + (a[b->k01 * stride + c] - a[b->k00 * stride + c]) * b->fu;
    float q = a[b->k10 * stride + c] + (a[b->k11 * stride + c] - a[b->k10 * stride + c]) * b->fu;
    return p + (q - p) * b->fw;
}

/* u mod n in [0, n). Hits are rarely more than a tile away, so one add or
 * subtract usually does, avoiding a division per texel. */
static inline float wrap_coord(float u, int n)
{
    float fn = (float)n;
    if (u < 0.0f || u >= fn) {
        if (u >= -fn && u < 2.0f * fn)
            u = u < 0.0f ? u + fn : u - fn;
        else
            u -= fn * floorf(u / fn);
    }
    return u >= fn || u < 0.0f ? 0.0f : u; /* rounding can land on fn */
}

/* --------------------------------------------------------------- view maps */

/* The height at which the view ray through (x, y, 0) first meets the
 * surface. On the ray, height z is at (x + a z, y + b z). The march goes down
 * from the top of the relief, where the ray is above the surface, to its
 * bottom, where it cannot be, so a crossing always exists. */
static float view_hit_z(const field *f, float x, float y, float a, float b, int steps)
{
    float top = f->hi, dz = (f->hi - f->lo) / (float)steps;
    float zp = top, fp = zp - field_at(f, x + a * zp, y + b * zp);
    if (fp <= 0.0f)
        return zp;
    for (int k = 1; k <= steps; k++) {
        float z = top - dz * (float)k;
        float fz = z - field_at(f, x + a * z, y + b * z);
        if (fz <= 0.0f)
            return zp - fp * (zp - z) / (fp - fz); /* secant: fp > 0 >= fz */
        zp = z;
        fp = fz;
    }
    return f->lo;
}

int btf_view_map_make(const btf_material *m, btf_dir view, btf_view_map **out,
                      btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "view map: no output given");
    *out = NULL;
    int rc = check_material(m, err);
    if (rc || (rc = check_dir("view", view, err)))
        return rc;
    double t = march_tan(view.theta);
    field f;
    if ((rc = field_init(&f, m, t, err)))
        return rc;
    int n = m->size;
    size_t count = (size_t)n * n;
    btf_view_map *vm = btf_alloc(1, sizeof *vm, err);
    float *block = vm ? btf_alloc(count * 8, sizeof(float), err) : NULL;
    if (!block) {
        free(vm);
        free(f.wrap);
        return BTF_E_NOMEM;
    }
    vm->size = n;
    vm->hit = block;
    vm->normal = block + 2 * count;
    vm->albedo = block + 5 * count;

    /* Ray offset per unit height, in texture coordinates (rows grow to -y). */
    double phi = view.phi * (MAT_PI / 180.0);
    float a = (float)(t * cos(phi)), b = (float)(-t * sin(phi));
    int steps = (int)ceil((double)(f.hi - f.lo) * t / MARCH_STEP);
    int flat = steps < 1 || t < 1e-9;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            size_t k = (size_t)y * n + x;
            float u = (float)x, w = (float)y;
            if (!flat) {
                float z = view_hit_z(&f, (float)x, (float)y, a, b, steps);
                u = wrap_coord((float)x + a * z, n);
                w = wrap_coord((float)y + b * z, n);
            }
            vm->hit[2 * k] = u;
            vm->hit[2 * k + 1] = w;
            bilerp bl = bilerp_at(n, u, w);
            float nv[3];
            for (int c = 0; c < 3; c++) {
                nv[c] = bilerp_get(&bl, m->normal, 3, c);
                vm->albedo[3 * k + c] = bilerp_get(&bl, m->albedo, 3, c);
            }
            float len = sqrtf(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
            if (!(len > 1e-6f) || !isfinite(len)) {
                nv[0] = nv[1] = 0.0f;
                nv[2] = len = 1.0f;
            }
            float inv = 1.0f / len;
            for (int c = 0; c < 3; c++)
                vm->normal[3 * k + c] = nv[c] * inv;
        }
    }
    free(f.wrap);
    *out = vm;
    return BTF_OK;
}

void btf_view_map_free(btf_view_map *vm)
{
    if (!vm)
        return;
    free(vm->hit);
    free(vm);
}

/* -------------------------------------------------------------- light maps */

/* Visibility of the light from (x, y, h0): march towards it, horizontally
 * along (cu, cw), rising 1/t per texel, until above the relief. The smallest
 * clearance angle (height over the ray / distance) decides: the light is a
 * disc of angular radius ~LIGHT_HALF_WIDTH, half hidden at clearance 0. */
static float light_vis(const field *f, float x, float y, float h0, float cu, float cw,
                       float inv_t, float reach)
{
    float worst = 1e30f;
    for (int k = 1;; k++) {
        float d = MARCH_STEP * (float)k;
        if (d > reach)
            break;
        float c = (h0 + d * inv_t - field_at(f, x + cu * d, y + cw * d)) / d;
        worst = c < worst ? c : worst;
        if (worst <= -LIGHT_HALF_WIDTH)
            return 0.0f;
    }
    float v = 0.5f + worst * (0.5f / LIGHT_HALF_WIDTH);
    return v > 1.0f ? 1.0f : v < 0.0f ? 0.0f : v;
}

int btf_light_map_make(const btf_material *m, btf_dir light, btf_light_map **out,
                       btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "light map: no output given");
    *out = NULL;
    int rc = check_material(m, err);
    if (rc || (rc = check_dir("light", light, err)))
        return rc;
    double t = march_tan(light.theta);
    field f;
    if ((rc = field_init(&f, m, t, err)))
        return rc;
    int n = m->size;
    size_t count = (size_t)n * n;
    btf_light_map *lm = btf_alloc(1, sizeof *lm, err);
    float *vis = lm ? btf_alloc(count, sizeof(float), err) : NULL;
    if (!vis) {
        free(lm);
        free(f.wrap);
        return BTF_E_NOMEM;
    }
    lm->size = n;
    lm->vis = vis;
    double phi = light.phi * (MAT_PI / 180.0);
    float cu = (float)cos(phi), cw = (float)-sin(phi);
    float inv_t = t > 1e-9 ? (float)(1.0 / t) : 0.0f;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            size_t k = (size_t)y * n + x;
            float h0 = m->height[k];
            float reach = (float)((double)(f.hi - h0) * t);
            vis[k] = t > 1e-9 && reach >= MARCH_STEP
                         ? light_vis(&f, (float)x, (float)y, h0, cu, cw, inv_t, reach)
                         : 1.0f;
        }
    }
    free(f.wrap);
    *out = lm;
    return BTF_OK;
}

void btf_light_map_free(btf_light_map *lm)
{
    if (!lm)
        return;
    free(lm->vis);
    free(lm);
}

/* ------------------------------------------------------------------ shading */

/* What is the same for every texel of one (view, light) pair. */
typedef struct shade_consts {
    float l[3], h[3];
    float kd, ks, shininess, ambient;
    float cut; /* n.h below which the lobe is negligible (< 1e-7) */
} shade_consts;

static shade_consts shade_setup(const btf_material *m, btf_dir view, btf_dir light)
{
    shade_consts s;
    float v[3];
    dir_vec(view, v);
    dir_vec(light, s.l);
    float hv[3] = {v[0] + s.l[0], v[1] + s.l[1], v[2] + s.l[2]};
    float len = sqrtf(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
    if (!(len > 1e-6f)) { /* opposite grazing directions: no half vector */
        hv[0] = hv[1] = 0.0f;
        hv[2] = len = 1.0f;
    }
    for (int c = 0; c < 3; c++)
        s.h[c] = hv[c] / len;
    float vh = v[0] * s.h[0] + v[1] * s.h[1] + v[2] * s.h[2];
    vh = vh < 0.0f ? 0.0f : vh > 1.0f ? 1.0f : vh;
    s.kd = 1.0f;
    s.ks = m->specular;
    if (m->fresnel0 > 0.0f) {
        /* Schlick; the coat reflects F and passes 1 - F to the base. */
        float q = 1.0f - vh, q5 = q * q * q * q * q;
        float fr = m->fresnel0 + (1.0f - m->fresnel0) * q5;
        s.kd = 1.0f - fr;
        s.ks = m->specular * fr / m->fresnel0;
    }
    s.shininess = m->shininess;
    s.ambient = m->ambient;
    s.cut = s.shininess > 0.0f ? expf(logf(1e-7f) / s.shininess) : 0.0f;
    return s;
}

int btf_material_render_maps(const btf_material *m, const btf_view_map *vm,
                             const btf_light_map *lm, btf_dir view, btf_dir light,
                             btf_image *out, btf_error *err)
{
    if (!out)
        return btf_fail(err, BTF_E_ARG, "render: no output image given");
    int rc = check_material(m, err);
    if (rc || (rc = check_dir("view", view, err)) || (rc = check_dir("light", light, err)))
        return rc;
    if (!vm || !lm || vm->size != m->size || lm->size != m->size)
        return btf_fail(err, BTF_E_ARG, "render: maps missing or not of material %s (size %d)",
                        m->name, m->size);
    int n = m->size;
    if ((rc = btf_image_alloc(out, n, n, 3, err)))
        return rc;
    shade_consts s = shade_setup(m, view, light);
    size_t count = (size_t)n * n;
    float *o = out->data;
    for (size_t k = 0; k < count; k++) {
        const float *nv = vm->normal + 3 * k, *al = vm->albedo + 3 * k;
        bilerp bl = bilerp_at(n, vm->hit[2 * k], vm->hit[2 * k + 1]);
        float vis = bilerp_get(&bl, lm->vis, 1, 0);
        float ndl = nv[0] * s.l[0] + nv[1] * s.l[1] + nv[2] * s.l[2];
        float diff = 0.0f, spec = 0.0f;
        if (ndl > 0.0f && vis > 0.0f) {
            diff = vis * s.kd * ndl;
            float ndh = nv[0] * s.h[0] + nv[1] * s.h[1] + nv[2] * s.h[2];
            /* The lobe fades out over the last ~6 degrees before the
             * terminator: light at grazing incidence brings no energy. */
            float fade = ndl < 0.1f ? 10.0f * ndl : 1.0f;
            if (ndh > s.cut)
                spec = vis * fade * s.ks * powf(ndh, s.shininess);
        }
        for (int c = 0; c < 3; c++)
            o[3 * k + c] = al[c] * (s.ambient + diff) + spec;
    }
    return BTF_OK;
}

int btf_material_render(const btf_material *m, btf_dir view, btf_dir light,
                        btf_image *out, btf_error *err)
{
    btf_view_map *vm = NULL;
    btf_light_map *lm = NULL;
    int rc = btf_view_map_make(m, view, &vm, err);
    if (!rc)
        rc = btf_light_map_make(m, light, &lm, err);
    if (!rc)
        rc = btf_material_render_maps(m, vm, lm, view, light, out, err);
    btf_view_map_free(vm);
    btf_light_map_free(lm);
    return rc;
}
