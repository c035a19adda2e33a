/*
 * colour_lab.c — CIE L*a*b* for colour matching (docs/synthesis.md,
 * "Colour matching"): the space the texture distances measure
 * first-order statistics in (measure/lab.c, through OpenCV), here in
 * plain C so that the analysis (the exemplar's quantiles) and the
 * synthesis (the output's, and the map back) convert identically on every
 * path, the GPU's output included (btf_gpu_synthesise matches on the host).
 * The constants are OpenCV's for COLOR_RGB2Lab on floats (sRGB primaries,
 * D65 white, the CIE's linear segment below (6/29)^3), so that a map made
 * here is measured in the same space; the inverse matrix is OpenCV's
 * XYZ-to-RGB, folded with the white point into float matrices. The
 * conversions run in float, a row at a time (GCC vectorises them).
 */
#include "core/core.h"
#include "synth/synth.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const double RGB_TO_XYZ[3][3] = {{0.412453, 0.357580, 0.180423},
                                        {0.212671, 0.715160, 0.072169},
                                        {0.019334, 0.119193, 0.950227}};
static const double XYZ_TO_RGB[3][3] = {{3.240479, -1.53715, -0.498535},
                                        {-0.969256, 1.875991, 0.041556},
                                        {0.055648, -0.204043, 1.057311}};
static const double WHITE[3] = {0.950456, 1.0, 1.088754};
#define LAB_T0 0.008856f    /* (6/29)^3: below it the CIE's linear segment */
#define LAB_SLOPE 7.787f    /* (29/6)^2 / 3 */
#define LAB_F0 (16.0f / 116.0f)
#define LAB_F_T0 0.206893f  /* f(LAB_T0): below it the inverse is linear */
#define LAB_RCBRT_MAGIC 0x54a21000 /* t^(-1/3)'s exponent-bit estimate */
/* Light above this (after the exposure) is taken as this: its L* is above
 * 10,000 and its a*, b* far outside [-128, 128], where every map is flat,
 * and the cube root's cubes stay far from the float limit. */
#define LAB_LIGHT_MAX 1e6f

/* The conversion's constants in float: the matrices with the white point
 * folded in, made once from the double constants (so every caller rounds
 * them the same way). */
typedef struct lab_consts {
    float to_xyz[3][3]; /* RGB_TO_XYZ[i][k] / WHITE[i] */
    float to_rgb[3][3]; /* XYZ_TO_RGB[k][i] * WHITE[i] */
} lab_consts;

static lab_consts lab_consts_make(void)
{
    lab_consts c;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            c.to_xyz[i][k] = (float)(RGB_TO_XYZ[i][k] / WHITE[i]);
            c.to_rgb[k][i] = (float)(XYZ_TO_RGB[k][i] * WHITE[i]);
        }
    return c;
}

void btf__lab_constants(float to_xyz[9], float to_rgb[9], float k[10], int32_t *magic)
{
    const lab_consts c = lab_consts_make();
    memcpy(to_xyz, c.to_xyz, 9 * sizeof(float));
    memcpy(to_rgb, c.to_rgb, 9 * sizeof(float));
    const float v[10] = {LAB_T0, LAB_SLOPE, LAB_F0, LAB_F_T0, 1.0f / 3.0f, LAB_LIGHT_MAX,
                         1.0f / 116.0f, 1.0f / 500.0f, 1.0f / 200.0f, 1.0f / LAB_SLOPE};
    memcpy(k, v, sizeof v);
    *magic = LAB_RCBRT_MAGIC;
}

/* The cube root of t in [LAB_T0, LAB_LIGHT_MAX] as t r^2, r = t^(-1/3) by
 * Newton's iteration r (4 - t r^3) / 3 from an estimate made of the
 * exponent bits (within 7 per cent; each step squares the error: three
 * leave 4.5e-7, a few float roundings). Multiplies only, no branch: the
 * AVX2 loops below do the same operations in the same order, so both give
 * the same bits (libm's cbrt made colour matching cost three times the
 * synthesis, and two Halley steps' divisions a third of the conversion). */
static inline float cube_root(float t)
{
    int32_t i;
    memcpy(&i, &t, sizeof i);
    i = LAB_RCBRT_MAGIC - (int32_t)((float)i * (1.0f / 3.0f));
    float r;
    memcpy(&r, &i, sizeof r);
    for (int k = 0; k < 3; k++) {
        float r3 = r * r * r;
        r = r * (4.0f - t * r3) * (1.0f / 3.0f);
    }
    return t * (r * r);
}

