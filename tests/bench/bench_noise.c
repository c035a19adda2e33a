/*
 * bench_noise.c -- speed of the CAR synthesis noise (src/synth/btf_noise.h) on one
 * core: ns per Gaussian through btf_noise4 (one Philox-4x32-7 call and two
 * Box-Muller pairs per 4 Gaussians), through btf_noise1, and Philox alone;
 * and the row generator CPU synthesis uses (btf__noise_blocks, AVX2 where
 * the CPU has it), rows of 136 blocks as in a level-0 field of 512 + margins.
 * Median of 5 runs; prints figures, never fails on time.
 */
#include "synth/synth.h"
#include "btf_noise.h"
#include "core/core.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define RUNS 5
#define CALLS 4000000u /* btf_noise4 / btf_philox calls per run */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Results feed this so the compiler cannot drop the work. */
static volatile float sink_f;
static volatile uint32_t sink_u;

static double run_noise4(void)
{
    float acc = 0.0f;
    double t0 = now();
    for (uint32_t i = 0; i < CALLS; i++) {
        btf_vec4 v = btf_noise4(1u, 2u, 3u, i >> 10, i & 1023u);
        acc += v.x + v.y + v.z + v.w;
    }
    double t = now() - t0;
    sink_f = acc;
    return t * 1e9 / (4.0 * CALLS);
}

static double run_noise1(void)
{
    float acc = 0.0f;
    double t0 = now();
    for (uint32_t i = 0; i < CALLS; i++)
        acc += btf_noise1(1u, 2u, 3u, i >> 12, i & 4095u);
    double t = now() - t0;
    sink_f = acc;
    return t * 1e9 / CALLS;
}

static double run_philox(void)
{
    uint32_t acc = 0;
    double t0 = now();
    for (uint32_t i = 0; i < CALLS; i++) {
        btf_uvec4 w = btf_philox(btf_make_uvec4(i, 7u, 3u, BTF_NOISE_TAG), btf_make_uvec2(1u, 2u));
        acc ^= w.x ^ w.y ^ w.z ^ w.w;
    }
    double t = now() - t0;
    sink_u = acc;
    return t * 1e9 / CALLS;
}

static double run_rows(void)
{
    enum { BLOCKS = 136 };
    static float row[4 * BLOCKS];
    float acc = 0.0f;
    uint32_t rows = CALLS / BLOCKS;
    double t0 = now();
    for (uint32_t r = 0; r < rows; r++) {
        btf__noise_blocks(1u, 2u, 3u, r, 67108860u, BLOCKS, 1, row);
        acc += row[r % (4 * BLOCKS)];
    }
    double t = now() - t0;
    sink_f = acc;
    return t * 1e9 / (4.0 * BLOCKS * rows);
}

static void report(const char *what, const char *unit, double (*fn)(void))
{
    double r[RUNS];
    fn(); /* warm up */
    for (int i = 0; i < RUNS; i++)
        r[i] = fn();
    qsort(r, RUNS, sizeof r[0], cmp_double);
    printf("noise: %-40s %6.2f ns/%s (median of %d; min %.2f, max %.2f)\n", what, r[RUNS / 2],
           unit, RUNS, r[0], r[RUNS - 1]);
}

int main(void)
{
    printf("== noise (src/synth/btf_noise.h), one core\n");
    report("btf_noise4 (Philox + 2 Box-Muller pairs)", "Gaussian", run_noise4);
    report("btf_noise1 (Philox + 1 Box-Muller pair)", "Gaussian", run_noise1);
    report("btf_philox (Philox-4x32-7 alone)", "call", run_philox);
    report(btf__noise_avx2_available() ? "btf_noise_blocks (rows, AVX2 path)"
                                 : "btf_noise_blocks (rows, portable path)",
           "Gaussian", run_rows);
    return 0;
}
