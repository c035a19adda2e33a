/*
 * synth.h — the CPU synthesis internals (src/synth/, Haindl & Filip 2007,
 * section II.C: CAR fields by their causal recursion, the pyramid collapse,
 * the inverse decorrelation), one section per file, callers above callees:
 *
 *   synthesise.c   the public calls: options, checks, the row loop
 *   tileable.c     the DFT torus reference of tileable synthesis (tests only)
 *   torus.c        one CAR field on a torus, solved by a 2D DFT
 *   collapse.c     the pyramid of one band, streamed row by row
 *   upsample.c     pyrUp of rows (horizontal pairs, vertical sums)
 *   field.c        one CAR field of a level: its ring of rows, and which
 *                  generator fills it
 *   wave.c         generator: the wavefront, eight rows per AVX2 step
 *   rows.c         generator: row by row (two rows at a time where it can)
 *   chains.c       the sequential same-row part of field rows
 *   neighbourhood.c  the order of a band's terms; the checks of a band
 *   noise_row.c    rows of Gaussian noise (AVX2 or portable)
 *   colour.c       inverse decorrelation of rows; the finite test
 *
 * No file calls into one above it. The GPU host code (gpu/synth_gpu.c)
 * uses neighbourhood.c and colour.c. Private to the library.
 */
#ifndef BTF_SYNTH_H
#define BTF_SYNTH_H

#include "btfcar.h"
#include "core/core.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* Row loops compiled twice, for plain x86-64 and for AVX2 (twice the
 * lanes), the choice made once at load time; AVX2 brings no FMA here and
 * the build forbids contraction, so both give the same bits. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define SYNTH_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#define SYNTH_HAVE_AVX2 1 /* hand-written AVX2 loops (under #pragma GCC target) */
#else
#define SYNTH_AVX2_CLONES
#endif

/* ------------------------------------------------------------ synthesise.c */

/* *o = opts (NULL: none; btf__opts_take) with every zero field replaced by
 * its default (btf_synth_defaults); shared with the GPU host code.
 * BTF_E_ARG: an options struct of another header's size. */
btf_status btf__synth_resolve(const btf_synth_opts *opts, btf_synth_opts *o, btf_error *err);

/* The CPU switches of btf_synth_opts, resolved: which generators run. */
typedef struct synth_paths {
    int vector_noise; /* the AVX2 noise loop (when the CPU has AVX2) */
    int wave;         /* the wavefront (where the band and the CPU qualify) */
    int tileable;     /* periodic noise: level l's field repeats its (W >> l) x (H >> l)
                       * window's noise (btf_synth_opts.tileable) */
} synth_paths;

/* A tileable size: both sides multiples of 2^(levels - 1), so that every
 * level has a whole period (BTF_E_ARG naming the size otherwise). */
btf_status btf__synth_check_tileable(int width, int height, int levels, btf_error *err);

/* ------------------------------------------------------------ tileable.c */

/* The test reference of tileable synthesis (synth_testing.h,
 * btf__synthesise_torus_dft): each level a CAR field solved exactly on its
 * torus (torus.c), the pyramid collapsed with wrap-around, rows handed to
 * fn in order. Whole planes in memory: sizes up to BTF_SYNTH_TILE_MAX_PIXELS
 * with no prime factor above BTF_SYNTH_TILE_MAX_PRIME (BTF_E_ARG). */
btf_status btf__synthesise_tileable(const btf_model *m, int subspace, const btf_synth_opts *o,
                                    int w, int h, btf_rows_fn fn, void *user, btf_error *err);

/* --------------------------------------------------------------- torus.c */

/* The zero-mean CAR field of band b on the w x h torus (periodic
 * boundaries) into out (w h floats, row-major), driven by the noise of
 * `stream` at rows and columns 0 .. h - 1, 0 .. w - 1: exactly
 * Y = sum_s gamma_s Y(wrapped neighbour) + sigma e at every pixel, up to
 * rounding. BTF_E_NUMERIC (the message starting with `what`) when the
 * recursion is singular at a grid frequency. */
btf_status synth_torus_field(const btf_car_band *b, uint32_t stream, int w, int h,
                             uint64_t seed, int vector_noise, const char *what, float *out,
                             btf_error *err);

/* ------------------------------------------------------------ noise_row.c */

/* The Gaussians of blocks b0 .. b0 + n - 1 of a row (btf_noise4 of each,
 * 4 n floats into out), bit for bit the same on every path; vector_path 0
 * forces the portable loop, 1 takes AVX2 where the CPU has it. */