static inline float lab_f(float t)
{
    float linear = LAB_SLOPE * t + LAB_F0;
    float root = cube_root(t > LAB_T0 ? t : LAB_T0);
    return t > LAB_T0 ? root : linear;
}

static inline float lab_f_inv(float f)
{
    float linear = (f - LAB_F0) * (1.0f / LAB_SLOPE);
    return f > LAB_F_T0 ? f * f * f : linear;
}

/* Negative light is shown as none, as the distances do (measure/lab.c);
 * values above 1 after the scale are not clipped (up to LAB_LIGHT_MAX):
 * the scale puts the exemplar's brightest channel at 1 and colour matching
 * clamps into its box. */
static inline void lab_pixel(const lab_consts *c, const float rgb[3], float scale, float *l,
                             float *a, float *b)
{
    float v[3], xyz[3];
    for (int k = 0; k < 3; k++) {
        float s = rgb[k] * scale;
        s = s > 0.0f ? s : 0.0f;
        v[k] = s < LAB_LIGHT_MAX ? s : LAB_LIGHT_MAX;
    }
    for (int i = 0; i < 3; i++)
        xyz[i] = c->to_xyz[i][0] * v[0] + c->to_xyz[i][1] * v[1] + c->to_xyz[i][2] * v[2];
    float fx = lab_f(xyz[0]), fy = lab_f(xyz[1]), fz = lab_f(xyz[2]);
    *l = 116.0f * fy - 16.0f;
    *a = 500.0f * (fx - fy);
    *b = 200.0f * (fy - fz);
}

static inline void rgb_pixel(const lab_consts *c, float l, float a, float b, float inv,
                             const float lo[3], const float hi[3], float rgb[3])
{
    float fy = (l + 16.0f) * (1.0f / 116.0f);
    float fx = fy + a * (1.0f / 500.0f), fz = fy - b * (1.0f / 200.0f);
    float xyz[3] = {lab_f_inv(fx), lab_f_inv(fy), lab_f_inv(fz)};
    for (int k = 0; k < 3; k++) {
        float v = (c->to_rgb[k][0] * xyz[0] + c->to_rgb[k][1] * xyz[1] +
                   c->to_rgb[k][2] * xyz[2]) * inv;
        v = v > lo[k] ? v : lo[k];
        rgb[k] = v < hi[k] ? v : hi[k];
    }
}

/* The map of one Lab channel (colour_match.c makes it): the segment of v
 * by a multiply and a floor, linear inside it, flat beyond the ends. */
static inline float lab_map_at(const btf_lab_map *m, float v)
{
    float t = (v - m->origin) * m->inv_h;
    t = t > 0.0f ? t : 0.0f; /* also a NaN from 0 * a huge inv_h */
    t = t < (float)BTF_LAB_MAP_SEGS ? t : (float)BTF_LAB_MAP_SEGS;
    int i = (int)t;
    i = i < BTF_LAB_MAP_SEGS - 1 ? i : BTF_LAB_MAP_SEGS - 1;
    return m->q[i] + (t - (float)i) * m->dq[i];
}

#ifdef SYNTH_HAVE_AVX2
#pragma GCC push_options
#pragma GCC target("avx2")
#include <immintrin.h>

#include "rgb8_avx2.h"

/* The scalar functions above on 8 pixels at a time: their operations in
 * their order (no FMA: the build forbids contraction and no intrinsic here
 * asks for it); max/min are the scalar code's comparisons (the second
 * operand on a tie or a NaN). Same bits. */
static inline __m256 cube_root8(__m256 t)
{
    __m256i i = _mm256_cvttps_epi32(
        _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_castps_si256(t)), _mm256_set1_ps(1.0f / 3.0f)));
    __m256 r = _mm256_castsi256_ps(_mm256_sub_epi32(_mm256_set1_epi32(LAB_RCBRT_MAGIC), i));
    const __m256 four = _mm256_set1_ps(4.0f), third = _mm256_set1_ps(1.0f / 3.0f);
    for (int k = 0; k < 3; k++) {
        __m256 r3 = _mm256_mul_ps(_mm256_mul_ps(r, r), r);
        r = _mm256_mul_ps(_mm256_mul_ps(r, _mm256_sub_ps(four, _mm256_mul_ps(t, r3))), third);
    }
    return _mm256_mul_ps(t, _mm256_mul_ps(r, r));
}

