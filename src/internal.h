/*
 * internal.h — helpers shared by the library's source files; not installed.
 */
#ifndef BTF_INTERNAL_H
#define BTF_INTERNAL_H

#include "btfcar.h"

#include <stdarg.h>
#include <stdio.h>

#if defined(__GNUC__)
#define BTF_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define BTF_PRINTF(a, b)
#endif

/* Fills err (if non-NULL) with a formatted one-line message; returns code. */
int btf_fail(btf_error *err, int code, const char *fmt, ...) BTF_PRINTF(3, 4);

/* malloc/calloc that report BTF_E_NOMEM through err; size overflow checked. */
void *btf_alloc(size_t count, size_t size, btf_error *err);
void *btf_calloc(size_t count, size_t size, btf_error *err);

/* Atomic file writing: btf_tmp_path gives a unique temporary name beside
 * `path` (same folder, so rename() is atomic); btf_commit_file renames it over
 * path, btf_abort_file removes it. */
int btf_tmp_path(const char *path, char *tmp, size_t n, btf_error *err);
int btf_commit_file(const char *tmp, const char *path, btf_error *err);
void btf_abort_file(const char *tmp);
/* btf_write_file_atomic (a whole buffer) is public: include/btfcar.h. */
/* Reads a whole file (at most max_bytes) into a malloc'd buffer. */
int btf_read_file(const char *path, size_t max_bytes, unsigned char **data,
                  size_t *n, btf_error *err);

/* rm -r: removes a folder and everything below it (links are not
 * followed); errors are ignored. For temporary output after a failure. */
void btf_remove_tree(const char *path);
/* Joins a folder and a name into out (size n); BTF_E_ARG when too long. */
int btf_path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err);

/* Number of online CPUs (at least 1). */
int btf_cpu_count(void);

/* Directions named in whole degrees (file names) match a known set within
 * this many degrees (src/directions.c, src/dataset.c). */
#define BTF_DIR_NAME_TOLERANCE 0.75

/* Spectral decorrelation: src/decorrelate.c. Mean colour, orthonormal 3x3
 * basis (rows by decreasing variance) and the band variances. */
int btf_pca3(const btf_image *img, float mean[3], float basis[9], double variance[3],
             btf_error *err);
/* bands[b][i] = basis row b . (rgb_i - mean), in double. */
void btf_decorrelate(const btf_image *img, const float mean[3], const float basis[9],
                     double *bands[3]);

/* Gaussian-Laplacian pyramid: src/pyramid.c. */
typedef struct btf_pyramid {
    int levels;
    int width[BTF_MAX_LEVELS], height[BTF_MAX_LEVELS];
    double *level[BTF_MAX_LEVELS]; /* Laplacian levels; the last is the low-pass */
} btf_pyramid;
int btf_pyr_down(const double *src, int w, int h, double **dst, btf_error *err);
int btf_pyr_up(const double *src, int w2, int h2, int w, int h, double **dst, btf_error *err);
int btf_pyramid_build(const double *band, int w, int h, int levels, btf_pyramid *p,
                      btf_error *err);
int btf_pyramid_collapse(const btf_pyramid *p, double **out, btf_error *err);
void btf_pyramid_free(btf_pyramid *p);

/* Synthesis margins (src/margin.c): the rows above its window a band's
 * CAR field starts, and the columns it runs on either side, so that the
 * zero boundary's transient has died out (below BTF_SYNTH_MARGIN_EPS of the
 * stationary variance) before the window. Depends on the band alone; CPU
 * and GPU synthesis both use it. 0 for a band without neighbours. */
#define BTF_SYNTH_MARGIN_MIN 8
#define BTF_SYNTH_MARGIN_MAX 256
#define BTF_SYNTH_MARGIN_EPS 1e-4
int btf_car_margin(const btf_car_band *b);
/* The same with a work budget (grid cells times neighbours, decremented):
 * when it runs out, the safe answer BTF_SYNTH_MARGIN_MAX. Reading a model
 * file uses it so that a small crafted file cannot cost minutes. Both
 * return -1 when out of memory. */
int btf_car_margin_within(const btf_car_band *b, double *budget);
/* The share of the impulse response's energy beyond m rows or columns: a
 * lower bound of what a pixel that far from the zero boundary misses of the
 * stationary variance (the side boundaries pin the field to 0, which costs
 * nearly unstable bands more), or -1 when out of memory. */
double btf_car_margin_shortfall(const btf_car_band *b, int m);
/* The margin synthesis uses: the band's cached one (set by fitting and
 * reading models), else btf_car_margin; -1 when out of memory. */
int btf_band_margin(const btf_car_band *b);

/* Noise rows (src/noise_row.c): the Gaussians of blocks b0 .. b0 + n - 1 of
 * a row (btf_noise4 of each, 4 n floats into out), bit for bit the same on
 * every path; vector_path 0 forces the portable loop. btf_noise_path_avx2
 * says whether the AVX2 path is in use (CPU support, BTF_NOISE_PORTABLE). */
