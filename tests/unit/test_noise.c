/*
 * test_noise.c -- the CAR synthesis noise of src/synth/btf_noise.h: Philox-4x32-7
 * (and -10) known answers, the accuracy of the polynomial log / sqrt / cos / sin, the
 * Gaussian's moments, Kolmogorov-Smirnov distance and exact tails, range,
 * determinism, independence, and that the header also builds as GLSL.
 *
 * Statistical bounds: each test uses a fixed seed, so it is deterministic;
 * the bounds sit at about 5 standard errors (or the Kolmogorov 1e-5 level),
 * so a correct generator would fail them for a tiny fraction of seeds only.
 */
#include "synth/synth.h"
#include "testutil.h"
#include "core/core.h"

#include "btf_noise.h"
#include "noise_check_spv.h" /* built from gpu/noise_check.comp by the Makefile */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* ------------------------------------------------------------ helpers */

/* An independent Philox-4xW32 with any round count, written from the paper
 * (arrays, key schedule bumped before each round but the first). */
static void ref_philox(int rounds, const uint32_t ctr[4], const uint32_t key[2],
                       uint32_t out[4])
{
    uint32_t c[4] = {ctr[0], ctr[1], ctr[2], ctr[3]};
    uint32_t k[2] = {key[0], key[1]};
    for (int r = 0; r < rounds; r++) {
        if (r > 0) {
            k[0] += 0x9E3779B9u;
            k[1] += 0xBB67AE85u;
        }
        uint64_t p0 = 0xD2511F53ull * c[0], p1 = 0xCD9E8D57ull * c[2];
        uint32_t n[4] = {(uint32_t)(p1 >> 32) ^ c[1] ^ k[0], (uint32_t)p1,
                         (uint32_t)(p0 >> 32) ^ c[3] ^ k[1], (uint32_t)p0};
        memcpy(c, n, sizeof c);
    }
    memcpy(out, c, sizeof c);
}

