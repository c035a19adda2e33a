/*
 * car.h — the modelling stage's internals (src/car/, paper section II.C):
 * causal offsets, spectral decorrelation, the Gaussian-Laplacian pyramid
 * and synthesis margins of CAR bands. Private to the library.
 */
#ifndef BTF_CAR_H
#define BTF_CAR_H

#include "btfcar.h"

/* The CAR fit of one sub-band (car/car_fit.c) and its parts; the public
 * entry is btf_texture_fit (btfcar/analyse.h). */
#define BTF_CAR_MAX_CANDIDATES 16
typedef struct btf_car_fit_info {
    int candidates;                       /* evaluated */
    int size[BTF_CAR_MAX_CANDIDATES];     /* their neighbour counts */
    double log_evidence[BTF_CAR_MAX_CANDIDATES];
    int chosen;                           /* index into the above; -1: none fitted */
    double shrink;                        /* 1: as estimated; < 1: gamma scaled for stability */
    long pixels;                          /* equations used (t) */
} btf_car_fit_info;

/* Fits the CAR model to one sub-band (w x h doubles): Bayesian estimates
 * gamma = V_xx^-1 V_xy, sigma^2 from lambda, with the neighbourhood chosen by
 * its posterior probability among a nested family of candidates (or fixed).
 * Constant, tiny or ill-conditioned bands degrade to smaller models; an
 * unstable estimate is shrunk until stable (a warning). Output always finite. */
btf_status btf__car_fit(const double *band, int w, int h, const btf_car_fit_opts *opts,
                        btf_car_band *out, btf_car_fit_info *info, btf_error *err);
/* 1 when the recursion 1/A(z1, z2) of the band's model is stable. */
int btf__car_is_stable(const btf_car_band *b);
/* sigma^2 times the mean of 1/|A|^2 over the frequency torus: the variance of
 * the stationary field (without its mean). */
double btf__car_stationary_variance(const btf_car_band *b);

/* Models one subspace image (linear RGB): decorrelation, pyramid, one CAR
 * model per band and level. view and light are left -1. */
btf_status btf__fit_subspace(const btf_image *img, const btf_fit_opts *opts,
                             btf_subspace_model *out, btf_error *err);
/* The candidate neighbourhood family of the Bayesian choice (docs/model.md):
 * its BTF_CAR_MAX_NEIGHBOURS causal offsets in order, nearest first; a
 * "fixed order n" neighbourhood is its first n. Returns the count. */
int btf__car_candidate_offsets(btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS]);
/* The automatic number of pyramid levels for a band (docs/model.md). */
int btf__auto_levels(const double *band, int w, int h);

/* 1 when the offset is causal: row < 0, or row 0 and col < 0
 * (car/neighbourhood.c). */
int btf__offset_is_causal(btf_offset o);

/* Spectral decorrelation: car/decorrelate.c. Mean colour, orthonormal 3x3
 * basis (rows by decreasing variance) and the band variances. */
btf_status btf__pca3(const btf_image *img, float mean[3], float basis[9], double variance[3],
                     btf_error *err);
/* bands[b][i] = basis row b . (rgb_i - mean), in double. */
void btf__decorrelate(const btf_image *img, const float mean[3], const float basis[9],
                      double *bands[3]);

/* Gaussian-Laplacian pyramid: car/pyramid.c. */
typedef struct btf_pyramid {
    int levels;
    int width[BTF_MAX_LEVELS], height[BTF_MAX_LEVELS];
    double *level[BTF_MAX_LEVELS]; /* Laplacian levels; the last is the low-pass */
} btf_pyramid;
btf_status btf__pyr_down(const double *src, int w, int h, double **dst, btf_error *err);
btf_status btf__pyr_up(const double *src, int w2, int h2, int w, int h, double **dst,
                       btf_error *err);
btf_status btf__pyramid_build(const double *band, int w, int h, int levels, btf_pyramid *p,
                              btf_error *err);
btf_status btf__pyramid_collapse(const btf_pyramid *p, double **out, btf_error *err);
void btf__pyramid_free(btf_pyramid *p);

/* The CAR fit of a Laplacian level that independent synthesis of the
 * levels needs (car/car_fit.c, docs/model.md "Levels that add up"): band
 * is the Gaussian level G_l, sub the up-sampled coarser level up(G_{l+1});
 * the model's moments are G_l's less sub's, so that a field of it plus an
 * independent field with sub's statistics has G_l's autocovariance at the
 * neighbourhood's lags. Where that difference has no variance or is not
 * positive definite, the fit of the difference band G_l - sub instead. */
btf_status btf__car_fit_complement(const double *band, const double *sub, int w, int h,
                                   const btf_car_fit_opts *opts, btf_car_band *out,
                                   btf_car_fit_info *info, btf_error *err);

/* The CAR models of one band's pyramid of `levels` levels, out[0] the
 * finest (analyse/subspace_fit.c): the coarsest is fitted to the low-pass, every
 * finer one by btf__car_fit_complement. what names the band in warnings. */