void btf__noise_blocks(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                       uint32_t b0, uint32_t n, int vector_path, float *out);
/* Whether this build and CPU have the AVX2 noise loop. */
int btf__noise_avx2_available(void);

/* -------------------------------------------------------- neighbourhood.c */

/* The indices of a band's same-row offsets in the order btf_shared.h adds
 * them (farthest column first); returns their count. The GPU host code
 * orders the shader's offsets so. */
int btf__car_same_row_order(const btf_car_band *b, int *idx);
/* k when the band's same-row offsets are exactly columns -k .. -1 (k <= 3,
 * the candidate family's shapes), with their gammas in gamma3[3 - k .. 2]
 * (gamma3[2] for column -1, the rest 0); -1 for any other set. */
int btf__car_same_row_shape(const btf_car_band *b, float gamma3[3]);
/* A band synthesis can run with this margin: 0..BTF_CAR_MAX_NEIGHBOURS
 * causal offsets within 64 pixels, a margin within 0..BTF_SYNTH_MARGIN_MAX
 * (CPU and GPU paths alike). */
btf_status btf__synth_check_band(const btf_car_band *b, int margin, btf_error *err);
/* A synthesis size: 1..BTF_SYNTH_MAX_SIDE on each side. */
btf_status btf__synth_check_size(int width, int height, btf_error *err);

/* Hands row y (width x 3 floats) to a btf_rows_fn consumer: its non-zero
 * answer as a status (positive: BTF_E_IO), with a message when it left none
 * (synthesise.c; every synthesis path emits its rows so). */
btf_status btf__synth_emit_row(btf_rows_fn fn, void *user, int y, const float *row,
                               btf_error *err);
/* Colour matching can run on subspace `subspace` of m: BTF_E_ARG, naming it,
 * when it is out of range or holds no Lab histogram (a file of format 1.2
 * or older) (colour_match.c; synthesis and the GPU check before work). */
btf_status btf__colour_match_check(const btf_model *m, int subspace, btf_error *err);
/* Whether colour matching runs on subspace `subspace` under the option's
 * value opt (btf_synth_opts.match_colours): -1 off; 1 on, or
 * btf__colour_match_check's error; 0 (the default) on where the subspace
 * holds the exemplar's Lab quantiles (format 1.3 on), off for older files. */
btf_status btf__colour_match_wanted(const btf_model *m, int subspace, int opt, int *on,
                                  btf_error *err);

/* ------------------------------------------------------------ colour_lab.c */

/* CIE L*a*b* as OpenCV's float conversion (docs/synthesis.md, "Colour
 * matching"), in float, a row at a time: n interleaved RGB pixels times
 * scale (negative light as none) to planar L*, a*, b*, and back (divided by
 * scale, each channel clamped into [lo[k], hi[k]]). */
#define BTF_LAB_SAMPLE ((size_t)256 * 256) /* an exemplar's quantiles: pixels read at most */
#define BTF_LAB_MATCH_SAMPLE ((size_t)128 * 128) /* an image colour matching maps */
float btf__lab_scale(const btf_marginal *mg); /* 1 / the largest rgb_hi, or 1 */
void btf__lab_row(const float *rgb, int n, float scale, float *l, float *a, float *b);
void btf__rgb_row_from_lab(const float *l, const float *a, const float *b, int n, float scale,
                           const float lo[3], const float hi[3], float *rgb);
/* An RGB image's L*, a*, b* quantiles at j / (BTF_MARGIN_KNOTS - 1), from
 * every pixel up to `most`, else a regular grid of pixels (the standard
 * error of a quantile of 16,384 samples is far below the bench's
 * self-distances); clamped to L* in [0, 100], a*, b* in [-128, 128],
 * nondecreasing. On the calling thread. */
btf_status btf__lab_quantiles(const btf_image *img, float scale, size_t most,
                              float q[3][BTF_MARGIN_KNOTS], btf_error *err);
/* The same in steps, for an image that comes row by row (the streaming
 * synthesis' first pass): begin (the grid for width x height, at most
 * `most` samples), row y's samples (nothing unless y is a grid row;
 * scratch: cols x 3 floats), then the quantiles; free in any case. */
