/*
 * model_check.c — the validator of models (docs/model-format.md, "Validation"):
 * direction sets, the index table, every subspace's spectral basis and CAR
 * bands (paper section II.C: causal neighbourhoods, finite coefficients,
 * sigma >= 0), and the range-map tile (section II.B). The encoder runs it
 * before writing and the decoder after reading, so the two agree on what a
 * model is, and the decoder trusts nothing it has not checked.
 */
#include "car/car.h"
#include "container/container.h"
#include "model/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Rows of the basis must be orthonormal within this: synthesis inverts the
 * basis by transposition. */
#define BASIS_TOL 1e-3

#define failf btf__box_fail

/* A set of no directions is a model of a single texture; the pole at
 * several phi is left to the renderer, which refuses it: a set of such
 * images is a measurement, if not one it interpolates. */
static btf_status check_dirset(const btf_dirset *s, const char *what, const char *name,
                               btf_status code, btf_error *err)
{
    if (s->count < 0 || s->count > BTF_MODEL_MAX_DIRS)
        return failf(err, code, name, "%s: %d directions (expected 0..%d)", what, s->count,
                     BTF_MODEL_MAX_DIRS);
    if (s->count == 0)
        return BTF_OK;
    if (!s->dirs)
        return failf(err, code, name, "%s: no direction array (expected %d directions)", what,
                     s->count);
    size_t len = strnlen(s->name, sizeof s->name);
    if (len > BTF_MODEL_MAX_NAME)
        return failf(err, code, name, "%s: set name is not terminated (expected at most %d characters)",
                     what, BTF_MODEL_MAX_NAME);
    size_t bad = btf__box_name_unprintable(s->name, len);
    if (bad < len)
        return failf(err, code, name, "%s: set name has byte 0x%02x (expected printable ASCII)",
                     what, (unsigned char)s->name[bad]);
    for (int i = 0; i < s->count; i++)
        if (!btf__box_dir_in_range(s->dirs[i]))
            return failf(err, code, name,
                         "%s: direction %d is (theta %g, phi %g) (expected theta in [0, 90], "
                         "phi in [0, 360))", what, i, s->dirs[i].theta, s->dirs[i].phi);
    int j, i = btf__box_dirs_repeat(s, &j);
    if (i >= 0)
        return failf(err, code, name, "%s: directions %d and %d are both (theta %g, phi %g) "
                     "(expected distinct directions)", what, i, j, s->dirs[i].theta,
                     s->dirs[i].phi);
    return BTF_OK;
}

/* BTF_MODEL_MAX_VALUE (1e30) bounds what synthesis adds or multiplies per
 * band: sigma, the band's mean, the subspace's colour mean. The worst case
 * of the arithmetic it then does (src/synth/) in float, whose limit is
 * 3.4e38:
 *  - noise: |e| <= 5.77 (btf_noise.h), so |sigma e| <= 5.8e30;
 *  - the recursion Y = sum gamma Y' + sigma e multiplies that by its gain
 *    G, the sum of |h| over its impulse response: 1 / (1 - sum |gamma|)
 *    when sum |gamma| < 1; for other bands the stability check
 *    (car/stability.c) keeps |A(w)|^2 above 1e-6, a spectral gain below
 *    1000;
 *  - the collapse G_l = mean + Y_l + pyrUp(G_{l+1}) adds at most 8 levels,
 *    and pyrUp's a + c + 6 b holds 8 times a coarse value before its / 8:
 *    at most 64 (1e30 + 5.8e30 G);
 *  - the colour transform, mean + 3 basis entries (each |b| <= 1) times a
 *    band, adds 1e30 and 3 times that (a marginal transfer replaces the
 *    bands by quantiles of at most 1e37 first: 3e37 + 1e30).
 * Together at most 1.9e32 + 1.1e33 G: finite for every G up to 3e5, about
 * 50 times the largest gain measured on fitted bands (tens to some
 * thousands; generated leather, wood and fabric textures). A larger G still
 * meets synthesis' own check, BTF_E_NUMERIC naming the row, never Inf or
 * NaN. The exemplars texture-fit accepts
 * (|value| <= BTF_EXEMPLAR_MAX_VALUE, 1e28) give bands well inside it. */