static inline __m256 lab_f8(__m256 t)
{
    const __m256 t0 = _mm256_set1_ps(LAB_T0);
    __m256 linear = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(LAB_SLOPE), t),
                                  _mm256_set1_ps(LAB_F0));
    __m256 root = cube_root8(_mm256_max_ps(t, t0));
    return _mm256_blendv_ps(linear, root, _mm256_cmp_ps(t, t0, _CMP_GT_OQ));
}

static inline __m256 lab_f_inv8(__m256 f)
{
    __m256 linear = _mm256_mul_ps(_mm256_sub_ps(f, _mm256_set1_ps(LAB_F0)),
                                  _mm256_set1_ps(1.0f / LAB_SLOPE));
    __m256 cube = _mm256_mul_ps(_mm256_mul_ps(f, f), f);
    return _mm256_blendv_ps(linear, cube, _mm256_cmp_ps(f, _mm256_set1_ps(LAB_F_T0), _CMP_GT_OQ));
}

static inline void lab8(const lab_consts *c, const __m256 rgb[3], float scale, __m256 lab[3])
{
    __m256 v[3], f[3];
    for (int k = 0; k < 3; k++) {
        __m256 s = _mm256_mul_ps(rgb[k], _mm256_set1_ps(scale));
        s = _mm256_max_ps(s, _mm256_setzero_ps());
        v[k] = _mm256_min_ps(s, _mm256_set1_ps(LAB_LIGHT_MAX));
    }
    for (int i = 0; i < 3; i++) {
        __m256 s = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c->to_xyz[i][0]), v[0]),
                                 _mm256_mul_ps(_mm256_set1_ps(c->to_xyz[i][1]), v[1]));
        f[i] = lab_f8(_mm256_add_ps(s, _mm256_mul_ps(_mm256_set1_ps(c->to_xyz[i][2]), v[2])));
    }
    lab[0] = _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(116.0f), f[1]), _mm256_set1_ps(16.0f));
    lab[1] = _mm256_mul_ps(_mm256_set1_ps(500.0f), _mm256_sub_ps(f[0], f[1]));
    lab[2] = _mm256_mul_ps(_mm256_set1_ps(200.0f), _mm256_sub_ps(f[1], f[2]));
}

static inline void rgb8(const lab_consts *c, const __m256 lab[3], float inv, const float lo[3],
                        const float hi[3], __m256 rgb[3])
{
    __m256 fy = _mm256_mul_ps(_mm256_add_ps(lab[0], _mm256_set1_ps(16.0f)),
                              _mm256_set1_ps(1.0f / 116.0f));
    __m256 fx = _mm256_add_ps(fy, _mm256_mul_ps(lab[1], _mm256_set1_ps(1.0f / 500.0f)));
    __m256 fz = _mm256_sub_ps(fy, _mm256_mul_ps(lab[2], _mm256_set1_ps(1.0f / 200.0f)));
    __m256 xyz[3] = {lab_f_inv8(fx), lab_f_inv8(fy), lab_f_inv8(fz)};
    for (int k = 0; k < 3; k++) {
        __m256 s = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(c->to_rgb[k][0]), xyz[0]),
                                 _mm256_mul_ps(_mm256_set1_ps(c->to_rgb[k][1]), xyz[1]));
        s = _mm256_add_ps(s, _mm256_mul_ps(_mm256_set1_ps(c->to_rgb[k][2]), xyz[2]));
        s = _mm256_mul_ps(s, _mm256_set1_ps(inv));
        s = _mm256_max_ps(s, _mm256_set1_ps(lo[k]));
        rgb[k] = _mm256_min_ps(s, _mm256_set1_ps(hi[k]));
    }
}

/* lab_map_at: the segment's numbers by two gathers from the map. */
static inline __m256 map8(const btf_lab_map *m, __m256 v)
{
    __m256 t = _mm256_mul_ps(_mm256_sub_ps(v, _mm256_set1_ps(m->origin)), _mm256_set1_ps(m->inv_h));
    t = _mm256_min_ps(_mm256_max_ps(t, _mm256_setzero_ps()), _mm256_set1_ps((float)BTF_LAB_MAP_SEGS));
    __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(t), _mm256_set1_epi32(BTF_LAB_MAP_SEGS - 1));
    __m256 f = _mm256_sub_ps(t, _mm256_cvtepi32_ps(i));
    __m256 q = _mm256_i32gather_ps(m->q, i, 4), dq = _mm256_i32gather_ps(m->dq, i, 4);
    return _mm256_add_ps(q, _mm256_mul_ps(f, dq));
}