typedef struct btf_lab_sample {
    int sx, sy, cols, rows; /* the grid's steps, its size in samples */
    size_t n;               /* cols * rows */
    float scale;
    float *v;               /* L* of every sample, then a*, b*, then the sort's scratch */
} btf_lab_sample;
btf_status btf__lab_sample_begin(btf_lab_sample *s, int width, int height, size_t most,
                                 float scale, btf_error *err);
void btf__lab_sample_row(btf_lab_sample *s, int y, const float *row, float *scratch);
/* The grid alone (steps and size; no values held), for a sample taken
 * elsewhere (the GPU: gpu/match_gpu.c). */
void btf__lab_sample_grid(btf_lab_sample *s, int width, int height, size_t most);
btf_status btf__lab_sample_quantiles(btf_lab_sample *s, float q[3][BTF_MARGIN_KNOTS],
                                     btf_error *err);
void btf__lab_sample_free(btf_lab_sample *s);
/* btf__lab_sample_quantiles in two halves, for a sample sorted elsewhere
 * (the GPU: gpu/match_gpu.c): the ranks of the order statistics the
 * quantiles interpolate (2 per knot, returns their count) and the weights,
 * then channel c's quantiles from the statistics at those ranks. */
int btf__lab_quantile_ranks(size_t n, size_t ranks[2 * BTF_MARGIN_KNOTS],
                            double frac[BTF_MARGIN_KNOTS]);
void btf__lab_quantiles_at(int c, const float at[2 * BTF_MARGIN_KNOTS],
                           const double frac[BTF_MARGIN_KNOTS], float q[BTF_MARGIN_KNOTS]);
/* The conversion's constants as this file rounds them, for a shader that
 * must give the same bits (gpu/match_layout.h): the two matrices
 * row-major, T0, SLOPE, F0, F_T0, 1/3, LIGHT_MAX, 1/116, 1/500, 1/200,
 * 1/SLOPE, and the cube root's magic number. */
void btf__lab_constants(float to_xyz[9], float to_rgb[9], float k[10], int32_t *magic);
/* A map of one Lab channel, resampled on BTF_LAB_MAP_SEGS segments of
 * equal width (colour_match.c makes it): t = (v - origin) inv_h clamped to
 * [0, SEGS], q[i] + (t - i) dq[i] at its segment i. */
#define BTF_LAB_MAP_SEGS 256
typedef struct btf_lab_map {
    float origin, inv_h;
    float q[BTF_LAB_MAP_SEGS + 1], dq[BTF_LAB_MAP_SEGS];
} btf_lab_map;
/* n interleaved RGB pixels in place: to Lab, each channel through its map,
 * back, clamped into [lo[k], hi[k]] (AVX2 where the CPU has it, the same
 * bits as the scalar code). */
void btf__lab_match_row(const btf_lab_map map[3], float scale, const float lo[3],
                        const float hi[3], float *rgb, int n);
/* The maps from an image's own quantiles src onto the exemplar's, mg's
 * (colour_match.c; a marginal that holds them: btf__colour_match_check). */
void btf__colour_match_maps(const btf_marginal *mg, const float src[3][BTF_MARGIN_KNOTS],
                            btf_lab_map map[3]);
/* Colour matching as a task (colour_match.c): its jobs, in order, sample
 * the image's Lab, make the maps from the sample's quantiles, then map the
 * image's rows, a few thousand pixels a job. btf__match_task_begin checks the
 * subspace (not the pixels: a synthesis' are finite) and sets bg up, so
 * that a relay's helper (core/pool.c) can run the task in its idle time;
 * btf__match_task_finish runs what is left, the rows over the thread pool,
 * and reports bg's failure if it had one. Same bytes whoever runs a job. */
typedef struct btf_match_task {
    btf_image *img;
    const btf_marginal *mg;
    float scale;
    btf_lab_sample sample;
    float *scratch;             /* the sample's, [worker 0..1][cols * 3] */
    int sample_rows_per_job, rows_per_job;
    btf_lab_map map[3];
    btf_background bg;
} btf_match_task;
btf_status btf__match_task_begin(btf_match_task **out, const btf_model *m, int subspace,
                                 btf_image *img, btf_error *err);
btf_status btf__match_task_finish(btf_match_task *t, btf_error *err);
void btf__match_task_free(btf_match_task *t);
/* btf__colour_match of an image the synthesis made (RGB, finite: not
 * checked again), on the calling thread and the pool. */
btf_status btf__match_synthesised(const btf_model *m, int subspace, btf_image *img,
                                  btf_error *err);