/* splitmix64, for test inputs. */
static uint64_t mix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Sorts n floats (no NaN) by an LSD radix sort on order-preserving keys. */
static void sort_floats(float *v, size_t n)
{
    uint32_t *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    size_t *cnt = malloc(65536 * sizeof *cnt);
    assert_non_null(a);
    assert_non_null(b);
    assert_non_null(cnt);
    for (size_t i = 0; i < n; i++) {
        uint32_t u = btf_float_bits(v[i]);
        a[i] = (u & 0x80000000u) ? ~u : (u | 0x80000000u);
    }
    for (int pass = 0; pass < 2; pass++) {
        int sh = 16 * pass;
        memset(cnt, 0, 65536 * sizeof *cnt);
        for (size_t i = 0; i < n; i++)
            cnt[(a[i] >> sh) & 0xFFFFu]++;
        size_t sum = 0;
        for (size_t d = 0; d < 65536; d++) {
            size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            b[cnt[(a[i] >> sh) & 0xFFFFu]++] = a[i];
        uint32_t *t = a;
        a = b;
        b = t;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t k = a[i];
        v[i] = btf_bits_float((k & 0x80000000u) ? (k & 0x7FFFFFFFu) : ~k);
    }
    free(a);
    free(b);
    free(cnt);
}

static double normal_cdf(double x)
{
    return 0.5 * erfc(-x / sqrt(2.0));
}

static double normal_pdf(double x)
{
    return exp(-0.5 * x * x) / sqrt(2.0 * PI);
}

/* Pearson correlation of two sample arrays. */
static double correlation(const double *x, const double *y, size_t n)
{
    double mx = 0, my = 0;
    for (size_t i = 0; i < n; i++) {
        mx += x[i];
        my += y[i];
    }
    mx /= (double)n;
    my /= (double)n;
    double sxy = 0, sxx = 0, syy = 0;
    for (size_t i = 0; i < n; i++) {
        sxy += (x[i] - mx) * (y[i] - my);
        sxx += (x[i] - mx) * (x[i] - mx);
        syy += (y[i] - my) * (y[i] - my);
    }
    return sxy / sqrt(sxx * syy);
}

static const uint32_t SEED_LO = 0x12345678u, SEED_HI = 0x9ABCDEF0u;

/* ------------------------------------------------------------- Philox */

static void philox_known_answers(void **state)
{
    (void)state;
    /* Random123 tests/kat_vectors, "philox4x32 10" lines: ctr[4] key[2] -> out[4];
     * they check the independent reference's key schedule. */
    static const uint32_t kat[3][10] = {
        {0, 0, 0, 0, 0, 0, 0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8},
        {0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff,
         0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd},
        {0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344, 0xa4093822, 0x299f31d0,
         0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1},
    };
    /* The same file's "philox4x32 7" lines: the rounds the noise uses. */
    static const uint32_t kat7[3][4] = {
        {0x5f6fb709, 0x0d893f64, 0x4f121f81, 0x4f730a48},
        {0x5207ddc2, 0x45165e59, 0x4d8ee751, 0x8c52f662},
        {0x4dfccaba, 0x190a87f0, 0xc47362ba, 0xb6b5242a},
    };
    assert_int_equal(BTF_PHILOX_ROUNDS, 7);
    for (int i = 0; i < 3; i++) {
        const uint32_t *v = kat[i];
        btf_uvec4 o = btf_philox(btf_make_uvec4(v[0], v[1], v[2], v[3]),
                                 btf_make_uvec2(v[4], v[5]));
        assert_int_equal(o.x, kat7[i][0]);
        assert_int_equal(o.y, kat7[i][1]);
        assert_int_equal(o.z, kat7[i][2]);
        assert_int_equal(o.w, kat7[i][3]);
        uint32_t r[4];
        ref_philox(10, v, v + 4, r);
        assert_memory_equal(r, v + 6, sizeof r);
        ref_philox(7, v, v + 4, r);
        assert_memory_equal(r, kat7[i], sizeof r);
    }
    /* The header equals the independent reference on random inputs. */
    uint64_t s = 42;
    for (int i = 0; i < 100000; i++) {
        uint64_t a = mix64(&s), b = mix64(&s), c = mix64(&s);
        uint32_t ctr[4] = {(uint32_t)a, (uint32_t)(a >> 32), (uint32_t)b, (uint32_t)(b >> 32)};
        uint32_t key[2] = {(uint32_t)c, (uint32_t)(c >> 32)};
        uint32_t r[4];
        ref_philox(BTF_PHILOX_ROUNDS, ctr, key, r);
        btf_uvec4 o = btf_philox(btf_make_uvec4(ctr[0], ctr[1], ctr[2], ctr[3]),
                                 btf_make_uvec2(key[0], key[1]));
        assert_true(o.x == r[0] && o.y == r[1] && o.z == r[2] && o.w == r[3]);
    }
}

/* ------------------------------------------------- polynomial pieces */

/* Measured: 5.0e-7 absolute (0.27 ulp of ln 2^-24) and 1.0e-7 relative on
 * every multiple of 2^-24 in (0, 1); 1.0e-7 relative on the normal floats
 * in [2^-100, 2^100] (every 7th). */
static void log_accuracy(void **state)
{
    (void)state;
    double max_abs = 0, max_rel = 0;
    for (uint32_t k = 1; k < (1u << 24); k++) {
        float u = (float)k * 0x1p-24f;
        double l = log((double)u), e = fabs(btf_noise_log(u) - l);
        max_abs = fmax(max_abs, e);
        max_rel = fmax(max_rel, e / fabs(l));
    }
    assert_true(btf_noise_log(1.0f) == 0.0f);
    double wide_rel = 0;
    for (uint32_t b = 0x0D800000u; b < 0x71800000u; b += 7) {
        float x = btf_bits_float(b);
        double l = log((double)x);
        if (x != 1.0f)
            wide_rel = fmax(wide_rel, fabs(btf_noise_log(x) - l) / fabs(l));
    }
    print_message("log: max abs error %.3g, max rel error %.3g on (0,1); rel %.3g on "
                  "[2^-100, 2^100]\n", max_abs, max_rel, wide_rel);
    assert_true(max_abs < 6e-7);
    assert_true(max_rel < 1.2e-7);
    assert_true(wide_rel < 1.2e-7);
}

/* Measured: 2.2e-7 relative (at most 4 ulp) on the normal floats (every 61st);
 * sqrt(0) = 0 exactly. */
static void sqrt_accuracy(void **state)
{
    (void)state;
    double max_rel = 0;
    for (uint32_t b = 0x00800000u; b < 0x7F000000u; b += 61) {
        float x = btf_bits_float(b);
        double r = sqrt((double)x);
        max_rel = fmax(max_rel, fabs(btf_noise_sqrt(x) - r) / r);
    }
    print_message("sqrt: max rel error %.3g\n", max_rel);
    assert_true(max_rel < 2.5e-7);
    assert_true(btf_noise_sqrt(0.0f) == 0.0f);
    assert_true(btf_noise_sqrt(4.0f) > 1.9999996f && btf_noise_sqrt(4.0f) < 2.0000004f);
}

/* Measured: 8.7e-8 absolute for both cos and sin on all 2^24 angles. */
static void cossin_accuracy(void **state)
{
    (void)state;
    double ec = 0, es = 0;
    for (uint32_t k = 0; k < (1u << 24); k++) {
        btf_vec2 v = btf_noise_cossin(k);
        double a = 2.0 * PI * k / 16777216.0;
        ec = fmax(ec, fabs(v.x - cos(a)));
        es = fmax(es, fabs(v.y - sin(a)));
        assert_true(v.x * v.x + v.y * v.y < 1.000001f);
    }
    print_message("cos/sin: max abs error %.3g / %.3g\n", ec, es);
    assert_true(ec < 1.2e-7 && es < 1.2e-7);
    /* Exact at the axes; only the low 24 bits count; exact symmetries. */
    btf_vec2 a0 = btf_noise_cossin(0), a1 = btf_noise_cossin(1u << 22);
    btf_vec2 a2 = btf_noise_cossin(2u << 22), a3 = btf_noise_cossin(3u << 22);
    assert_true(a0.x == 1.0f && a0.y == 0.0f && a1.x == 0.0f && a1.y == 1.0f);
    assert_true(a2.x == -1.0f && a2.y == 0.0f && a3.x == 0.0f && a3.y == -1.0f);
    for (uint32_t k = 1; k < (1u << 24); k += 4099) {
        btf_vec2 p = btf_noise_cossin(k), q = btf_noise_cossin((1u << 24) - k);
        btf_vec2 h = btf_noise_cossin(k + (1u << 23)), w = btf_noise_cossin(k + 0xFF000000u);
        assert_true(q.x == p.x && q.y == -p.y);
        assert_true(h.x == -p.x && h.y == -p.y);
        assert_true(w.x == p.x && w.y == p.y);
    }
}

/* The radius sqrt(-2 ln u1) on all 2^23 uniforms and the Box-Muller pair on
 * a 2^23/97 x 509 grid, vs the same map in double.  Measured: 7.1e-7 and
 * 8.8e-7.  The uniform is (2k+1)/2^24: strictly inside (0, 1), so the
 * radius is at most sqrt(-2 ln 2^-24) = BTF_NOISE_MAX_ABS. */
static void box_muller_accuracy(void **state)
{
    (void)state;
    double er = 0, rmax = 0;
    for (uint32_t k = 0; k < (1u << 23); k++) {
        float u = btf_noise_uniform_open(k << 9 | 0x1FFu);
        assert_true(u == (float)((2.0 * k + 1) / 16777216.0));
        float r = btf_noise_sqrt(-2.0f * btf_noise_log(u));
        er = fmax(er, fabs(r - sqrt(-2.0 * log((double)u))));
        rmax = fmax(rmax, r);
    }
    double ez = 0;
    for (uint32_t k = 0; k < (1u << 23); k += 97)
        for (uint32_t j = 0; j < (1u << 24); j += 32957) {
            btf_vec2 g = btf_noise_gauss2(k << 9, j << 8);
            double r = sqrt(-2.0 * log((2.0 * k + 1) / 16777216.0));
            double a = 2.0 * PI * j / 16777216.0;
            ez = fmax(ez, fmax(fabs(g.x - r * cos(a)), fabs(g.y - r * sin(a))));
        }
    print_message("Box-Muller: radius max abs error %.3g, pair %.3g; max radius %.9g\n",
                  er, ez, rmax);
    assert_true(er < 1e-6 && ez < 1.5e-6);
    assert_true(rmax == btf_noise_gauss2(0, 0).x);
    assert_true(fabs(rmax - sqrt(48.0 * log(2.0))) < 1e-6);
    assert_true(rmax <= BTF_NOISE_MAX_ABS);
}

/* ---------------------------------------------------------- Gaussian */

#define NSAMPLES 10000000u
#define NBLOCKS 1000u

static float *draw(uint32_t stream)
{
    float *z = malloc(NSAMPLES * sizeof *z);
    assert_non_null(z);
    for (uint32_t i = 0; i < NSAMPLES / 4; i++) {
        btf_vec4 v = btf_noise4(SEED_LO, SEED_HI, stream, i / NBLOCKS, i % NBLOCKS);
        z[4 * i] = v.x;
        z[4 * i + 1] = v.y;
        z[4 * i + 2] = v.z;
        z[4 * i + 3] = v.w;
    }
    return z;
}

/* 10^7 samples.  Standard errors: mean 1/sqrt(n) = 3.2e-4, variance
 * sqrt(2/n) = 4.5e-4, skewness sqrt(6/n) = 7.7e-4, kurtosis sqrt(24/n) =
 * 1.5e-3; bounds at 5 of them (variance: 2.5e-3 = 0.25 %). */
static void gaussian_moments(void **state)
{
    (void)state;
    float *z = draw(btf_noise_stream(3, 1, 2));
    double s1 = 0, s2 = 0, s3 = 0, s4 = 0, lo = 0, hi = 0;
    for (size_t i = 0; i < NSAMPLES; i++) {
        double x = z[i];
        assert_true(isfinite(x));
        s1 += x;
        s2 += x * x;
        s3 += x * x * x;
        s4 += x * x * x * x;
        lo = fmin(lo, x);
        hi = fmax(hi, x);
    }
    double n = NSAMPLES, mean = s1 / n, var = s2 / n - mean * mean;
    double m3 = s3 / n - 3 * mean * s2 / n + 2 * mean * mean * mean;
    double m4 = s4 / n - 4 * mean * s3 / n + 6 * mean * mean * s2 / n - 3 * pow(mean, 4);
    double skew = m3 / pow(var, 1.5), kurt = m4 / (var * var);
    print_message("Gaussian (n = 1e7): mean %.3g, variance %.5f, skewness %.3g, "
                  "kurtosis %.4f, min %.4f, max %.4f\n", mean, var, skew, kurt, lo, hi);
    assert_true(fabs(mean) < 1.6e-3);
    assert_true(fabs(var - 1.0) < 2.5e-3);
    assert_true(fabs(skew) < 3.9e-3);
    assert_true(fabs(kurt - 3.0) < 7.7e-3);
    assert_true(-lo <= BTF_NOISE_MAX_ABS && hi <= BTF_NOISE_MAX_ABS);
    free(z);
}

/* Kolmogorov-Smirnov distance to the normal CDF over 10^7 samples:
 * P(sqrt(n) D > 2.5) is about 2 exp(-12.5) = 7e-6 for a true normal. */
static void gaussian_ks(void **state)
{
    (void)state;
    float *z = draw(btf_noise_stream(7, 0, 0));
    sort_floats(z, NSAMPLES);
    double d = 0, n = NSAMPLES;
    for (size_t i = 0; i < NSAMPLES; i++) {
        double f = normal_cdf(z[i]);
        d = fmax(d, fmax(fabs((double)(i + 1) / n - f), fabs((double)i / n - f)));
    }
    print_message("Gaussian (n = 1e7): KS distance %.3g, sqrt(n) D = %.3f\n", d, sqrt(n) * d);
    assert_true(sqrt(n) * d < 2.5);
    free(z);
}

/* P(z > t) over the generator's whole sample space (2^23 radii x 2^24
 * angles, with the header's own float arithmetic) vs the normal tail, as a
 * quantile shift (P - Q(t)) / pdf(t).  Measured: <= 1.7e-7 up to t = 3,
 * 2.6e-6 at 4, 2.5e-5 at 4.5, 4.4e-4 at 5, 1.1e-2 at 5.5 (only 6e-8 of the mass lies
 * beyond the 5.77 bound). */
static void gaussian_exact_tails(void **state)
{
    (void)state;
    const uint32_t n1 = 1u << 23, n2 = 1u << 24;
    float *r = malloc(n1 * sizeof *r), *c = malloc(n2 * sizeof *c);
    assert_non_null(r);
    assert_non_null(c);
    for (uint32_t k = 0; k < n1; k++)
        r[k] = btf_noise_sqrt(-2.0f * btf_noise_log(btf_noise_uniform_open(k << 9)));
    /* The cosines (first component); the sines are the same multiset. */
    size_t npos = 0;
    float *sn = malloc(n2 * sizeof *sn);
    assert_non_null(sn);
    size_t nsin = 0;
    for (uint32_t k = 0; k < n2; k++) {
        btf_vec2 v = btf_noise_cossin(k);
        if (v.x > 0.0f)
            c[npos++] = v.x;
        if (v.y > 0.0f)
            sn[nsin++] = v.y;
    }
    sort_floats(c, npos);
    sort_floats(sn, nsin);
    assert_int_equal(npos, nsin);
    assert_memory_equal(c, sn, npos * sizeof *c);
    free(sn);
    static const double ts[] = {1.0, 2.0, 3.0, 4.0, 4.5, 5.0, 5.5};
    static const double tol[] = {1e-6, 1e-6, 1e-6, 1e-5, 1e-4, 1e-3, 3e-2};
    for (int it = 0; it < 7; it++) {
        float t = (float)ts[it];
        double count = 0;
        for (uint32_t k = 0; k < n1; k++) {
            if (r[k] <= t)
                continue;
            /* first index whose cosine makes r * c > t (monotone in c) */
            size_t lo = 0, hi = npos;
            while (lo < hi) {
                size_t mid = lo + (hi - lo) / 2;
                float z = r[k] * c[mid];
                if (z > t)
                    hi = mid;
                else
                    lo = mid + 1;
            }
            count += (double)(npos - lo);
        }
        double p = count / ((double)n1 * n2), q = 0.5 * erfc(ts[it] / sqrt(2.0));
        double shift = (p - q) / normal_pdf(ts[it]);
        print_message("tail P(z > %.1f) = %.6e (normal %.6e): quantile shift %.2e\n",
                      ts[it], p, q, shift);
        assert_true(fabs(shift) < tol[it]);
    }
    free(r);
    free(c);
}

/* ----------------------------------------------- determinism, streams */

static void determinism_and_golden(void **state)
{
    (void)state;
    /* Fixed outputs: changing them changes every synthesised image. */
    btf_vec4 v = btf_noise4(SEED_LO, SEED_HI, btf_noise_stream(1, 2, 0), 5, 17);
    btf_vec4 v2 = btf_noise4(SEED_LO, SEED_HI, btf_noise_stream(1, 2, 0), 5, 17);
    assert_memory_equal(&v, &v2, sizeof v);
    const uint32_t got[4] = {btf_float_bits(v.x), btf_float_bits(v.y), btf_float_bits(v.z),
                             btf_float_bits(v.w)};
    static const uint32_t golden[4] = {0xbfc0ebb3u, 0x3f81ce0au, 0x3f5cc818u, 0xbe26853bu};
    print_message("golden: 0x%08x 0x%08x 0x%08x 0x%08x\n", got[0], got[1], got[2], got[3]);
    assert_memory_equal(got, golden, sizeof got);
    /* The counter layout: (block, row, stream, tag), key (seed_lo, seed_hi). */
    btf_uvec4 w = btf_philox(btf_make_uvec4(17, 5, 0x00010200u, BTF_NOISE_TAG),
                             btf_make_uvec2(SEED_LO, SEED_HI));
    btf_vec2 g0 = btf_noise_gauss2(w.x, w.y), g1 = btf_noise_gauss2(w.z, w.w);
    assert_true(g0.x == v.x && g0.y == v.y && g1.x == v.z && g1.y == v.w);
    assert_int_equal(btf_noise_stream(1, 2, 3), 0x00010203u);
    assert_int_equal(btf_noise_stream(65535, 255, 255), 0xFFFFFFFFu);
    /* Distinct (subspace, band, level) give distinct streams. */
    for (uint32_t s = 0; s < 64; s++)
        for (uint32_t b = 0; b < 8; b++)
            for (uint32_t l = 0; l < 8; l++)
                assert_int_equal(btf_noise_stream(s, b, l), (s << 16) | (b << 8) | l);
}

/* btf_noise1 is bit for bit the matching component of btf_noise4, also for
 * columns and rows from negative ints (wrapped to uint). */
static void noise1_matches_noise4(void **state)
{
    (void)state;
    uint64_t s = 7;
    for (int i = 0; i < 200000; i++) {
        uint64_t a = mix64(&s), b = mix64(&s);
        uint32_t row = (uint32_t)a, col = (uint32_t)(a >> 32);
        if (i < 1000) {
            row = (uint32_t)(int32_t)(i - 500);
            col = (uint32_t)(int32_t)(i % 50 - 25);
        }
        uint32_t stream = (uint32_t)b;
        btf_vec4 v = btf_noise4((uint32_t)(b >> 32), 3u, stream, row, col >> 2);
        float one = btf_noise1((uint32_t)(b >> 32), 3u, stream, row, col);
        assert_true(btf_float_bits(one) == btf_float_bits(btf_vec4_at(v, col)));
    }
}

/* The row generator of CPU synthesis (src/synth/noise_row.c, an AVX2 path where
 * the CPU has it) gives bit for bit btf_noise4 of each block, for every
 * length (whole 16-block groups and tails) and for random keys, streams,
 * rows and starting blocks, wrapped negative ones included. */
static void noise_rows_match_noise4(void **state)
{
    (void)state;
    enum { MAXB = 70 };
    float fast[4 * MAXB + 1], slow[4 * MAXB + 1];
    uint64_t s = 11;
    long compared = 0;
    for (int i = 0; i < 20000; i++) {
        uint64_t a = mix64(&s), b = mix64(&s);
        uint32_t n = (uint32_t)(a % (MAXB + 1));
        uint32_t b0 = i < 100 ? (uint32_t)(i - 50) : (uint32_t)(b >> 32);
        uint32_t row = (uint32_t)(a >> 32), stream = (uint32_t)b;
        fast[4 * n] = slow[4 * n] = 12345.0f; /* nothing written past the end */
        btf__noise_blocks((uint32_t)(a >> 8), (uint32_t)(b >> 40), stream, row, b0, n, 1, fast);
        btf__noise_blocks((uint32_t)(a >> 8), (uint32_t)(b >> 40), stream, row, b0, n, 0, slow);
        for (uint32_t k = 0; k < n; k++) {
            btf_vec4 v = btf_noise4((uint32_t)(a >> 8), (uint32_t)(b >> 40), stream, row, b0 + k);
            for (uint32_t c = 0; c < 4; c++) {
                uint32_t want = btf_float_bits(btf_vec4_at(v, c));
                assert_true(btf_float_bits(fast[4 * k + c]) == want);
                assert_true(btf_float_bits(slow[4 * k + c]) == want);
            }
        }
        assert_true(fast[4 * n] == 12345.0f && slow[4 * n] == 12345.0f);
        compared += 4 * (long)n;
    }
    printf("noise rows: %ld Gaussians identical on both paths (vector path: %s)\n", compared,
           btf__noise_avx2_available() ? "AVX2" : "portable only on this CPU");
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#pragma GCC push_options
#pragma GCC target("avx2")
#include "noise_avx2.h"

/* 8 pairs through the AVX2 Box-Muller against btf_noise_gauss2; the number
 * of pairs whose bits differ. (Arrays, not vectors, cross the call: the
 * caller is not compiled for AVX2.) */
static long gauss2_lockstep_mismatches(const uint32_t *wa, const uint32_t *wb)
{
    v8u a, b;
    memcpy(&a, wa, sizeof a);
    memcpy(&b, wb, sizeof b);
    v8f z0[1], z1[1];
    gauss2_lockstep(1, &a, &b, z0, z1);
    long bad = 0;
    for (int k = 0; k < 8; k++) {
        btf_vec2 g = btf_noise_gauss2(wa[k], wb[k]);
        bad += btf_float_bits(g.x) != ((v8u)z0[0])[k] || btf_float_bits(g.y) != ((v8u)z1[0])[k];
    }
    return bad;
}
#pragma GCC pop_options

/* The AVX2 Box-Muller (src/synth/noise_avx2.h) rewrites btf_noise_gauss2's
 * halving test and quadrant selects as bit tricks: every radius word (all
 * 2^24 values of a >> 8) and every angle word (all 2^24 of b >> 8) gives
 * the same bits as the shared header. */
static void lockstep_every_radius_and_angle(void **state)
{
    (void)state;
    if (!__builtin_cpu_supports("avx2"))
        skip(); /* the vector code cannot run on this CPU */
    long bad = 0;
    for (uint32_t i = 0; i < (1u << 24); i += 8) {
        uint32_t a[8], b[8];
        for (uint32_t k = 0; k < 8; k++) { /* radius word i + k, some angle */
            a[k] = ((i + k) << 8) | 0x5Au;
            b[k] = (i + k) * 2654435761u;
        }
        bad += gauss2_lockstep_mismatches(a, b);
        for (uint32_t k = 0; k < 8; k++) { /* angle word i + k, some radius */
            b[k] = ((i + k) << 8) | 0xA5u;
            a[k] = (i + k) * 2246822519u;
        }
        bad += gauss2_lockstep_mismatches(a, b);
    }
    printf("AVX2 Box-Muller: 2 x 2^24 word pairs, %ld differ from btf_noise_gauss2\n", bad);
    assert_int_equal(bad, 0);
}
#endif

/* Pairs of samples that must be independent: |corr| < 5 / sqrt(n) with
 * n = 10^6 pairs (also of squares, which catches a shared radius). */
static void independence(void **state)
{
    (void)state;
    enum { N = 1000000 };
    double *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y);
    double *x2 = malloc(N * sizeof *x2), *y2 = malloc(N * sizeof *y2);
    assert_non_null(x);
    assert_non_null(y);
    assert_non_null(x2);
    assert_non_null(y2);
    const char *what[] = {"band 1 / 2",        "level 0 / 1",     "row r / r+1",
                          "block b / b+1",     "component x / y", "component x / z",
                          "seed_lo / seed_lo+1", "seed_hi / seed_hi+1", "subspace 2 / 3"};
    const double bound = 5.0 / sqrt((double)N);
    for (int t = 0; t < 9; t++) {
        for (uint32_t i = 0; i < N; i++) {
            uint32_t row = i / 1000, blk = i % 1000, st = btf_noise_stream(2, 1, 0);
            btf_vec4 a = btf_noise4(SEED_LO, SEED_HI, st, row, blk), b = a;
            switch (t) {
            case 0: b = btf_noise4(SEED_LO, SEED_HI, btf_noise_stream(2, 2, 0), row, blk); break;
            case 1: b = btf_noise4(SEED_LO, SEED_HI, btf_noise_stream(2, 1, 1), row, blk); break;
            case 2: b = btf_noise4(SEED_LO, SEED_HI, st, row + 1, blk); break;
            case 3: b = btf_noise4(SEED_LO, SEED_HI, st, row, blk + 1); break;
            case 4: b.x = a.y; break;
            case 5: b.x = a.z; break;
            case 6: b = btf_noise4(SEED_LO + 1, SEED_HI, st, row, blk); break;
            case 7: b = btf_noise4(SEED_LO, SEED_HI + 1, st, row, blk); break;
            default: b = btf_noise4(SEED_LO, SEED_HI, btf_noise_stream(3, 1, 0), row, blk); break;
            }
            x[i] = a.x;
            y[i] = b.x;
            x2[i] = (double)a.x * a.x;
            y2[i] = (double)b.x * b.x;
        }
        double c = correlation(x, y, N), c2 = correlation(x2, y2, N);
        print_message("corr %-22s %+.2e (squares %+.2e)\n", what[t], c, c2);
        assert_true(fabs(c) < bound);
        assert_true(fabs(c2) < bound);
    }
    free(x);
    free(y);
    free(x2);
    free(y2);
}

/* The shader that includes btf_noise.h compiled and passed spirv-val (the
 * Makefile builds it before this test): check it is a SPIR-V module. */
static void glsl_build(void **state)
{
    (void)state;
    assert_true(sizeof noise_check_spv > 64);
    assert_int_equal(noise_check_spv[0], 0x07230203u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(philox_known_answers),
        cmocka_unit_test(log_accuracy),
        cmocka_unit_test(sqrt_accuracy),
        cmocka_unit_test(cossin_accuracy),
        cmocka_unit_test(box_muller_accuracy),
        cmocka_unit_test(gaussian_moments),
        cmocka_unit_test(gaussian_ks),
        cmocka_unit_test(gaussian_exact_tails),
        cmocka_unit_test(determinism_and_golden),
        cmocka_unit_test(noise1_matches_noise4),
        cmocka_unit_test(noise_rows_match_noise4),
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
        cmocka_unit_test(lockstep_every_radius_and_angle),
#endif
        cmocka_unit_test(independence),
        cmocka_unit_test(glsl_build),
    };
    return cmocka_run_group_tests_name("noise", tests, NULL, NULL);
}