static int lab_row_avx2(const lab_consts *c, const float *rgb, int n, float scale, float *l,
                        float *a, float *b)
{
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        __m256 v[3], lab[3];
        btf_rgb8_load(rgb + 3 * (size_t)x, v);
        lab8(c, v, scale, lab);
        _mm256_storeu_ps(l + x, lab[0]);
        _mm256_storeu_ps(a + x, lab[1]);
        _mm256_storeu_ps(b + x, lab[2]);
    }
    return x;
}

static int rgb_row_avx2(const lab_consts *c, const float *l, const float *a, const float *b,
                        int n, float inv, const float lo[3], const float hi[3], float *rgb)
{
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        __m256 lab[3] = {_mm256_loadu_ps(l + x), _mm256_loadu_ps(a + x), _mm256_loadu_ps(b + x)};
        __m256 v[3];
        rgb8(c, lab, inv, lo, hi, v);
        btf_rgb8_store(v, rgb + 3 * (size_t)x);
    }
    return x;
}

static int match_row_avx2(const lab_consts *c, const btf_lab_map map[3], float scale, float inv,
                          const float lo[3], const float hi[3], float *rgb, int n)
{
    int x = 0;
    for (; x + 8 <= n; x += 8) {
        __m256 v[3], lab[3];
        btf_rgb8_load(rgb + 3 * (size_t)x, v);
        lab8(c, v, scale, lab);
        for (int k = 0; k < 3; k++)
            lab[k] = map8(&map[k], lab[k]);
        rgb8(c, lab, inv, lo, hi, v);
        btf_rgb8_store(v, rgb + 3 * (size_t)x);
    }
    return x;
}
#pragma GCC pop_options
#define HAVE_AVX2() __builtin_cpu_supports("avx2")
#else
#define HAVE_AVX2() 0
#endif

void btf__lab_row(const float *rgb, int n, float scale, float *l, float *a, float *b)
{
    const lab_consts c = lab_consts_make();
    int x = 0;
#ifdef SYNTH_HAVE_AVX2
    if (HAVE_AVX2())
        x = lab_row_avx2(&c, rgb, n, scale, l, a, b);
#endif
    for (; x < n; x++)
        lab_pixel(&c, rgb + 3 * (size_t)x, scale, l + x, a + x, b + x);
}

void btf__rgb_row_from_lab(const float *l, const float *a, const float *b, int n, float scale,
                           const float lo[3], const float hi[3], float *rgb)
{
    const lab_consts c = lab_consts_make();
    const float inv = 1.0f / scale;
    int x = 0;
#ifdef SYNTH_HAVE_AVX2
    if (HAVE_AVX2())
        x = rgb_row_avx2(&c, l, a, b, n, inv, lo, hi, rgb);
#endif
    for (; x < n; x++)
        rgb_pixel(&c, l[x], a[x], b[x], inv, lo, hi, rgb + 3 * (size_t)x);
}

void btf__lab_match_row(const btf_lab_map map[3], float scale, const float lo[3],
                        const float hi[3], float *rgb, int n)
{
    const lab_consts c = lab_consts_make();
    const float inv = 1.0f / scale;
    int x = 0;
#ifdef SYNTH_HAVE_AVX2
    if (HAVE_AVX2())
        x = match_row_avx2(&c, map, scale, inv, lo, hi, rgb, n);
#endif
    for (; x < n; x++) {
        float *p = rgb + 3 * (size_t)x, lab[3];
        lab_pixel(&c, p, scale, &lab[0], &lab[1], &lab[2]);
        for (int k = 0; k < 3; k++)
            lab[k] = lab_map_at(&map[k], lab[k]);
        rgb_pixel(&c, lab[0], lab[1], lab[2], inv, lo, hi, p);
    }
}

/* The exposure of the texture distances (measure/lab.c): an exemplar within
 * [0, 1] is converted as it is, a brighter one scaled so that its largest
 * value is 1. Lab is not invariant to exposure (its linear segment near
 * black is not a cube root), and matching in another exposure than the one
 * measured left up to 1.29 of first-order distance where this leaves 0.9
 * (docs/fidelity.md). */