/* Streaming colour matching keeps the whole image when it takes at most
 * this many bytes, else synthesises twice (synthesise.c). */
#define BTF_MATCH_WHOLE_BYTES ((size_t)256 << 20)

/* -------------------------------------------------------------- marginal.c */

/* A subspace's marginal transfer as synthesis applies it (docs/synthesis.md,
 * "Marginals"; the formulas in btf_shared.h): per band the grid's origin,
 * the inverse of its segments' width, where the end knots fall on it, the
 * exemplar's range, each segment's start value and rise (BTF_MARGIN_TABLE
 * entries); the subspace's mean colour, the RGB box and the mean's
 * distances to its sides; on 0: none (identity, no clamp). Made on the
 * host for the CPU and the GPU alike. portable 1 (tests): no AVX2. */
typedef struct btf_marginal_table {
    int on, portable;
    float origin[3], inv_h[3], tlo[3], thi[3], qmin[3], qmax[3];
    float q[3][16], dq[3][16]; /* BTF_MARGIN_TABLE of btf_shared.h */
    float mean[3], lo[3], hi[3], nlo[3], nhi[3];
} btf_marginal_table;
/* The standard normal quantiles N_j of the model's knots. */
extern const double btf__marginal_normal_knots[BTF_MARGIN_KNOTS];
void btf__marginal_table_make(const btf_subspace_model *sm, btf_marginal_table *t);
/* out[x] = the transfer of band `band` at v[x]; nonzero when a v is Inf or
 * NaN. */
int btf__marginal_row(const btf_marginal_table *t, int band, const float *v, int width,
                      float *out);
/* One colour c into the table's box, moved towards the mean
 * (btf_shared.h, "Gamut"). */
void btf__marginal_gamut(const btf_marginal_table *t, float c[3]);
/* The colour step of one row with the transfer on (t->on): each band
 * through it, the inverse decorrelation (btf_unmix), the gamut, RGB
 * interleaved into row. Nonzero when a band value is Inf or NaN (row then
 * holds no meaningful colour). */
int btf__marginal_unmix_row(const btf_subspace_model *sm, const btf_marginal_table *t,
                            const float *b0, const float *b1, const float *b2, int width,
                            float *row);

/* ---------------------------------------------------------------- colour.c */

/* 1 when v is Inf or NaN (all exponent bits set), else 0: a branch-free
 * test that row loops OR together and the compiler vectorises. */
static inline uint32_t btf_nonfinite_bits(float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    return (uint32_t)((u & 0x7F800000u) == 0x7F800000u);
}
/* 1 when any of n values is Inf or NaN. */
int btf__any_nonfinite(const float *v, size_t n);

/* Scratch floats per pixel that btf__unmix_row needs. */
#define BTF_UNMIX_SCRATCH 3
/* One row of a subspace image from its three bands: the marginal transfer
 * (t, when on), inverse decorrelation (btf_unmix per channel), the RGB
 * clamp (when on), interleaved RGB into row (scratch: BTF_UNMIX_SCRATCH *
 * width floats). Returns nonzero when a value is Inf or NaN. */
int btf__unmix_row(const btf_subspace_model *sm, const btf_marginal_table *t, const float *b0,
                   const float *b1, const float *b2, int width, float *scratch, float *row);
/* BTF_E_NUMERIC naming the subspace and row if any of n values is not
 * finite: no synthesis hands out Inf or NaN (a model fitted to values near
 * the float limit can overflow); both backends check their output with it. */
btf_status btf__check_finite_row(const float *v, size_t n, int subspace, int y, btf_error *err);

/* -------------------------------------------------------------- upsample.c */

/* Horizontal pyrUp of a coarse row c (its window starts at column cx0) to
 * the fine columns [fx0, fx0 + n). */
void btf__up_row(const float *c, int cx0, int fx0, int n, float *out);
/* One row of G_l = mean + field + vertical pyrUp of the coarser level's
 * horizontally up-sampled rows: none (b NULL: the coarsest level), b and c
 * (an odd row: a NULL), or a, b and c (an even row). */
void btf__level_sum_row(int w, float mean, const float *field, const float *a, const float *b,
                        const float *c, float *out);

/* ---------------------------------------------------------------- chains.c */

/* One sequential same-row chain: out[i] = acc[i] + the same-row terms of
 * columns -3, -2, -1 (gammas gamma3[0..2]); out[-3 .. -1] hold the columns
 * before. */
