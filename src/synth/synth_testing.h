/*
 * synth_testing.h — hooks into synthesis for tests and benchmarks only
 * (CAR synthesis, Haindl & Filip 2007, section II.C): a single CAR field,
 * forced margins, the GPU's buffer
 * limit and tiling. Not part of the public
 * API; the definitions live beside the code they reach into
 * (src/synth/synthesise.c, src/synth/torus.c, gpu/synth_gpu.c).
 */
#ifndef BTF_SYNTH_TESTING_H
#define BTF_SYNTH_TESTING_H

#include "btfcar.h"

/* One CAR field alone (its mean included), 1 channel, opts->width x
 * opts->height (both required), streamed like btf_synthesise; stream names
 * the noise stream; margin < 0: the band's own (btf__car_margin). */
btf_status btf__car_synthesise_field(const btf_car_band *band, int margin, uint32_t stream,
                                     const btf_synth_opts *opts, btf_rows_fn fn, void *user,
                                     btf_error *err);

/* The DFT reference's bounds: width x height (8192 x 8192), and the largest
 * prime factor of a side (its DFT's cost grows with it). */
#define BTF_SYNTH_TILE_MAX_PIXELS (1ull << 26)
#define BTF_SYNTH_TILE_MAX_PRIME 127

/* One CAR field alone on the w x h torus (tileable synthesis' generator,
 * src/synth/torus.c), zero-mean (without band->mean), into out (w h floats). */
btf_status btf__car_torus_field(const btf_car_band *band, uint32_t stream, int w, int h,
                                uint64_t seed, float *out, btf_error *err);

/* The exact tileable reference (src/synth/tileable.c): subspace image of
 * opts' size (0: the analysed size) with every CAR field solved on its
 * level's torus by a 2D DFT and the pyramid collapsed with wrap-around;
 * the streaming tileable synthesis (btf_synth_opts.tileable) converges to
 * it. Sizes within BTF_SYNTH_TILE_MAX_PIXELS, prime factors at most
 * BTF_SYNTH_TILE_MAX_PRIME; BTF_E_NUMERIC where a level is singular. */
btf_status btf__synthesise_torus_dft(const btf_model *m, int subspace, const btf_synth_opts *opts,
                                     btf_image *out, btf_error *err);

/* btf_synthesise with margins[band][level] instead of the bands' own
 * (NULL: their own). */
btf_status btf__synthesise_margins(const btf_model *m, int subspace,
                                   const int (*margins)[BTF_MAX_LEVELS],
                                   const btf_synth_opts *opts, btf_rows_fn fn, void *user,
                                   btf_error *err);

/* GPU buffers of at most `bytes` (0: the device's maxStorageBufferRange),
 * so that tests can force the tiling of btf_gpu_synthesise. */
void btf__gpu_set_max_buffer_bytes(btf_gpu *g, uint64_t bytes);
/* How the last btf_gpu_synthesise was cut: batches of images, and jobs
 * (one per strip of rows of a batch). */
void btf__gpu_last_tiling(const btf_gpu *g, int *batches, int *jobs);

#endif
