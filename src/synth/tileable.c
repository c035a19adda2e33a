/*
 * tileable.c — the exact reference of tileable synthesis (docs/synthesis.md,
 * "Tileable synthesis"), for tests only (synth_testing.h,
 * btf__synthesise_torus_dft): the pyramid of Haindl & Filip 2007, section
 * II.C, on a torus. Production tileable synthesis is the streaming
 * recursion driven by periodic noise (field.c, rows.c), whose window
 * converges to these fields; tests/unit/test_synth_tileable.c measures how close. Every level l of every spectral band is a CAR field on the
 * (W >> l) x (H >> l) torus (torus.c); the pyramid collapses as in the
 * streaming path, G_l = mean_l + Y_l + up(G_{l+1}), with the same pyrUp
 * weights (btf__up_row, btf__level_sum_row) but coarse indices taken modulo
 * the coarse size, so up-sampling a periodic level gives a periodic level;
 * the decorrelation is undone row by row (colour.c). Each output pixel then
 * depends on its neighbours across the right and bottom edges exactly as on
 * those inside: tiling the image shows no seam.
 *
 * Unlike the streaming path this holds whole fields: the three band planes
 * (12 bytes a pixel), and while a level is solved its DFT (16 bytes a pixel
 * here, some 32 more inside OpenCV), the finer level's up-sampled rows and
 * the coarser level (about 7). Hence BTF_SYNTH_TILE_MAX_PIXELS.
 */
#include "core/core.h"
#include "synth/synth.h"
#include "synth/synth_testing.h"

#include "btf_noise.h"
#include "btf_shared.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The largest prime factor of n >= 1 (1 for n = 1). */
static int largest_prime_factor(int n)
{
    int p = 1;
    for (int d = 2; (long)d * d <= n; d++)
        while (n % d == 0)
            p = d, n /= d;
    return n > 1 ? n : p;
}

/* The multiple of `factor` nearest to side whose prime factors are all at
 * most BTF_SYNTH_TILE_MAX_PRIME (the smaller of two at the same distance). */
static int nearest_smooth(int side, int factor)
{
    for (int d = 0;; d += factor) {
        if (side - d >= factor && largest_prime_factor(side - d) <= BTF_SYNTH_TILE_MAX_PRIME)
            return side - d;
        if (largest_prime_factor(side + d) <= BTF_SYNTH_TILE_MAX_PRIME)
            return side + d;
    }
}

/* The DFT reference's sizes: tileable ones, within its memory and prime
 * factor bounds. */
static btf_status check_torus_size(int width, int height, int levels, btf_error *err)
{
    btf_status rc = btf__synth_check_tileable(width, height, levels, err);
    if (rc)
        return rc;
    if ((uint64_t)width * (uint64_t)height > BTF_SYNTH_TILE_MAX_PIXELS)
        return btf__fail(err, BTF_E_ARG, "tileable synthesis of %dx%d: more than %llu pixels "
                         "(it holds whole fields, about 85 bytes a pixel); the streaming "
                         "synthesis has no such bound", width, height,
                         (unsigned long long)BTF_SYNTH_TILE_MAX_PIXELS);
    /* OpenCV's DFT costs a length-n transform about n p for a prime factor
     * p: a side of a large prime would take hours (docs/synthesis.md). */
    for (int k = 0; k < 2; k++) {
        int side = k ? height : width, p = largest_prime_factor(side);
        if (p > BTF_SYNTH_TILE_MAX_PRIME)
            return btf__fail(err, BTF_E_ARG, "tileable synthesis of %dx%d: %d has the prime "
                             "factor %d, and the DFT that solves the torus is slow for primes "
                             "above %d; %d would do", width, height, side, p,
                             BTF_SYNTH_TILE_MAX_PRIME, nearest_smooth(side, 1 << (levels - 1)));
    }
    return BTF_OK;
}

/* Coarse rows (ch rows of cw) up-sampled horizontally with wrap-around to
 * fine width 2 cw, into up (ch rows of 2 cw); row (cw + 2 floats of
 * scratch) holds a coarse row between its wrapped neighbours. */
static void up_rows_periodic(const float *coarse, int cw, int ch, float *row, float *up)
{
    for (int r = 0; r < ch; r++) {
        const float *c = coarse + (size_t)r * cw;
        row[0] = c[cw - 1]; /* coarse column -1 */
        memcpy(row + 1, c, (size_t)cw * sizeof(float));
        row[cw + 1] = c[0]; /* coarse column cw */
        btf__up_row(row, -1, 0, 2 * cw, up + (size_t)r * 2 * cw);
    }
}

/* G_l (fw x fh, holding the level's zero-mean field on entry) = mean + Y_l
 * + the vertical pyrUp of up (the coarser level up-sampled horizontally,
 * fh / 2 rows), rows wrapping around: fine row y reads coarse rows
 * y / 2 - 1 .. y / 2 + 1 modulo fh / 2. */
static void level_sum_periodic(float *g, int fw, int fh, float mean, const float *up)
{
    int ch = fh / 2;
    for (int y = 0; y < fh; y++) {
        int i = y / 2;
        const float *a = up + (size_t)((i + ch - 1) % ch) * fw;
        const float *b = up + (size_t)i * fw, *c = up + (size_t)((i + 1) % ch) * fw;
        float *row = g + (size_t)y * fw;
        /* in place: each output sample reads its own field sample only */
        btf__level_sum_row(fw, mean, row, (y & 1) ? NULL : a, b, c, row);
    }
}

/* The mean at every pixel of the coarsest level: G = mean + Y. */
static void add_mean(float *g, size_t n, float mean)
{
    for (size_t i = 0; i < n; i++)
        g[i] = btf_add_mean(mean, g[i]);
}