void btf_noise_blocks(uint32_t seed_lo, uint32_t seed_hi, uint32_t stream, uint32_t row,
                      uint32_t b0, uint32_t n, int vector_path, float *out);
int btf_noise_path_avx2(void);

/* The wavefront generator of CAR fields (src/wave.c): eight rows at once,
 * bit for bit the row-by-row recursion. btf_wave_supported says whether a
 * band and field width qualify on this machine (AVX2, small offsets, family
 * same-row shapes, wide enough; BTF_SYNTH_WAVE=0 or BTF_NOISE_PORTABLE=1
 * turn it off). A wave stores its rows into a ring of `depth` rows of fw + 2
 * pad floats (row r in slot r mod depth, as src/synth.c's ring_row; depth
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

/* Synthesis (src/synth.c): the indices of a band's same-row offsets in the
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

/* Tab-separated manifests: src/tsv.c */
typedef struct btf_tsv {
    char *text;          /* the file, split in place */
    int ncols, nrows;
    const char *names[64];
    char **cells;        /* nrows * ncols */
    int *line_no;        /* file line of each row, for messages */
} btf_tsv;
int btf_tsv_read(const char *path, btf_tsv *t, btf_error *err);
void btf_tsv_free(btf_tsv *t);
int btf_tsv_column(const btf_tsv *t, const char *name); /* -1 if absent */
const char *btf_tsv_cell(const btf_tsv *t, int row, int col);
int btf_tsv_number(const btf_tsv *t, const char *path, int row, int col, double *out,
                   btf_error *err);

/* EXR (OpenEXR core C API): src/exr_io.c */
int btf_exr_probe(const char *path, btf_image_header *hdr, btf_error *err);
int btf_exr_read(const char *path, int channels, btf_image *out, btf_error *err);
int btf_exr_write(const char *path, const btf_image *img, int half, btf_error *err);

/* Procedural materials (src/material.c): precomputation for rendering many
 * (view, light) pairs. What a view sees depends only on the view, and what a
 * light shadows only on the light, so a generator builds one view map per
 * view and one light map per light and combines them per pair with
 * btf_material_render_maps (cheap: one shading per texel). All coordinates are
 * texture coordinates: u = column, w = row (row 0 at the top); the reference
 * plane is z = 0 (btf_material_make's heights have zero mean). Directions and
 * stored normals use the frame x right, y UP in the image (row index grows
 * towards -y), z towards the camera. The maps are read-only once made, so any
 * number of threads may share them. */
typedef struct btf_view_map {
    int size;
    float *hit;    /* size*size*2: (u, w) of the surface point the view ray
                      through texel (x, y) of the reference plane hits,
                      wrapped into [0, size) */
    float *normal; /* size*size*3: unit normal at the hit */
    float *albedo; /* size*size*3: albedo at the hit */
} btf_view_map;
int btf_view_map_make(const btf_material *m, btf_dir view, btf_view_map **out,
                      btf_error *err);
void btf_view_map_free(btf_view_map *vm);

typedef struct btf_light_map {
    int size;
    float *vis;    /* size*size: visibility of the light from the surface point
                      above texel (x, y): 0 in cast shadow .. 1 lit (soft edge) */
} btf_light_map;
int btf_light_map_make(const btf_material *m, btf_dir light, btf_light_map **out,
                       btf_error *err);
void btf_light_map_free(btf_light_map *lm);

/* Shades one (view, light) pair from its maps into out (allocated here, size x
 * size x 3; the caller frees it). view and light must be the directions the
 * maps were made for. */
int btf_material_render_maps(const btf_material *m, const btf_view_map *vm,
                             const btf_light_map *lm, btf_dir view, btf_dir light,
                             btf_image *out, btf_error *err);
/* Recomputes m->normal from m->height (central differences, wrapping). */
void btf_material_normals_from_height(btf_material *m);

/* The OpenCV bridge (src/cv_bridge.cpp), a C interface. Error text goes to
 * errbuf; return 0 on success. */
int btfcv_read(const char *path, int *w, int *h, int *c, int *depth16,
               void **pixels, char *errbuf, size_t errlen);
int btfcv_encode(const char *ext, int w, int h, int c, const unsigned char *pixels,
                 int jpeg_quality, unsigned char **out, size_t *outlen,
                 char *errbuf, size_t errlen);
int btfcv_rgb_to_lab(const float *rgb, size_t n, float *lab, char *errbuf, size_t errlen);
int btfcv_dft2(double *re, double *im, int w, int h, int inverse, char *errbuf, size_t errlen);
int btfcv_dct2(double *a, int w, int h, int inverse, char *errbuf, size_t errlen);

#endif