float btf__lab_scale(const btf_marginal *mg)
{
    float big = mg->rgb_hi[0];
    for (int k = 1; k < 3; k++)
        big = mg->rgb_hi[k] > big ? mg->rgb_hi[k] : big;
    return big > 1.0f ? 1.0f / big : 1.0f;
}

/* The order statistics of n finite floats at the given ranks (each < n,
 * in any order), exactly, without sorting them all: the values fall into
 * ORDER_BUCKETS buckets of equal width between their minimum and maximum
 * (a monotone map, so a bucket's values all sort after the previous
 * bucket's), only the values of the buckets that hold a wanted rank are
 * moved to their places in tmp (n floats) and sorted there. Three passes
 * over the values where the LSD radix sort it replaces made six and
 * took most of a quantile estimate's time. */
#define ORDER_BUCKETS 4096

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static btf_status order_stats(const float *v, float *tmp, size_t n, const size_t *ranks, int nr,
                              float *out, btf_error *err)
{
    float lo = v[0], hi = v[0];
    for (size_t i = 1; i < n; i++) {
        lo = v[i] < lo ? v[i] : lo;
        hi = v[i] > hi ? v[i] : hi;
    }
    if (!(hi > lo)) { /* one value: every statistic is it */
        for (int r = 0; r < nr; r++)
            out[r] = lo;
        return BTF_OK;
    }
    uint32_t *start = btf__calloc(2 * (ORDER_BUCKETS + 1), sizeof(uint32_t), err);
    if (!start)
        return BTF_E_NOMEM;
    uint32_t *fill = start + ORDER_BUCKETS + 1; /* next free place of a wanted bucket, else 0 */
    double scale = ORDER_BUCKETS / ((double)hi - lo);
#define BUCKET(x) ((size_t)(((double)(x) - lo) * scale) < ORDER_BUCKETS - 1                   \
                       ? (size_t)(((double)(x) - lo) * scale) : (size_t)ORDER_BUCKETS - 1)
    for (size_t i = 0; i < n; i++)
        start[BUCKET(v[i]) + 1]++;
    for (size_t b = 0; b < ORDER_BUCKETS; b++)
        start[b + 1] += start[b];
    for (int r = 0; r < nr; r++) { /* the bucket b with start[b] <= rank < start[b + 1] */
        size_t b0 = 0, b1 = ORDER_BUCKETS - 1;
        while (b0 < b1) {
            size_t mid = (b0 + b1) / 2;
            if (start[mid + 1] <= ranks[r])
                b0 = mid + 1;
            else
                b1 = mid;
        }
        fill[b0] = start[b0] + 1; /* + 1: 0 says "not wanted" */
    }
    for (size_t i = 0; i < n; i++) {
        size_t k = BUCKET(v[i]);
        if (fill[k])
            tmp[fill[k]++ - 1] = v[i];
    }
#undef BUCKET
    for (size_t k = 0; k < ORDER_BUCKETS; k++)
        if (fill[k] && start[k + 1] - start[k] > 1)
            qsort(tmp + start[k], start[k + 1] - start[k], sizeof *tmp, cmp_float);
    for (int r = 0; r < nr; r++)
        out[r] = tmp[ranks[r]];
    free(start);
    return BTF_OK;
}

/* The sample: every pixel up to `most` of them, else the pixels of a
 * regular grid of steps sx, sy (each the smallest that brings the count
 * within it): deterministic, spread over the whole image. */
static void sample_steps(int w, int h, size_t most, int *sx, int *sy)
{
    *sx = *sy = 1;
    while ((size_t)((w + *sx - 1) / *sx) * (size_t)((h + *sy - 1) / *sy) > most) {
        if ((w + *sx - 1) / *sx >= (h + *sy - 1) / *sy)
            (*sx)++;
        else
            (*sy)++;
    }
}

void btf__lab_sample_grid(btf_lab_sample *s, int width, int height, size_t most)
{
    memset(s, 0, sizeof *s);
    sample_steps(width, height, most, &s->sx, &s->sy);
    s->cols = (width + s->sx - 1) / s->sx, s->rows = (height + s->sy - 1) / s->sy;
    s->n = (size_t)s->cols * s->rows;
}