static btf_status check_band(const btf_car_band *b, const char *where, const char *name,
                             btf_status code, btf_error *err)
{
    if (b->n < 0 || b->n > BTF_CAR_MAX_NEIGHBOURS)
        return failf(err, code, name, "%s: %d neighbours (expected 0..%d)", where, b->n,
                     BTF_CAR_MAX_NEIGHBOURS);
    for (int i = 0; i < b->n; i++) {
        btf_offset o = b->offsets[i];
        if (!btf__offset_is_causal(o))
            return failf(err, code, name,
                         "%s: neighbour offset %d:%d is not causal (expected row < 0, or row 0 "
                         "and column < 0)", where, o.row, o.col);
        /* The neighbourhood parser's limit: reaches beyond 64 would make
         * the GPU wavefront needlessly long (its slope grows with them). */
        if (o.row < -64 || o.col < -64 || o.col > 64)
            return failf(err, code, name,
                         "%s: neighbour offset %d:%d reaches beyond 64 pixels (expected rows and "
                         "columns within -64..64)", where, o.row, o.col);
        for (int j = 0; j < i; j++)
            if (b->offsets[j].row == o.row && b->offsets[j].col == o.col)
                return failf(err, code, name,
                             "%s: neighbour offset %d:%d appears twice (expected distinct offsets)",
                             where, o.row, o.col);
        if (!isfinite(b->gamma[i]))
            return failf(err, code, name, "%s: gamma[%d] is %g (expected a finite number)", where,
                         i, b->gamma[i]);
    }
    if (!(b->sigma >= 0.0f && b->sigma <= BTF_MODEL_MAX_VALUE))
        return failf(err, code, name, "%s: sigma is %g (expected a number in 0..%g, what "
                     "synthesis keeps within float)", where, b->sigma, BTF_MODEL_MAX_VALUE);
    if (!(fabsf(b->mean) <= BTF_MODEL_MAX_VALUE))
        return failf(err, code, name, "%s: mean is %g (expected a number of magnitude at most "
                     "%g, what synthesis keeps within float)", where, b->mean,
                     BTF_MODEL_MAX_VALUE);
    return BTF_OK;
}

/* The basis must be orthonormal: synthesis inverts it by transposition. */
static btf_status check_basis(const float *basis, int s, const char *name, btf_status code,
                              btf_error *err)
{
    for (int i = 0; i < 9; i++)
        if (!isfinite(basis[i]))
            return failf(err, code, name, "subspace %d: basis[%d] is %g (expected a finite number)",
                         s, i, basis[i]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j <= i; j++) {
            double dot = 0.0;
            for (int k = 0; k < 3; k++)
                dot += (double)basis[3 * i + k] * basis[3 * j + k];
            if (fabs(dot - (i == j)) > BASIS_TOL)
                return failf(err, code, name,
                             "subspace %d: basis rows %d and %d have dot product %g (expected an "
                             "orthonormal basis, within %g)", s, i, j, dot, BASIS_TOL);
        }
    return BTF_OK;
}

/* The marginal transfer (docs/model-format.md, "MARG"): none, or 32 knots
 * per band with finite numbers, sd >= 0, nondecreasing quantiles, knots
 * z = mean +- 3.49 sd and quantiles well inside the float range (so that
 * slopes and differences of knots stay finite), and an RGB box 0 <= lo <=
 * hi. */
#define MARGIN_LIMIT 1e37f

/* The exemplar's Lab histogram (docs/model-format.md, "LABQ"): none, or 32
 * nondecreasing quantiles per channel, L* in [0, 100], a* and b* in
 * [-128, 128] (what the file's codes can hold). */
