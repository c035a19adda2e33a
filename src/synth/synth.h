/*
 * synth.h — CPU synthesis internals (src/synth/): noise rows, the
 * wavefront generator, band checks shared with the GPU host code. Private
 * to the library.
 */
#ifndef BTF_SYNTH_H
#define BTF_SYNTH_H

#include "btfcar.h"

#include <stddef.h>

/* Noise rows (synth/noise_row.c): the Gaussians of blocks b0 .. b0 + n - 1 of
 * a row (btf_noise4 of each, 4 n floats into out), bit for bit the same on
 * every path; vector_path 0 forces the portable loop. btf_noise_path_avx2
 * says whether the AVX2 path is in use (CPU support, BTF_NOISE_PORTABLE). */
void btf_noise_blocks(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                      uint32_t b0, uint32_t n, int vector_path, float *out);
int btf_noise_path_avx2(void);

/* The wavefront generator of CAR fields (synth/wave.c): eight rows at once,
 * bit for bit the row-by-row recursion. btf_wave_supported says whether a
 * band and field width qualify on this machine (AVX2, small offsets, family
 * same-row shapes, wide enough; BTF_SYNTH_WAVE=0 or BTF_NOISE_PORTABLE=1
 * turn it off). A wave stores its rows into a ring of `depth` rows of fw + 2
 * pad floats (row r in slot r mod depth, as synth/synth.c's ring_row; depth
 * >= BTF_WAVE_DEPTH, pad >= btf_wave_pad(), else BTF_E_ARG): btf_wave_run
 * returns once row `row` (>= row0, rows asked in increasing order) is
 * complete there. Rows row + 1 .. row + 7 are then partly written, so only
 * row `row` may be read before the next run. */
typedef struct btf_wave btf_wave;
#define BTF_WAVE_DEPTH 8
int btf_wave_supported(const btf_car_band *b, int fw);
int btf_wave_pad(void);
btf_wave *btf_wave_new(const btf_car_band *b, int fw, int fx0, int row0, uint32_t stream,
                       float *ring, int depth, int pad, btf_error *err);
void btf_wave_run(btf_wave *w, int row, uint32_t seed_lo, uint32_t seed_hi);
void btf_wave_free(btf_wave *w);
/* Turns the wavefront on or off for syntheses started afterwards and
 * returns whether it was on (tests and benchmarks compare the two, then
 * restore; the default: on unless BTF_SYNTH_WAVE=0). btf_wave_available:
 * whether this build and CPU have it at all (GCC, x86-64, AVX2, the AVX2
 * noise path). */
int btf_wave_enable(int on);
int btf_wave_available(void);

/* Synthesis (synth/synth.c): the indices of a band's same-row offsets in the
 * order btf_shared.h adds them (farthest column first); returns their count.
 * Shared with the GPU host code, which orders the shader's offsets so. */
int btf_car_same_row_order(const btf_car_band *b, int *idx);
/* A band synthesis can run: 0..BTF_CAR_MAX_NEIGHBOURS causal offsets, a
 * margin within 0..BTF_SYNTH_MARGIN_MAX (CPU and GPU paths alike). */
int btf_synth_check_band(const btf_car_band *b, btf_error *err);
/* BTF_E_NUMERIC naming the subspace and row if any of n values is not
 * finite: no synthesis hands out Inf or NaN (a model fitted to values near
 * the float limit can overflow); both backends check their output with it. */
int btf_check_finite_row(const float *v, size_t n, int subspace, int y, btf_error *err);

#endif
