/*
 * chains.c — the sequential part of a CAR field row (Haindl & Filip 2007,
 * section II.C: the causal recursion): each pixel adds the same-row
 * neighbours to its left, so a row is a chain in which one pixel waits on
 * the previous one. Several independent chains (rows of other bands, the
 * next row of the same band) run in one loop so that the core overlaps
 * their latencies; each chain's sums are what it would get alone, in the
 * order of src/synth/btf_shared.h (farthest column first).
 */
#include "synth/synth.h"

#include "btf_shared.h"

/* n_chains chains of one shape (same-row columns -shape .. -1) in one loop:
 * independent chains, so the core overlaps their latencies (one pixel waits
 * on the previous one for a multiply and an add, 6 cycles on Zen 3, the
 * largest cost of synthesis after the noise when a chain runs alone).
 * n_chains and shape are constants in each copy (btf__chains below), so the
 * tests on shape fold away and the chains' last values live in registers.
 * A missing term is skipped, never added as 0 * y, which could turn -0 into
 * +0. */
static inline __attribute__((always_inline)) void chains_run(const synth_chain *c,
                                                             const int n_chains,
                                                             const int shape, int len)
{
    const float *acc[SYNTH_MAX_CHAINS];
    float *out[SYNTH_MAX_CHAINS];
    float g0[SYNTH_MAX_CHAINS], g1[SYNTH_MAX_CHAINS], g2[SYNTH_MAX_CHAINS];
    float y1[SYNTH_MAX_CHAINS], y2[SYNTH_MAX_CHAINS], y3[SYNTH_MAX_CHAINS];
    for (int s = 0; s < n_chains; s++) {
        acc[s] = c[s].acc;
        out[s] = c[s].out;
        g0[s] = c[s].gamma3[0], g1[s] = c[s].gamma3[1], g2[s] = c[s].gamma3[2];
        y1[s] = shape >= 1 ? out[s][-1] : 0.0f;
        y2[s] = shape >= 2 ? out[s][-2] : 0.0f;
        y3[s] = shape >= 3 ? out[s][-3] : 0.0f;
    }
    for (int i = 0; i < len; i++) {
        _Pragma("GCC unroll 6") for (int s = 0; s < n_chains; s++) {
            float v = acc[s][i];
            if (shape >= 3)
                v = btf_car_accumulate(v, g0[s], y3[s]);
            if (shape >= 2)
                v = btf_car_accumulate(v, g1[s], y2[s]);
            if (shape >= 1)
                v = btf_car_accumulate(v, g2[s], y1[s]);
            y3[s] = y2[s];
            y2[s] = y1[s];
            out[s][i] = y1[s] = v;
        }
    }
}

void btf__chains(const synth_chain *c, int n_chains, int shape, int len)
{
    switch (n_chains * 4 + shape) {
#define CHAINS_CASE(n_, shape_)                                                                  \
    case (n_) * 4 + (shape_):                                                                    \
        chains_run(c, n_, shape_, len);                                                          \
        return;
#define CHAINS_SHAPES(n_) CHAINS_CASE(n_, 0) CHAINS_CASE(n_, 1) CHAINS_CASE(n_, 2) CHAINS_CASE(n_, 3)
        CHAINS_SHAPES(1)
        CHAINS_SHAPES(2)
        CHAINS_SHAPES(3)
        CHAINS_SHAPES(4)
        CHAINS_SHAPES(5)
        CHAINS_SHAPES(6)
#undef CHAINS_SHAPES
#undef CHAINS_CASE
    }
}