static btf_status check_lab(const btf_marginal *mg, int s, const char *name, btf_status code,
                            btf_error *err)
{
    if (mg->lab_knots == 0)
        return BTF_OK;
    if (mg->lab_knots != BTF_MARGIN_KNOTS)
        return failf(err, code, name, "subspace %d: Lab histogram of %d knots (expected 0 or %d)",
                     s, mg->lab_knots, BTF_MARGIN_KNOTS);
    static const char CH[3][3] = {"L*", "a*", "b*"};
    for (int c = 0; c < 3; c++) {
        float lo = c == 0 ? 0.0f : -128.0f, hi = c == 0 ? 100.0f : 128.0f;
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
            float q = mg->lab_quantile[c][j];
            if (!(q >= lo && q <= hi))
                return failf(err, code, name, "subspace %d: %s quantile %d is %g (expected %g..%g)",
                             s, CH[c], j, q, lo, hi);
            if (j > 0 && q < mg->lab_quantile[c][j - 1])
                return failf(err, code, name,
                             "subspace %d: %s quantile %d is %g, below quantile %d, %g (expected "
                             "nondecreasing quantiles)", s, CH[c], j, q, j - 1,
                             mg->lab_quantile[c][j - 1]);
        }
    }
    return BTF_OK;
}
static btf_status check_marginal(const btf_marginal *mg, int s, const char *name,
                                 btf_status code, btf_error *err)
{
    if (mg->knots == 0)
        return BTF_OK;
    if (mg->knots != BTF_MARGIN_KNOTS)
        return failf(err, code, name, "subspace %d: marginal transfer of %d knots (expected 0 or %d)",
                     s, mg->knots, BTF_MARGIN_KNOTS);
    for (int b = 0; b < 3; b++) {
        float mu = mg->synth_mean[b], sd = mg->synth_sd[b];
        if (!(fabsf(mu) <= MARGIN_LIMIT) || !(sd >= 0.0f && sd <= MARGIN_LIMIT))
            return failf(err, code, name,
                         "subspace %d, band %d: marginal transfer mean %g, sd %g (expected finite, "
                         "sd >= 0, magnitudes at most 1e37)", s, b, mu, sd);
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
            float q = mg->quantile[b][j];
            if (!(fabsf(q) <= MARGIN_LIMIT))
                return failf(err, code, name,
                             "subspace %d, band %d: marginal quantile %d is %g (expected a finite "
                             "number of magnitude at most 1e37)", s, b, j, q);
            if (j > 0 && q < mg->quantile[b][j - 1])
                return failf(err, code, name,
                             "subspace %d, band %d: marginal quantile %d is %g, below quantile %d, "
                             "%g (expected nondecreasing quantiles)", s, b, j, q, j - 1,
                             mg->quantile[b][j - 1]);
        }
    }
    for (int k = 0; k < 3; k++)
        if (!(mg->rgb_lo[k] >= 0.0f && mg->rgb_lo[k] <= mg->rgb_hi[k] &&
              mg->rgb_hi[k] <= MARGIN_LIMIT))
            return failf(err, code, name,
                         "subspace %d: RGB range [%g, %g] of channel %d (expected 0 <= low <= high, "
                         "finite)", s, mg->rgb_lo[k], mg->rgb_hi[k], k);
    return check_lab(mg, s, name, code, err);
}

static btf_status check_subspace(const btf_model *m, int s, const char *name, btf_status code,
                                 btf_error *err)
{
    const btf_subspace_model *sm = &m->subspaces[s];
    int none = sm->view == -1 && sm->light == -1;
    int valid = sm->view >= 0 && sm->view < m->views.count && sm->light >= 0 &&
                sm->light < m->lights.count;
    if (!none && !valid)
        return failf(err, code, name,
                     "subspace %d: representative (view %d, light %d) (expected both -1, or "
                     "indices below %d views and %d lights)", s, sm->view, sm->light,
                     m->views.count, m->lights.count);
    if (sm->width < 1 || sm->width > BTF_MODEL_MAX_IMAGE_SIDE || sm->height < 1 ||
        sm->height > BTF_MODEL_MAX_IMAGE_SIDE)
        return failf(err, code, name, "subspace %d: size %d x %d (expected 1..%d on each side)", s,
                     sm->width, sm->height, BTF_MODEL_MAX_IMAGE_SIDE);
    for (int c = 0; c < 3; c++)
        if (!(fabsf(sm->mean[c]) <= BTF_MODEL_MAX_VALUE))
            return failf(err, code, name, "subspace %d: mean[%d] is %g (expected a number of "
                         "magnitude at most %g, what synthesis keeps within float)", s, c,
                         sm->mean[c], BTF_MODEL_MAX_VALUE);
    btf_status rc = check_basis(sm->basis, s, name, code, err);
    if (rc)
        return rc;
    if (sm->levels < 1 || sm->levels > BTF_MAX_LEVELS)
        return failf(err, code, name, "subspace %d: %d pyramid levels (expected 1..%d)", s,
                     sm->levels, BTF_MAX_LEVELS);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < sm->levels; l++) {
            char where[64];
            snprintf(where, sizeof where, "subspace %d, band %d, level %d", s, b, l);
            if ((rc = check_band(&sm->bands[b][l], where, name, code, err)))
                return rc;
        }
    return check_marginal(&sm->marginal, s, name, code, err);
}