btf_status btf__lab_sample_begin(btf_lab_sample *s, int width, int height, size_t most,
                                 float scale, btf_error *err)
{
    btf__lab_sample_grid(s, width, height, most);
    s->scale = scale;
    s->v = btf__alloc(s->n * 4, sizeof(float), err); /* 3 channels, then the sort's scratch */
    return s->v ? BTF_OK : BTF_E_NOMEM;
}

void btf__lab_sample_row(btf_lab_sample *s, int y, const float *row, float *scratch)
{
    if (y % s->sy)
        return;
    if (s->sx > 1) { /* the row's samples side by side */
        for (int i = 0; i < s->cols; i++)
            memcpy(scratch + 3 * i, row + (size_t)3 * i * s->sx, 3 * sizeof(float));
        row = scratch;
    }
    size_t at = (size_t)(y / s->sy) * s->cols;
    btf__lab_row(row, s->cols, s->scale, s->v + at, s->v + s->n + at, s->v + 2 * s->n + at);
}

void btf__lab_sample_free(btf_lab_sample *s)
{
    free(s->v);
    s->v = NULL;
}

/* Each channel's quantiles: linear between its order statistics at
 * h = (n - 1) p, p = j / (knots - 1), as the band quantiles of the
 * marginal transfer (analyse/marginal_fit.c). One thread, as each job of
 * the sampling: both take a fraction of a millisecond for the 16,384
 * samples of a match, less than starting a thread (about 0.1 ms on a VM);
 * a batch runs them on the relay helper beside the next image's synthesis
 * (colour_match.c's task). */
int btf__lab_quantile_ranks(size_t n, size_t ranks[2 * BTF_MARGIN_KNOTS],
                            double frac[BTF_MARGIN_KNOTS])
{
    int nr = 0;
    for (int j = 0; j < BTF_MARGIN_KNOTS; j++) { /* the two order statistics around h_j */
        double hpos = (double)(n - 1) * j / (BTF_MARGIN_KNOTS - 1);
        size_t k = (size_t)hpos;
        frac[j] = hpos - (double)k;
        ranks[nr++] = k;
        ranks[nr++] = k + 1 < n ? k + 1 : k;
    }
    return nr;
}

void btf__lab_quantiles_at(int c, const float at[2 * BTF_MARGIN_KNOTS],
                           const double frac[BTF_MARGIN_KNOTS], float q[BTF_MARGIN_KNOTS])
{
    for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
        float a = at[2 * j], b = at[2 * j + 1];
        double x = a + frac[j] * ((double)b - a);
        float lim = c == 0 ? 100.0f : 128.0f, low = c == 0 ? 0.0f : -128.0f;
        float qv = (float)x;
        qv = qv < low ? low : qv > lim ? lim : qv;
        q[j] = j > 0 && qv < q[j - 1] ? q[j - 1] : qv;
    }
}

btf_status btf__lab_sample_quantiles(btf_lab_sample *s, float q[3][BTF_MARGIN_KNOTS],
                                     btf_error *err)
{
    size_t n = s->n, ranks[2 * BTF_MARGIN_KNOTS];
    double frac[BTF_MARGIN_KNOTS];
    int nr = btf__lab_quantile_ranks(n, ranks, frac);
    for (int c = 0; c < 3; c++) {
        float at[2 * BTF_MARGIN_KNOTS];
        btf_status rc = order_stats(s->v + c * n, s->v + 3 * n, n, ranks, nr, at, err);
        if (rc)
            return rc;
        btf__lab_quantiles_at(c, at, frac, q[c]);
    }
    return BTF_OK;
}

btf_status btf__lab_quantiles(const btf_image *img, float scale, size_t most,
                              float q[3][BTF_MARGIN_KNOTS], btf_error *err)
{
    btf_lab_sample s;
    btf_status rc = btf__lab_sample_begin(&s, img->width, img->height, most, scale, err);
    if (rc)
        return rc;
    float *scratch = btf__alloc((size_t)s.cols * 3, sizeof(float), err);
    for (int r = 0; scratch && r < s.rows; r++) {
        int y = r * s.sy;
        btf__lab_sample_row(&s, y, img->data + (size_t)y * img->width * 3, scratch);
    }
    rc = scratch ? btf__lab_sample_quantiles(&s, q, err) : BTF_E_NOMEM;
    free(scratch);
    btf__lab_sample_free(&s);
    return rc;
}
