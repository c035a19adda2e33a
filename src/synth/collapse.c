/*
 * collapse.c — the synthesis pyramid of one spectral band, streamed row by
 * row (Haindl & Filip 2007, section II.C: each level of the
 * Gaussian-Laplacian pyramid is synthesised as its own CAR field and the
 * pyramid is collapsed, G_l = mean_l + Y_l + up(G_{l+1})).
 *
 * Level windows follow src/synth/geometry.h: level l + 1 covers what
 * up-sampling level l reads. A row of G_l needs the field's row and two or
 * three rows of G_{l+1} up-sampled horizontally to level l's window; those
 * are kept in a ring of 3 per level, so every level holds a few rows only
 * and memory grows with the width, not the height.
 *
 * The three bands of a subspace have the same windows and ask for the same
 * rows in the same order (only their fields' margins differ), so every
 * step is taken for all of them together and the row generator can run
 * their sequential recursions in one loop (rows.c). Each band's results
 * are what it would get alone.
 */
#include "core/core.h"
#include "synth/synth.h"

#include "btf_noise.h"
#include "btf_shared.h"
#include "geometry.h"

#include <stdlib.h>
#include <string.h>

void synth_band_free(synth_band *sb)
{
    for (int l = 0; l < sb->levels; l++) {
        synth_level *lv = &sb->level[l];
        synth_field_free(&lv->field);
        free(lv->gauss_row);
        for (int k = 0; k < 3; k++)
            free(lv->up_rows[k]);
    }
    memset(sb, 0, sizeof *sb);
}

btf_status synth_band_init(synth_band *sb, const btf_car_band *bands, const int *margins,
                           int levels, int subspace, int band, int w, int h, uint64_t seed,
                           const synth_paths *paths, btf_error *err)
{
    memset(sb, 0, sizeof *sb);
    sb->seed_lo = (uint32_t)seed;
    sb->seed_hi = (uint32_t)(seed >> 32);
    btf_span xs = {0, w}, ys = {0, h};
    for (int l = 0; l < levels; l++) {
        synth_level *lv = &sb->level[l];
        sb->levels = l + 1; /* what synth_band_free frees, should this level fail */
        lv->x0 = xs.lo, lv->x1 = xs.hi, lv->y0 = ys.lo, lv->y1 = ys.hi;
        for (int k = 0; k < 3; k++)
            lv->up_row_of[k] = INT32_MIN;
        uint32_t stream = btf_noise_stream((uint32_t)subspace, (uint32_t)band, (uint32_t)l);
        /* tileable: level l's noise has the period of its share of the
         * output, (w >> l) x (h >> l) (docs/synthesis.md, "Tileable synthesis") */
        btf_status rc = synth_field_init(&lv->field, &bands[l], margins[l], stream, xs.lo, xs.hi,
                                         ys.lo, ys.hi, w >> l, h >> l, paths, err);
        if (rc == BTF_OK && !(lv->gauss_row = btf__alloc((size_t)(xs.hi - xs.lo), sizeof(float),
                                                       err)))
            rc = BTF_E_NOMEM;
        if (rc == BTF_OK && l > 0) {
            lv->fine_x0 = sb->level[l - 1].x0;
            lv->fine_w = sb->level[l - 1].x1 - sb->level[l - 1].x0;
            for (int k = 0; rc == BTF_OK && k < 3; k++)
                if (!(lv->up_rows[k] = btf__alloc((size_t)lv->fine_w, sizeof(float), err)))
                    rc = BTF_E_NOMEM;
        }
        if (rc) {
            synth_band_free(sb);
            return rc;
        }
        xs = btf_coarser_span(xs);
        ys = btf_coarser_span(ys);
    }
    return BTF_OK;
}

/* Zero-mean field row y of level l of each band, over the level's window. */
static void field_rows(synth_band *sb, int nb, int l, int y, const float **rows)
{
    synth_field *f[3];
    for (int b = 0; b < nb; b++)
        f[b] = &sb[b].level[l].field;
    synth_field_rows(f, nb, y, sb[0].seed_lo, sb[0].seed_hi, rows);
}

/* Row i of G_l (l >= 1) of each band up-sampled horizontally to the window
 * of level l - 1, from the 3-slot rings (all bands' rings hold the same
 * rows). Rows are requested in increasing order. */
static void up_rows(synth_band *sb, int nb, int l, int i, const float **out)
{
    int slot = ((i % 3) + 3) % 3;
    if (sb[0].level[l].up_row_of[slot] != i) {
        const float *rows[3];
        synth_gauss_rows(sb, nb, l, i, rows);
        for (int b = 0; b < nb; b++) {
            synth_level *lv = &sb[b].level[l];
            btf__up_row(rows[b], lv->x0, lv->fine_x0, lv->fine_w, lv->up_rows[slot]);
            lv->up_row_of[slot] = i;
        }
    }
    for (int b = 0; b < nb; b++)
        out[b] = sb[b].level[l].up_rows[slot];
}

static void gauss_rows(synth_band *sb, int nb, int l, int y, const float **out,
                       float *const *dst);

void synth_gauss_rows(synth_band *sb, int nb, int l, int y, const float **out)
{
    gauss_rows(sb, nb, l, y, out, NULL);
}

void synth_gauss_rows_to(synth_band *sb, int nb, int y, float *const *dst)
{
    const float *out[3];
    gauss_rows(sb, nb, 0, y, out, dst);
}

static void gauss_rows(synth_band *sb, int nb, int l, int y, const float **out,
                       float *const *dst)
{
    const float *f[3];
    field_rows(sb, nb, l, y, f);
    int last = l == sb[0].levels - 1;
    const float *a[3], *b[3], *c[3];
    int i = btf_floordiv2(y);
    if (!last && (y & 1)) {
        up_rows(sb, nb, l + 1, i, b);
        up_rows(sb, nb, l + 1, i + 1, c);
    } else if (!last) {
        /* Fetch in increasing order: i - 1, i, i + 1 share the 3-slot ring. */
        up_rows(sb, nb, l + 1, i - 1, a);
        up_rows(sb, nb, l + 1, i, b);
        up_rows(sb, nb, l + 1, i + 1, c);
    }
    for (int n = 0; n < nb; n++) {
        synth_level *lv = &sb[n].level[l];
        int w = lv->x1 - lv->x0;
        float mean = lv->field.band->mean, *g = dst ? dst[n] : lv->gauss_row;
        if (last)
            btf__level_sum_row(w, mean, f[n], NULL, NULL, NULL, g);
        else if (y & 1)
            btf__level_sum_row(w, mean, f[n], NULL, b[n], c[n], g);
        else
            btf__level_sum_row(w, mean, f[n], a[n], b[n], c[n], g);
        out[n] = g;
    }
}
