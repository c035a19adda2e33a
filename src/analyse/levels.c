/*
 * levels.c — the depth of the Gaussian-Laplacian pyramid, measured
 * (`--levels auto`; paper section II.C uses at most 3 levels; docs/model.md,
 * "Choosing the levels").
 *
 * A deeper pyramid lets a small causal neighbourhood reach coarser scales
 * (a neighbour at level l is 2^l pixels away), but each level is one more
 * model fitted to fewer pixels, so whether it helps is a question for the
 * data. The answer is measured on the dominant band: for every depth L from
 * 1 to the cap, the band's models are fitted (btf__fit_band_levels), a field
 * of the band's size is synthesised from them (every level its own CAR field,
 * the pyramid collapsed, as synthesis does) for SEEDS seeds, and both the
 * band and the syntheses are cut into octaves by a deep Laplacian pyramid
 * (down to OCTAVE_MIN pixels). The distance of a depth is the root mean
 * square over the octaves of ln(E_synth / E_band), E the octave's variance:
 * an octave-binned log power spectrum distance, coarse structure up to the
 * band's own size included (the last octave is the low-pass remainder). A
 * deeper pyramid is chosen only when it beats every shallower one by
 * MARGIN and by REL_MARGIN of its distance: ties go to the smaller model
 * (a 14 % step bought nothing on the rendered material, 21 % did: docs/
 * model.md, "Choosing the levels").
 *
 * The cap: at most 3 levels (the paper's bound), and no more than keep the
 * coarsest level 16 pixels wide (a CAR model of 24 neighbours needs rows
 * and columns to fit on); the caller may lower it (2 beside a structure
 * layer, analyse/analyse.c).
 *
 * With a mask (the structure layer's factor the render multiplies the band's
 * image by), the octaves are those of the rendered product: the mask's
 * relative octave energies, in the band's units, are added to the band's
 * and the synthesis' on both sides (docs/model.md, "Choosing the levels").
 */
#include <stdio.h>
#include "core/core.h"
#include "car/car.h"
#include "synth/synth_testing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define AUTO_MAX_LEVELS 3
#define COARSEST_MIN 16
#define OCTAVE_MIN 4
#define SEEDS 2
#define MARGIN 0.02
#define REL_MARGIN 0.17
#define MAX_OCTAVES 24

int btf__levels_cap(int w, int h)
{
    int side = w < h ? w : h, cap = 1;
    while (cap < AUTO_MAX_LEVELS && (side >> cap) >= COARSEST_MIN)
        cap++;
    return cap;
}

/* The variance of each octave of a w x h band (a Laplacian pyramid down to
 * OCTAVE_MIN pixels a side, the low-pass remainder last), into e; returns
 * the number of octaves, or -1 when out of memory. */
static int octave_energies(const double *band, int w, int h, double *e, btf_error *err)
{
    int side = w < h ? w : h, k = 1;
    while (k < MAX_OCTAVES && k < BTF_MAX_LEVELS && (side >> k) >= OCTAVE_MIN)
        k++;
    btf_pyramid p;
    if (btf__pyramid_build(band, w, h, k, &p, err))
        return -1;
    for (int l = 0; l < k; l++) {
        size_t n = (size_t)p.width[l] * p.height[l];
        double m = 0.0, v = 0.0;
        for (size_t i = 0; i < n; i++)
            m += p.level[l][i];
        m /= (double)n;
        for (size_t i = 0; i < n; i++)
            v += (p.level[l][i] - m) * (p.level[l][i] - m);
        e[l] = v / (double)n;
    }
    btf__pyramid_free(&p);
    return k;
}

typedef struct rows_into {
    double *data;
    int width;
} rows_into;

static int store_rows(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    rows_into *r = user;
    for (size_t i = 0; i < (size_t)nrows * r->width; i++)
        r->data[(size_t)y * r->width + i] = rows[i];
    return 0;
}

/* A synthesis of the band's pyramid models at w x h: each level's field at
 * its pyramid size, collapsed; *out malloc'd. */