/* Every band's stability, by the test fitting stabilises to
 * (car/stability.c, docs/model.md "Stability"): an unstable recursion
 * makes synthesis grow exponentially along or down the rows, whatever the
 * size. Most bands pass its sufficient test at once; the rest take up to a
 * few milliseconds, so the distinct bands are checked on every CPU, each
 * once (a crafted file of a few KB can repeat one band thousands of
 * times); the first unstable band in file order is the one named, with the
 * recursion that grows. */
typedef struct stability_jobs {
    const btf_model *m;
    const int *unique;   /* the job of each distinct band */
    signed char *stable; /* per job: 1 stable, 0 not */
} stability_jobs;

static void band_of_job(int job, int *s, int *b, int *l)
{
    *s = job / (3 * BTF_MAX_LEVELS);
    *b = job / BTF_MAX_LEVELS % 3;
    *l = job % BTF_MAX_LEVELS;
}

static const btf_car_band *band_of(const btf_model *m, int job)
{
    int s, b, l;
    band_of_job(job, &s, &b, &l);
    return l < m->subspaces[s].levels ? &m->subspaces[s].bands[b][l] : NULL;
}

static btf_status stability_job(void *user, int k, int worker, btf_error *err)
{
    (void)worker, (void)err;
    stability_jobs *sj = user;
    sj->stable[sj->unique[k]] = (signed char)btf__car_is_stable(band_of(sj->m, sj->unique[k]));
    return BTF_OK;
}

/* A band as the test sees it: its neighbour count, offsets and gammas as
 * bytes (unused entries zero), with its job. */
typedef struct band_key {
    unsigned char bytes[sizeof(int) + sizeof(((btf_car_band *)0)->offsets) +
                        sizeof(((btf_car_band *)0)->gamma)];
    int job;
} band_key;

static void key_of(const btf_car_band *b, int job, band_key *k)
{
    memset(k, 0, sizeof *k);
    int n = b->n;
    memcpy(k->bytes, &n, sizeof n);
    memcpy(k->bytes + sizeof n, b->offsets, (size_t)n * sizeof *b->offsets);
    memcpy(k->bytes + sizeof n + sizeof b->offsets, b->gamma, (size_t)n * sizeof *b->gamma);
    k->job = job;
}

static int key_order(const void *a, const void *b)
{
    const band_key *x = a, *y = b;
    int c = memcmp(x->bytes, y->bytes, sizeof x->bytes);
    return c ? c : (x->job > y->job) - (x->job < y->job);
}

/* same[job] gets the first job of an identical band (itself if none), and
 * unique the first job of every distinct band; returns their count. */
static int distinct_bands(const btf_model *m, int jobs, band_key *keys, int *same, int *unique)
{
    int n = 0, count = 0;
    for (int j = 0; j < jobs; j++)
        if (band_of(m, j))
            key_of(band_of(m, j), j, &keys[n++]);
    qsort(keys, (size_t)n, sizeof *keys, key_order);
    for (int i = 0; i < n; i++) {
        int first = i > 0 && !memcmp(keys[i].bytes, keys[i - 1].bytes, sizeof keys[i].bytes);
        same[keys[i].job] = first ? same[keys[i - 1].job] : keys[i].job;
        if (!first)
            unique[count++] = keys[i].job;
    }
    return count;
}

