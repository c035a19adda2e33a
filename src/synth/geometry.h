/*
 * geometry.h — the windows of the synthesis pyramid (Haindl & Filip 2007,
 * section II.C: each sub-band level is synthesised as its own CAR field and
 * the Gaussian-Laplacian pyramid is collapsed), shared by the CPU code
 * (src/synth/collapse.c) and the GPU host code (gpu/synth_gpu.c) so that
 * both compute the same fields over the same pixels.
 *
 * Level 0 covers the output window [x0, x1) x [y0, y1). Level l + 1 covers
 * what up-sampling level l reads: a fine pixel x reads coarse pixels
 * floor(x / 2) - 1 .. floor(x / 2) + 1 (btf_up_even, btf_up_odd), so the
 * coarser window is [floor(x0 / 2) - 1, floor((x1 - 1) / 2) + 2), the same
 * along rows. Each level's field then runs its band's margin beyond the
 * window (src/car/margin.c).
 */
#ifndef BTF_SYNTH_GEOMETRY_H
#define BTF_SYNTH_GEOMETRY_H

#include "btf_shared.h" /* btf_floordiv2, also used by the collapse shader */

/* A half-open span [lo, hi) of columns or rows. */
typedef struct btf_span {
    int lo, hi;
} btf_span;

/* The span of the next coarser level that up-sampling a span reads. */
static inline btf_span btf_coarser_span(btf_span s)
{
    btf_span c = {btf_floordiv2(s.lo) - 1, btf_floordiv2(s.hi - 1) + 2};
    return c;
}

/* The span of level `level` that output span s (level 0) reads. */
static inline btf_span btf_level_span(btf_span s, int level)
{
    for (int l = 0; l < level; l++)
        s = btf_coarser_span(s);
    return s;
}

#endif
