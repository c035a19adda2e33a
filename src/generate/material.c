/*
 * material.c — procedural materials: the surfaces whose BTF btfcar
 * generates to test the analysis of the paper's section II on a known
 * truth (height, normals, albedo).
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
 * Rendering the images a BTF measurement records is generate/render.c.
 */
#include <stdio.h>
#include "core/core.h"
#include "generate/material.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAT_PI 3.14159265358979323846

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
    int i0 = btf_wrap_int((int64_t)fx0, px), j0 = btf_wrap_int((int64_t)fy0, py);
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
            int i = btf_wrap_int((int64_t)cx + di, q), j = btf_wrap_int((int64_t)cy + dj, q);
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

typedef void (*material_fn)(btf_procedural *m, const noise *ns);

static void set_rgb(float *p, double r, double g, double b)
{
    p[0] = (float)r;
    p[1] = (float)g;
    p[2] = (float)b;
}

/* Leather: pebbles (Worley F2 - F1 is 0 on the border between two cells, so a
 * smoothstep of it raises the cell interiors and leaves creases between
 * them), domed a little, plus fractal micro-relief and a broad undulation. */
static void make_leather(btf_procedural *m, const noise *ns)
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
static void make_fabric(btf_procedural *m, const noise *ns)
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
            int i = btf_wrap_int((int64_t)fi, k2), j = btf_wrap_int((int64_t)fj, k2);
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
static void make_wood(btf_procedural *m, const noise *ns)
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
            int pi = btf_wrap_int((int64_t)fi, pore_x), pj = btf_wrap_int((int64_t)fj, pore_y);
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

const char *const *btf_procedural_names(void)
{
    return material_names;
}

void btf__material_normals_from_height(btf_procedural *m)
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
static void centre_height(btf_procedural *m)
{
    size_t count = (size_t)m->size * m->size;
    double sum = 0;
    for (size_t k = 0; k < count; k++)
        sum += m->height[k];
    float mean = (float)(sum / (double)count);
    for (size_t k = 0; k < count; k++)
        m->height[k] -= mean;
}

btf_status btf_procedural_make(const char *name, int size, uint64_t seed, btf_procedural *m,
                             btf_error *err)
{
    if (!m)
        return btf__fail(err, BTF_E_ARG, "material: no output given");
    memset(m, 0, sizeof *m);
    if (!name)
        return btf__fail(err, BTF_E_ARG, "material: no name given");
    const material_entry *e = NULL;
    for (size_t i = 0; i < N_MATERIALS; i++)
        if (!strcmp(name, materials[i].name))
            e = &materials[i];
    if (!e)
        return btf__fail(err, BTF_E_ARG, "unknown material '%s' (expected leather, fabric or wood)",
                         name);
    if (size < 1 || size > BTF_MATERIAL_MAX_SIZE)
        return btf__fail(err, BTF_E_ARG, "material %s: size %d out of range 1..%d", name, size,
                         BTF_MATERIAL_MAX_SIZE);
    size_t count = (size_t)size * size;
    float *block = btf__alloc(count * 7, sizeof(float), err);
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
    btf__material_normals_from_height(m);
    return BTF_OK;
}

void btf_procedural_free(btf_procedural *m)
{
    if (!m)
        return;
    /* make() allocates one block; height is its start. */
    free(m->height);
    memset(m, 0, sizeof *m);
}