static btf_status check_stability(const btf_model *m, const char *name, btf_status code,
                                  btf_error *err)
{
    int jobs = m->n_subspaces * 3 * BTF_MAX_LEVELS;
    band_key *keys = malloc((size_t)jobs * sizeof *keys);
    int *same = malloc((size_t)jobs * sizeof *same);
    int *unique = malloc((size_t)jobs * sizeof *unique);
    stability_jobs sj = {m, unique, calloc((size_t)jobs, 1)};
    btf_status rc = BTF_OK;
    if (!keys || !same || !unique || !sj.stable)
        rc = btf__fail(err, BTF_E_NOMEM, "%s: out of memory checking the CAR stability", name);
    if (rc == BTF_OK)
        rc = btf__pool_run(distinct_bands(m, jobs, keys, same, unique), 0, stability_job, &sj,
                           NULL, err);
    for (int j = 0; rc == BTF_OK && j < jobs; j++) {
        if (!band_of(m, j) || sj.stable[same[j]])
            continue;
        int s, b, l;
        band_of_job(j, &s, &b, &l);
        char why[200];
        btf__car_stability_why(band_of(m, j), why, sizeof why);
        rc = failf(err, code, name,
                   "subspace %d, band %d, level %d: the CAR coefficients are unstable: %s "
                   "(expected every root of the recursion below 1 - %g in modulus, as fitting "
                   "makes)", s, b, l, why, BTF_CAR_STABILITY_MARGIN);
    }
    BTF_FREE_ALL(keys, same, unique, sj.stable);
    return rc;
}

/* The pair gains: one colour per measured pair, finite and positive. */
static btf_status check_gains(const btf_model *m, const char *name, btf_status code,
                              btf_error *err)
{
    if (!m->gain)
        return BTF_OK;
    if (m->views.count < 1 || m->lights.count < 1)
        return failf(err, code, name, "pair gains without directions (expected none)");
    size_t n = (size_t)m->views.count * m->lights.count * 3;
    for (size_t i = 0; i < n; i++)
        if (!(m->gain[i] > 0.0f && m->gain[i] < 65536.0f))
            return failf(err, code, name, "pair gain (view %zu, light %zu) is %g (expected 0 < "
                         "g < 65536)", i / 3 / (size_t)m->lights.count,
                         i / 3 % (size_t)m->lights.count, m->gain[i]);
    return BTF_OK;
}

static btf_status check_range(const btf_model *m, const char *name, btf_status code, btf_error *err)
{
    if (m->albedo && !m->range)
        return failf(err, code, name, "structure layer without a range map");
    if ((m->shadows || m->chroma) && !m->albedo)
        return failf(err, code, name, "%s without a structure layer",
                     m->chroma ? "a colour layer" : "shadows");
    if (m->range_width == 0 && m->range_height == 0 && !m->range)
        return BTF_OK;
    if (m->range_width < 1 || m->range_width > BTF_MODEL_MAX_RANGE_SIDE || m->range_height < 1 ||
        m->range_height > BTF_MODEL_MAX_RANGE_SIDE ||
        (long)m->range_width * m->range_height > BTF_MODEL_MAX_RANGE_SAMPLES)
        return failf(err, code, name,
                     "range map: size %d x %d (expected 1..%d on each side, at most %ld samples)",
                     m->range_width, m->range_height, BTF_MODEL_MAX_RANGE_SIDE, BTF_MODEL_MAX_RANGE_SAMPLES);
    if (!m->range)
        return failf(err, code, name, "range map: %d x %d but no heights (expected an array)",
                     m->range_width, m->range_height);
    if (!(isfinite(m->range_texel) && m->range_texel > 0.0f))
        return failf(err, code, name, "range map: texel %g (expected a finite number > 0)",
                     m->range_texel);
    size_t n = (size_t)m->range_width * m->range_height;
    if (m->albedo && m->range_texel != 1.0f)
        return failf(err, code, name, "structure layer on a range map of texel %g (expected "
                     "texel 1: the analysed resolution)", m->range_texel);
    if (m->albedo && !(m->ambient >= 0.0f && m->ambient <= BTF_STRUCTURE_AMBIENT_MAX))
        return failf(err, code, name, "structure layer: ambient %g (expected 0..%g)",
                     m->ambient, BTF_STRUCTURE_AMBIENT_MAX);
    for (size_t i = 0; m->albedo && i < n; i++)
        if (!(m->albedo[i] > 0.0f && m->albedo[i] < 65536.0f))
            return failf(err, code, name, "structure layer: albedo %zu is %g (expected 0 < a "
                         "< 65536)", i, m->albedo[i]);
    for (size_t i = 0; m->chroma && i < 3 * n; i++)
        if (!(m->chroma[i] > 0.0f && m->chroma[i] < 65536.0f))
            return failf(err, code, name, "colour layer: factor %zu is %g (expected 0 < c "
                         "< 65536)", i, m->chroma[i]);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(m->range[i]))
            return failf(err, code, name, "range map: height %zu is %g (expected a finite number)",
                         i, m->range[i]);
    return BTF_OK;
}

