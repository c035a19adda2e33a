/*
 * field.c — one CAR random field of a pyramid level (Haindl & Filip 2007,
 * section II.C: every sub-band level is synthesised by its causal
 * recursion): the field covers the level's window plus the band's margin
 * on either side and starts `margin` rows above it, with zeros outside, so
 * that the zero boundary's transient has died out before the window
 * (src/car/margin.c). Rows go top to bottom into a ring holding the rows
 * the recursion reaches back to: memory grows with the width only.
 *
 * Two generators fill the ring, with the same bits: the wavefront
 * (wave.c, eight rows per AVX2 step) where the band, the width and the CPU
 * qualify and the caller allows it, else row by row (rows.c). A tileable
 * field (periodic noise, the same recursion) always runs row by row.
 */
#include "core/core.h"
#include "synth/synth.h"

#include <stdlib.h>
#include <string.h>

btf_status synth_field_init(synth_field *f, const btf_car_band *band, int margin,
                            uint32_t stream, int x0, int x1, int y0, int y1, int period_w,
                            int period_h, const synth_paths *paths, btf_error *err)
{
    memset(f, 0, sizeof *f);
    f->band = band;
    f->stream = stream;
    f->window_x0 = x0;
    f->end = y1;
    f->fx0 = x0 - margin;
    f->fw = (x1 - x0) + 2 * margin;
    f->vector_noise = paths->vector_noise;
    int up = 0;
    f->pad = 1;
    for (int s = 0; s < band->n; s++) {
        if (-band->offsets[s].row > up)
            up = -band->offsets[s].row;
        int c = band->offsets[s].col < 0 ? -band->offsets[s].col : band->offsets[s].col;
        if (c > f->pad)
            f->pad = c;
    }
    f->depth = up + 2;
    int periodic = paths->tileable && period_w > 0 && period_h > 0;
    /* The wavefront draws each lane's noise blocks inline from its
     * coordinates; periodic noise is a lookup of one period instead (rows.c),
     * so periodic fields run row by row (the same sums: the same bits as the
     * GPU's, which wraps the coordinates of every pixel's noise). */
    int wave = paths->wave && !periodic && btf__wave_supported(band, f->fw);
    if (wave) {
        f->depth = BTF_WAVE_DEPTH;
        f->pad = btf__wave_pad();
    }
    f->same_row_shape = btf__car_same_row_shape(band, f->same_row_gamma3);
    int same[BTF_CAR_MAX_NEIGHBOURS];
    f->n_same_row = btf__car_same_row_order(band, same);
    for (int t = 0; t < f->n_same_row; t++) {
        f->same_row_col[t] = band->offsets[same[t]].col;
        f->same_row_gamma[t] = band->gamma[same[t]];
    }
    f->next = y0 - margin;
    f->ring = btf__calloc((size_t)f->depth * (f->fw + 2 * f->pad), sizeof(float), err);
    if (!f->ring)
        return BTF_E_NOMEM;
    if (wave) /* the wave draws its noise lane by lane: no noise or sum rows */
        return (f->wave = btf__wave_new(band, f->fw, f->fx0, f->next, stream, f->ring, f->depth,
                                        f->pad, err)) ? BTF_OK : BTF_E_NOMEM;
    if (periodic) {
        f->period_w = period_w, f->period_h = period_h;
        if (!(f->period_noise = btf__alloc((size_t)period_w + 4, sizeof(float), err)))
            return BTF_E_NOMEM;
    }
    f->noise = btf__alloc((size_t)f->fw + 6, sizeof(float), err);
    f->noise_next = btf__alloc((size_t)f->fw + 6, sizeof(float), err);
    f->acc = btf__alloc((size_t)f->fw, sizeof(float), err);
    f->acc_next = btf__alloc((size_t)f->fw, sizeof(float), err);
    return f->noise && f->noise_next && f->acc && f->acc_next ? BTF_OK : BTF_E_NOMEM;
}

void synth_field_free(synth_field *f)
{
    BTF_FREE_ALL(f->ring, f->noise, f->noise_next, f->acc, f->acc_next, f->period_noise);
    btf__wave_free(f->wave);
    memset(f, 0, sizeof *f);
}

/* Advances the n fields, all at row r = next: a field with a wavefront by
 * one row through it; the others together, by two rows when row r + 1 is
 * wanted too (below `until`) and the rows are wide enough, else by one. */
static void advance(synth_field *const *all, int n_all, int until, uint32_t seed_lo,
                    uint32_t seed_hi)
{
    synth_field *f[3];
    int n = 0;
    for (int b = 0; b < n_all; b++) {
        if (all[b]->wave) /* a wave runs eight rows at once on its own */
            btf__wave_run(all[b]->wave, all[b]->next++, seed_lo, seed_hi);
        else
            f[n++] = all[b];
    }
    if (n == 0)
        return;
    int lead = btf__rows_pair_lead(f, n), narrow = 0;
    for (int b = 0; b < n; b++)
        narrow |= f[b]->fw < 2 * lead;
    if (f[0]->next + 1 < until && !narrow)
        btf__rows_pair(f, n, lead, seed_lo, seed_hi);
    else
        btf__rows_step(f, n, seed_lo, seed_hi);
}

const float *synth_field_row(synth_field *f, int y, uint32_t seed_lo, uint32_t seed_hi)
{
    while (f->next <= y)
        advance(&f, 1, f->end, seed_lo, seed_hi);
    return synth_field_ring_row(f, y) + (f->window_x0 - f->fx0);
}

void synth_field_rows(synth_field *const *f, int n, int y, uint32_t seed_lo, uint32_t seed_hi,
                      const float **rows)
{
    synth_field *due[3];
    int ndue = 0;
    for (int b = 0; b < n; b++) {
        /* Burn-in rows differ with the margin: each field alone up to y - 1. */
        while (f[b]->next < y)
            advance(&f[b], 1, y, seed_lo, seed_hi);
        if (f[b]->next == y)
            due[ndue++] = f[b];
    }
    if (ndue > 0) /* row y (and y + 1) of all fields at once */
        advance(due, ndue, due[0]->end, seed_lo, seed_hi);
    for (int b = 0; b < n; b++)
        rows[b] = synth_field_ring_row(f[b], y) + (f[b]->window_x0 - f[b]->fx0);
}