btf_status btf__fit_band_levels(const double *band, int w, int h, int levels,
                                const btf_car_fit_opts *car, const char *what, btf_car_band *out,
                                btf_error *err);

/* The measured choice of the pyramid depth (analyse/levels.c, docs/model.md
 * "Choosing the levels"): for 1 .. btf__levels_cap(w, h) levels, the band's
 * models are fitted and synthesised, and the depth whose synthesis' octave
 * energies come closest to the band's wins, at most max_levels of them (0:
 * the paper's 3). distance[L - 1] (when not NULL, BTF_MAX_LEVELS entries,
 * -1 where not tried) gets each depth's distance. mask (NULL: none) is a
 * factor the render multiplies the band's image by: its relative octave
 * energies are added to the band's relative ones (band / level, level the
 * image's mean along the band) on both sides, so that the depth is chosen
 * for the product, where the mask hides what it outweighs. */
typedef struct btf_levels_mask {
    const float *factor; /* w x h, positive */
    double level;        /* the band's image's mean level (> 0) */
} btf_levels_mask;
btf_status btf__choose_levels(const double *band, int w, int h, const btf_car_fit_opts *car,
                              int max_levels, const btf_levels_mask *mask, int *levels,
                              double *distance, btf_error *err);
/* The most levels the choice considers for a w x h band. */
int btf__levels_cap(int w, int h);

/* Synthesis margins (car/margin.c): the rows above its window a band's
 * CAR field starts, and the columns it runs on either side, so that the
 * zero boundary's transient has died out (below BTF_SYNTH_MARGIN_EPS of the
 * stationary variance) before the window. Depends on the band alone; CPU
 * and GPU synthesis both use it. 0 for a band without neighbours. */
#define BTF_SYNTH_MARGIN_MIN 8
#define BTF_SYNTH_MARGIN_MAX 256
#define BTF_SYNTH_MARGIN_EPS 1e-4
int btf__car_margin(const btf_car_band *b);
/* The same with a work budget (grid cells times neighbours, decremented):
 * when it runs out, the safe answer BTF_SYNTH_MARGIN_MAX. Reading a model
 * file uses it so that a small crafted file cannot cost minutes. Both
 * return -1 when out of memory. */
int btf__car_margin_within(const btf_car_band *b, double *budget);
/* The share of the impulse response's energy beyond m rows or columns: a
 * lower bound of what a pixel that far from the zero boundary misses of the
 * stationary variance (the side boundaries pin the field to 0, which costs
 * nearly unstable bands more), or -1 when out of memory. */
double btf__car_margin_shortfall(const btf_car_band *b, int m);
/* A model keeps its bands' margins: model/model.h, btf__model_margin. */

/* Stability of a band's recursion (car/stability.c, docs/model.md
 * "Stability"): the exact test of the causal (non-symmetric half-plane)
 * recursion synthesis runs, with a margin: every root of the recursion
 * along a row, and of the row-to-row recursion at every column frequency,
 * of modulus below 1 - BTF_CAR_STABILITY_MARGIN. The margin keeps rounding
 * harmless: a root the check misplaces by rounding, or that float
 * synthesis' own rounding (about 1e-6 relative for 24 neighbours, in the
 * worst alignment) pushes outward, still grows by less than e^0.07 over
 * the largest synthesis (65536 pixels plus two 256-pixel margins). It
 * rejects no stable estimate farther than 1e-6 from the unit circle: a
 * 1-pixel checkerboard's fit (roots of modulus 0.99999) stays, and is
 * reported as a periodic pattern that synthesis misses (car_fit.c). 1 when
 * stable; 0 when not, with why (n bytes; NULL: none) a phrase that says
 * which recursion grows. */
#define BTF_CAR_STABILITY_MARGIN 1e-6
int btf__car_stability_why(const btf_car_band *b, char *why, size_t n);

/* The fit's settling rule on top of stability (car/settle.c): 1 when a
 * field of the band's recursion from zeros stops growing within a 160 x
 * 192 test field (or sum |gamma| < 1), 0 when it does not (roots close to
 * the unit circle, from about 0.98: correlation beyond the synthesis
 * margins), -1 when out of memory. */
int btf__car_fit_settles(const btf_car_band *b);

/* The variance synthesis gives a band in its first rows and columns: the
 * sample variance of the 64 x 64 window of a field started `margin` rows
 * above and columns beside it from zeros (as synth/field.c does), with the
 * band's noise (a fixed seed). Far below btf__car_stationary_variance when
 * the margin is too short for the band (a nearly periodic pattern, such as
 * a 1-pixel checkerboard, whose recursion barely decays). -1 when out of
 * memory. Costs (margin + 64) (2 margin + 64) n multiply-adds. */
double btf__car_synth_variance(const btf_car_band *b, int margin);

#endif