/* The periodic cells: with the structure layer, one per subspace, their
 * geometry in bounds, their factors positive and finite. */
static btf_status check_cells(const btf_model *m, const char *name, btf_status code,
                              btf_error *err)
{
    const btf_cells *c = btf__model_cells(m);
    if (!c)
        return BTF_OK;
    if (!m->albedo || !btf__structure_quilted(m))
        return failf(err, code, name, "periodic cells without a structure layer at texel 1");
    if (c->w < 1 || c->h < 1 || (long)c->w * c->h > BTF_CELLS_MAX_TEXELS || c->shift < 0 ||
        c->shift >= c->w || c->n_subspaces != m->n_subspaces)
        return failf(err, code, name, "periodic cells of %d x %d texels, shift %d, for %d "
                     "subspaces (expected 1..%d texels, a shift below the width, %d subspaces)",
                     c->w, c->h, c->shift, c->n_subspaces, BTF_CELLS_MAX_TEXELS,
                     m->n_subspaces);
    size_t n = (size_t)c->n_subspaces * c->w * c->h * 3;
    for (size_t i = 0; i < n; i++)
        if (!(c->value[i] > 0.0f) || !isfinite(c->value[i]))
            return failf(err, code, name, "periodic cell of subspace %zu: factor %g (expected "
                         "positive and finite)", i / ((size_t)c->w * c->h * 3),
                         (double)c->value[i]);
    return BTF_OK;
}

/* Every rule of docs/model-format.md that a model in memory must meet. code
 * is BTF_E_DATA when writing (the caller's model is wrong) and BTF_E_FORMAT
 * when reading (the file is). */
btf_status btf__model_validate(const btf_model *m, const char *name, btf_status code,
                               btf_error *err)
{
    btf_status rc;
    if ((rc = check_dirset(&m->views, "views", name, code, err)) ||
        (rc = check_dirset(&m->lights, "lights", name, code, err)))
        return rc;
    if ((m->views.count == 0) != (m->lights.count == 0))
        return failf(err, code, name, "%d views and %d lights (expected both or neither)",
                     m->views.count, m->lights.count);
    if (m->n_subspaces < 1 || m->n_subspaces > BTF_MODEL_MAX_SUBSPACES || !m->subspaces)
        return failf(err, code, name, "%d subspaces (expected 1..%d)", m->n_subspaces,
                     BTF_MODEL_MAX_SUBSPACES);
    if (m->views.count > 0) {
        if (!m->index)
            return failf(err, code, name, "no index table (expected %d x %d entries)",
                         m->views.count, m->lights.count);
        size_t n = (size_t)m->views.count * m->lights.count, measured = 0;
        for (size_t i = 0; i < n; i++) {
            if (m->index[i] == BTF_PAIR_NONE)
                continue; /* a pair a sparse set did not measure */
            measured++;
            if (m->index[i] >= m->n_subspaces)
                return failf(err, code, name,
                             "index table: (view %zu, light %zu) -> subspace %u (expected < %d, "
                             "or %d: not measured)",
                             i / (size_t)m->lights.count, i % (size_t)m->lights.count,
                             m->index[i], m->n_subspaces, BTF_PAIR_NONE);
        }
        if (measured == 0)
            return failf(err, code, name, "index table: no measured pair (every entry is %d)",
                         BTF_PAIR_NONE);
    } else if (m->index) {
        return failf(err, code, name, "an index table without directions (expected none)");
    }
    for (int s = 0; s < m->n_subspaces; s++)
        if ((rc = check_subspace(m, s, name, code, err)))
            return rc;
    if ((rc = check_range(m, name, code, err)) || (rc = check_gains(m, name, code, err)) ||
        (rc = check_cells(m, name, code, err)))
        return rc;
    return check_stability(m, name, code, err);
}