typedef struct synth_chain {
    const float *acc;
    float *out;
    const float *gamma3;
} synth_chain;
#define SYNTH_MAX_CHAINS 6
/* n_chains (1..SYNTH_MAX_CHAINS) chains of one shape (0..3: the same-row
 * terms are columns -shape .. -1), len pixels each, in one loop. */
void btf__chains(const synth_chain *c, int n_chains, int shape, int len);

/* ------------------------------------------------------------------ wave.c */

/* The wavefront generator of CAR fields: eight rows at once, bit for bit
 * the row-by-row recursion. btf__wave_supported says whether a band and
 * field width qualify on this machine (AVX2, small offsets, the family's
 * same-row shapes, wide enough). A wave stores its rows into a ring of
 * `depth` rows of fw + 2 pad floats (row r in slot r mod depth, as
 * synth_field_ring_row; depth >= BTF_WAVE_DEPTH, pad >= btf__wave_pad(),
 * else BTF_E_ARG): btf__wave_run returns once row `row` (>= row0, rows asked
 * in increasing order) is complete there. Rows row + 1 .. row + 7 are then
 * partly written, so only row `row` may be read before the next run. */
typedef struct btf_wave btf_wave;
#define BTF_WAVE_DEPTH 8
int btf__wave_supported(const btf_car_band *b, int fw);
int btf__wave_pad(void);
btf_wave *btf__wave_new(const btf_car_band *b, int fw, int fx0, int row0, uint32_t stream,
                        float *ring, int depth, int pad, btf_error *err);
void btf__wave_run(btf_wave *w, int row, uint32_t seed_lo, uint32_t seed_hi);
void btf__wave_free(btf_wave *w);
/* Whether this build and CPU have the wavefront at all (GCC, x86-64, AVX2). */
int btf__wave_available(void);

/* ----------------------------------------------------------------- field.c */

/* One CAR field: a level's window plus its margin on either side, rows
 * generated top to bottom into a ring that keeps the rows its recursion
 * reaches back to. */
typedef struct synth_field {
    const btf_car_band *band;
    uint32_t stream;       /* noise stream (subspace, band, level) */
    int fx0, fw;           /* field columns [fx0, fx0 + fw): the window and margins */
    int window_x0;         /* the window's first column */
    int end;               /* one past the last row anyone asks for */
    int pad;               /* zero columns on each side of a ring row */
    int depth;             /* ring rows: reach up + 2, one more than the recursion
                            * reads, as a row is read after the row pair
                            * generator has also written the next (with reach
                            * up 0, one row would not hold both); a wave's:
                            * BTF_WAVE_DEPTH */
    int next;              /* next field row to generate */
    int vector_noise;      /* synth_paths.vector_noise */
    int period_w, period_h; /* tileable: the noise of field pixel (r, c) is that of
                            * (r mod period_h, c mod period_w); 0: not periodic */
    float *period_noise;   /* period_w + 4 floats: one period of a row's noise */
    int same_row_shape;    /* btf__car_same_row_shape, and its gammas */
    float same_row_gamma3[3];
    int n_same_row;        /* the same-row offsets in adding order */
    int same_row_col[BTF_CAR_MAX_NEIGHBOURS];
    float same_row_gamma[BTF_CAR_MAX_NEIGHBOURS];
    float *ring;           /* depth rows of (fw + 2 pad) floats */
    float *noise, *noise_next; /* fw + 6 floats: the Gaussians of a row (of the next) */
    float *acc, *acc_next; /* fw floats: the earlier-row part of each sum (next row) */
    btf_wave *wave;        /* the wavefront that fills the ring, or NULL (row by row) */
} synth_field;

/* Field row r (any integer): a pointer to its field column 0 in the ring. */
static inline float *synth_field_ring_row(const synth_field *f, int r)
{
    int slot = ((r % f->depth) + f->depth) % f->depth;
    return f->ring + (size_t)slot * (f->fw + 2 * f->pad) + f->pad;
}

/* A field over window columns [x0, x1) and rows [y0, y1) with `margin`
 * (rows above, columns either side), zeros outside; period_w, period_h > 0
 * (paths->tileable): its noise is periodic with that period (floor-mod of
 * the field coordinates, the burn-in rows and margin columns included), so
 * that the window converges to the field on the period_w x period_h torus
 * (docs/synthesis.md, "Tileable synthesis"). Periodic fields run row by row. */