/* Spectral band `band` of a subspace collapsed to level 0 (w x h) in out. */
static btf_status band_plane(const btf_subspace_model *sm, int subspace, int band, int w, int h,
                             uint64_t seed, int vector_noise, float *out, btf_error *err)
{
    int top = sm->levels - 1;
    /* the coarser level's G, this level's, the coarser one's up-sampled rows, a row */
    float *coarse = NULL, *fine = NULL, *up = NULL, *row = NULL;
    btf_status rc = BTF_OK;
    for (int l = top; rc == BTF_OK && l >= 0; l--) {
        int fw = w >> l, fh = h >> l;
        char what[96];
        snprintf(what, sizeof what, "subspace %d, band %d, level %d", subspace, band, l);
        float *g = l == 0 ? out : (fine = btf__alloc((size_t)fw * fh, sizeof(float), err));
        if (!g)
            rc = BTF_E_NOMEM;
        uint32_t stream = btf_noise_stream((uint32_t)subspace, (uint32_t)band, (uint32_t)l);
        if (rc == BTF_OK)
            rc = synth_torus_field(&sm->bands[band][l], stream, fw, fh, seed, vector_noise, what,
                                   g, err);
        if (rc == BTF_OK && l == top)
            add_mean(g, (size_t)fw * fh, sm->bands[band][l].mean);
        if (rc == BTF_OK && l < top) {
            up = btf__alloc((size_t)fw * (fh / 2), sizeof(float), err);
            row = up ? btf__alloc((size_t)fw / 2 + 2, sizeof(float), err) : NULL;
            if (!row)
                rc = BTF_E_NOMEM;
        }
        if (rc == BTF_OK && l < top) {
            up_rows_periodic(coarse, fw / 2, fh / 2, row, up);
            level_sum_periodic(g, fw, fh, sm->bands[band][l].mean, up);
        }
        free(up), free(row), free(coarse);
        up = row = coarse = NULL;
        if (rc == BTF_OK && g != out) /* this level is the next one's coarser */
            coarse = g, fine = NULL;
    }
    free(coarse);
    free(fine);
    return rc;
}

/* The three spectral bands are independent: one pool job each. */
typedef struct band_jobs {
    const btf_subspace_model *sm;
    int subspace, w, h, vector_noise;
    uint64_t seed;
    float *planes;
} band_jobs;

static btf_status band_job(void *user, int band, int worker, btf_error *err)
{
    (void)worker;
    const band_jobs *j = user;
    size_t n = (size_t)j->w * j->h;
    return band_plane(j->sm, j->subspace, band, j->w, j->h, j->seed, j->vector_noise,
                      j->planes + n * band, err);
}

static int image_rows(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    btf_image *img = user;
    size_t n = (size_t)img->width * 3;
    memcpy(img->data + (size_t)y * n, rows, (size_t)nrows * n * sizeof(float));
    return 0;
}

btf_status btf__synthesise_tileable(const btf_model *m, int subspace, const btf_synth_opts *o,
                                    int w, int h, btf_rows_fn fn, void *user, btf_error *err)
{
    const btf_subspace_model *sm = &m->subspaces[subspace];
    btf_status rc = check_torus_size(w, h, sm->levels, err);
    if (rc)
        return rc;
    size_t n = (size_t)w * h;
    btf_marginal_table mt;
    btf__marginal_table_make(sm, &mt);
    float *planes = btf__alloc(n * 3 + (size_t)w * (3 + BTF_UNMIX_SCRATCH), sizeof(float), err);
    if (!planes)
        return BTF_E_NOMEM;
    float *rgb = planes + n * 3, *scratch = rgb + (size_t)w * 3;
    band_jobs jobs = {sm, subspace, w, h, !o->portable_noise, o->seed, planes};
    /* a band's plane depends on the band alone: the same bytes on any
     * number of threads (0: every CPU, at most 3 here) */
    rc = btf__pool_run(3, 0, band_job, &jobs, NULL, err);
    for (int y = 0; rc == BTF_OK && y < h; y++) {
        size_t at = (size_t)y * w;
        if (btf__unmix_row(sm, &mt, planes + at, planes + n + at, planes + 2 * n + at, w, scratch, rgb))
            rc = btf__check_finite_row(rgb, (size_t)w * 3, subspace, y, err);
        if (rc == BTF_OK)
            rc = btf__synth_emit_row(fn, user, y, rgb, err);
    }
    free(planes);
    return rc;
}

btf_status btf__synthesise_torus_dft(const btf_model *m, int subspace, const btf_synth_opts *opts,
                                     btf_image *out, btf_error *err)
{
    memset(out, 0, sizeof *out);
    btf_synth_opts o;
    if (btf__synth_resolve(opts, &o, err))
        return BTF_E_ARG;
    if (!m || subspace < 0 || subspace >= m->n_subspaces)
        return btf__fail(err, BTF_E_ARG, "subspace %d: the model has %d", subspace,
                         m ? m->n_subspaces : 0);
    const btf_subspace_model *sm = &m->subspaces[subspace];
    int w = o.width ? o.width : sm->width, h = o.height ? o.height : sm->height;
    btf_status rc = btf__synth_check_size(w, h, err);
    if (rc == BTF_OK)
        rc = check_torus_size(w, h, sm->levels, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, w, h, 3, err);
    if (rc == BTF_OK)
        rc = btf__synthesise_tileable(m, subspace, &o, w, h, image_rows, out, err);
    if (rc)
        btf_image_free(out);
    return rc;
}