static btf_status synthesise_band(const btf_car_band *models, int levels, int w, int h,
                                  uint64_t seed, double **out, btf_error *err)
{
    btf_pyramid p;
    memset(&p, 0, sizeof p);
    p.levels = levels;
    btf_status rc = BTF_OK;
    for (int l = 0; l < levels && rc == BTF_OK; l++) {
        p.width[l] = w, p.height[l] = h;
        if (!(p.level[l] = btf__alloc((size_t)w * h, sizeof(double), err))) {
            rc = BTF_E_NOMEM;
            break;
        }
        btf_synth_opts o = btf_synth_defaults();
        o.width = w, o.height = h, o.seed = seed;
        rows_into r = {p.level[l], w};
        rc = btf__car_synthesise_field(&models[l], -1, (uint32_t)(0x5eed0u + l), &o, store_rows, &r,
                                       err);
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
    if (rc == BTF_OK)
        rc = btf__pyramid_collapse(&p, out, err);
    btf__pyramid_free(&p);
    return rc;
}

/* The octave distance of a depth's models from the band's energies, each
 * octave's energy raised by floor_e[octave] on both sides. */
static btf_status depth_distance(const btf_car_band *models, int levels, int w, int h,
                                 const double *e_band, int octaves, const double *floor_e,
                                 double *d, btf_error *err)
{
    double e_syn[MAX_OCTAVES] = {0};
    for (int s = 0; s < SEEDS; s++) {
        double *syn, e[MAX_OCTAVES];
        btf_status rc = synthesise_band(models, levels, w, h, 1 + (uint64_t)s, &syn, err);
        if (rc)
            return rc;
        int k = octave_energies(syn, w, h, e, err);
        free(syn);
        if (k < 0)
            return BTF_E_NOMEM;
        for (int i = 0; i < octaves; i++)
            e_syn[i] += e[i] / SEEDS;
    }
    double sum = 0.0;
    for (int i = 0; i < octaves; i++) {
        double r = log((e_syn[i] + floor_e[i]) / (e_band[i] + floor_e[i]));
        sum += r * r;
    }
    *d = sqrt(sum / octaves);
    return BTF_OK;
}

static btf_status choose(const double *band, int w, int h, const btf_car_fit_opts *car, int cap,
                         const double *mask_e, int *levels, double *distance, btf_error *err);

/* The mask's octave energies relative to its mean squared, times the
 * band's level squared: what the mask adds to each octave of the product,
 * in the band's units (log-domain energies add: log(T S) = log T + log S,
 * and a fluctuation small against its level has var(log T) ~ var(T) / T^2).
 * Returns the octave count, 0 without a usable mask, -1 out of memory. */
static int mask_energies(const btf_levels_mask *mask, int w, int h, double big, double *e,
                         btf_error *err)
{
    if (!mask || !mask->factor || !(mask->level > 0.0) || !isfinite(mask->level))
        return 0;
    size_t n = (size_t)w * h;
    double *f = btf__alloc(n, sizeof(double), err), mean = 0.0;
    if (!f)
        return -1;
    for (size_t i = 0; i < n; i++)
        mean += (f[i] = isfinite(mask->factor[i]) ? mask->factor[i] : 0.0);
    mean /= (double)n;
    int k = 0;
    if (mean > 0.0) {
        for (size_t i = 0; i < n; i++)
            f[i] /= mean;
        k = octave_energies(f, w, h, e, err);
        double s = (mask->level / big) * (mask->level / big);
        for (int i = 0; i < k; i++)
            e[i] *= s;
    }
    free(f);
    return k;
}

btf_status btf__choose_levels(const double *band, int w, int h, const btf_car_fit_opts *car,
                              int max_levels, const btf_levels_mask *mask, int *levels,
                              double *distance, btf_error *err)
{
    *levels = 1;
    for (int l = 0; distance && l < BTF_MAX_LEVELS; l++)
        distance[l] = -1.0;
    int cap = btf__levels_cap(w, h);
    if (max_levels > 0 && cap > max_levels)
        cap = max_levels;
    if (cap == 1)
        return BTF_OK;
    /* The distances are ratios: measured on the band scaled to its largest
     * magnitude, so that no trial synthesis overflows floats where the
     * band's own values would. */
    size_t n = (size_t)w * h;
    double big = 0.0;
    for (size_t i = 0; i < n; i++)
        if (fabs(band[i]) > big)
            big = fabs(band[i]);
    if (!(big > 0.0) || !isfinite(big))
        return BTF_OK; /* zero (or not finite: the fit refuses it) */
    double mask_e[MAX_OCTAVES] = {0};
    if (mask_energies(mask, w, h, big, mask_e, err) < 0)
        return BTF_E_NOMEM;
    double *z = btf__alloc(n, sizeof(double), err);
    if (!z)
        return BTF_E_NOMEM;
    for (size_t i = 0; i < n; i++)
        z[i] = band[i] / big;
    btf_status rc = choose(z, w, h, car, cap, mask_e, levels, distance, err);
    free(z);
    return rc;
}

static btf_status choose(const double *band, int w, int h, const btf_car_fit_opts *car, int cap,
                         const double *mask_e, int *levels, double *distance, btf_error *err)
{
    double e_band[MAX_OCTAVES], total = 0.0;
    int octaves = octave_energies(band, w, h, e_band, err);
    if (octaves < 0)
        return BTF_E_NOMEM;
    for (int i = 0; i < octaves; i++)
        total += e_band[i];
    if (!(total > 1e-24) || !isfinite(total))
        return BTF_OK; /* a constant band: nothing to place at any scale */
    /* Octaves a million times weaker than the band count as empty alike. */
    double floor_e[MAX_OCTAVES], best = INFINITY;
    for (int i = 0; i < octaves; i++) /* the mask's octaves outweigh the band's alike */
        floor_e[i] = 1e-6 * total + mask_e[i];
    btf_car_fit_opts quiet = car ? *car : btf_car_fit_defaults();
    quiet.warn = NULL; /* the chosen depth is fitted again, with warnings */
    for (int L = 1; L <= cap; L++) {
        btf_car_band models[BTF_MAX_LEVELS];
        double d;
        btf_status rc = btf__fit_band_levels(band, w, h, L, &quiet, "levels", models, err);
        if (rc == BTF_OK)
            rc = depth_distance(models, L, w, h, e_band, octaves, floor_e, &d, err);
        if (rc == BTF_E_NOMEM)
            return rc;
        if (rc) { /* a depth that cannot be fitted or synthesised is not chosen */
            if (err)
                err->code = 0, err->msg[0] = '\0';
            continue;
        }
        if (distance)
            distance[L - 1] = d;
        if (d < best - MARGIN && d < best * (1.0 - REL_MARGIN)) {
            best = d;
            *levels = L;
        }
    }
    return BTF_OK;
}

int btf__auto_levels(const double *band, int w, int h)
{
    int levels = 1;
    btf_error e = {0};
    if (!band || w < 1 || h < 1)
        return 1;
    btf_car_fit_opts car = btf_car_fit_defaults();
    if (btf__choose_levels(band, w, h, &car, 0, NULL, &levels, NULL, &e) != BTF_OK)
        return 1;
    return levels;
}