btf_status synth_field_init(synth_field *f, const btf_car_band *band, int margin,
                            uint32_t stream, int x0, int x1, int y0, int y1, int period_w,
                            int period_h, const synth_paths *paths, btf_error *err);
void synth_field_free(synth_field *f);
/* Zero-mean row y (increasing from call to call) of one field, over its
 * window. */
const float *synth_field_row(synth_field *f, int y, uint32_t seed_lo, uint32_t seed_hi);
/* The same for n (1..3) fields of one level of a subspace (same window,
 * same rows; their margins differ), stepping together: each field's values
 * are what it would get alone. */
void synth_field_rows(synth_field *const *f, int n, int y, uint32_t seed_lo, uint32_t seed_hi,
                      const float **rows);

/* ------------------------------------------------------------------ rows.c */

/* The row-by-row generator, on n (1..3) fields all at row next: one row
 * each, or two (rows next and next + 1; every field width >= 2 lead, lead
 * from btf__rows_pair_lead) with twice the independent chains. */
void btf__rows_step(synth_field *const *f, int n, uint32_t seed_lo, uint32_t seed_hi);
int btf__rows_pair_lead(synth_field *const *f, int n);
void btf__rows_pair(synth_field *const *f, int n, int lead, uint32_t seed_lo, uint32_t seed_hi);

/* -------------------------------------------------------------- collapse.c */

/* One level of a band's pyramid during synthesis. */
typedef struct synth_level {
    synth_field field;
    int x0, x1, y0, y1;    /* the level's window, absolute level coordinates */
    float *gauss_row;      /* G_l of the last row asked for, window width */
    /* Rows of G_l up-sampled horizontally to the finer level's window, for
     * its vertical pass: 3 slots, slot i mod 3 holding row up_row_of[slot]. */
    float *up_rows[3];
    int up_row_of[3];
    int fine_x0, fine_w;   /* the finer level's window */
} synth_level;

/* The pyramid of one spectral band. */
typedef struct synth_band {
    int levels;
    synth_level level[BTF_MAX_LEVELS];
    uint32_t seed_lo, seed_hi;
} synth_band;

/* Sets up the levels of spectral band `band` of a subspace for the output
 * window [0, w) x [0, h); margins[l] per level. */
btf_status synth_band_init(synth_band *sb, const btf_car_band *bands, const int *margins,
                           int levels, int subspace, int band, int w, int h, uint64_t seed,
                           const synth_paths *paths, btf_error *err);
void synth_band_free(synth_band *sb);
/* Row y of G_l of each of the nb (1..3) bands of one subspace, which step
 * together, over the level's window; rows asked in increasing order. */
void synth_gauss_rows(synth_band *sb, int nb, int l, int y, const float **out);
/* Row y of G_0 of each band written to dst[b] (the level's width) instead
 * of the band's own row: a caller that keeps rows saves a copy. */
void synth_gauss_rows_to(synth_band *sb, int nb, int y, float *const *dst);

/* btf_synthesise_image with the structure layer's pattern given (albedo:
 * the whole image's, or one period of it, as btf__structure_albedo makes it
 * for this size and seed), so that a caller that quilted the layers already
 * (the render) does not quilt them again; NULL quilts it here. */
btf_status btf__synthesise_image_albedo(const btf_model *m, int subspace,
                                        const btf_synth_opts *opts, const btf_image *albedo,
                                        btf_image *out, btf_error *err);

/* Colour matching (src/synth/colour_match.c, docs/synthesis.md, "Colour
 * matching"): the per-band marginal transfer gives each decorrelated band
 * the exemplar's histogram, but the bands are synthesised independently
 * where the material's chroma depends on its lightness, and a small
 * synthesis' histogram strays from the model's with its realisation: both
 * show in the CIE Lab histograms (the texture distances' first-order
 * component, btfcar/report.h). This pass measures img's own L*, a*, b*
 * quantiles (every pixel up to 128 x 128, a regular grid of as many
 * beyond), sends each channel of every pixel through the piecewise-linear
 * map from them onto the model's lab_quantile (resampled on 256 segments),
 * converts back and clamps into the exemplar's RGB box. Monotone per channel, deterministic, finite; a
 * tileable image stays tileable. BTF_E_ARG when the subspace holds no Lab
 * quantiles or img is not RGB or holds Inf or NaN. The synthesis calls it
 * by default (btf_synth_opts.match_colours). */
btf_status btf__colour_match(const btf_model *m, int subspace, btf_image *img, btf_error *err);

#endif
