/*
 * btfcar/model.h — the two model families and their files: the CAR model
 * (btf_model, MODEL.btfcar) and the reflectance-field model (btf_rf_model).
 * Part of the public C API of btfcar; include/btfcar.h includes every
 * topical header, and its conventions (docs/api.md) hold here too.
 */
#ifndef BTFCAR_MODEL_H
#define BTFCAR_MODEL_H

#include "base.h"
#include "image.h"

#include <stddef.h>
#include <stdint.h>

/* What this header declares is part of the ABI of libbtfcar.so: the library
 * is compiled with -fvisibility=hidden, and the declarations of the public
 * headers alone are exported (docs/install.md, "Shared library and soname"). */
#pragma GCC visibility push(default)

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------- the CAR model */

/* Paper section II.C. Each subspace image is decorrelated into 3 mono-spectral
 * bands (PCA, Karhunen-Loeve), each band decomposed into a Gaussian-Laplacian
 * pyramid, and each sub-band (band, level) modelled by a 2D causal
 * auto-regressive field  Y_r = gamma X_r + e_r,  e_r ~ N(0, sigma^2),  where
 * X_r holds the sub-band's values at the causal neighbourhood offsets. */

#define BTF_CAR_MAX_NEIGHBOURS 24
#define BTF_MAX_LEVELS 8

/* A causal offset: row < 0, or row == 0 and col < 0. */
typedef struct btf_offset {
    int8_t row, col;
} btf_offset;

typedef struct btf_car_band {
    int n;                                   /* neighbours, 0..BTF_CAR_MAX_NEIGHBOURS */
    btf_offset offsets[BTF_CAR_MAX_NEIGHBOURS];
    float gamma[BTF_CAR_MAX_NEIGHBOURS];     /* coefficients, one per offset */
    float sigma;                             /* noise standard deviation, >= 0 */
    float mean;                              /* mean of the sub-band */
} btf_car_band;

/* Marginal transfer of a subspace (docs/synthesis.md, "Marginals"): the CAR
 * fields' collapsed bands are Gaussian, the material's decorrelated channels
 * are not; synthesis sends each band v through the monotone piecewise-linear
 * map with knots z_j = synth_mean + synth_sd * N_j (N_j the standard normal
 * quantiles of the documented probabilities) onto the exemplar's quantiles
 * quantile[j], clamped to [quantile[0], quantile[last]] (the exemplar's
 * range), and the RGB result to [rgb_lo, rgb_hi] (the exemplar's RGB box,
 * rgb_lo >= 0). knots 0: no transfer (identity, no clamp), as in a model
 * file of format 1.0 or 1.1. */
#define BTF_MARGIN_KNOTS 32
typedef struct btf_marginal {
    int knots;                            /* 0 or BTF_MARGIN_KNOTS */
    float synth_mean[3], synth_sd[3];     /* per band: the synthesised band's mean and
                                             standard deviation (sd >= 0) */
    float quantile[3][BTF_MARGIN_KNOTS];  /* per band: the exemplar's quantiles, nondecreasing;
                                             [0] its minimum, [last] its maximum */
    float rgb_lo[3], rgb_hi[3];           /* the exemplar's linear RGB range, 0 <= lo <= hi */
    /* The exemplar's CIE Lab histogram (format 1.3, docs/synthesis.md,
     * "Colour matching"): L*, a*, b* of its RGB times the distances'
     * exposure (1, or 1 / the largest rgb_hi when that is above 1) at
     * probabilities j / 31, [0] the
     * minimum, [last] the maximum; nondecreasing, L* in [0, 100], a*, b* in
     * [-128, 128]. lab_knots 0: none (a file of format 1.2 or older), and
     * colour matching refuses the subspace. Only with knots. */
    int lab_knots;                        /* 0 or BTF_MARGIN_KNOTS */
    float lab_quantile[3][BTF_MARGIN_KNOTS];
} btf_marginal;

typedef struct btf_subspace_model {
    int view, light;           /* the representative image's pair; -1 for a texture */
    int width, height;         /* size of the analysed image */
    float mean[3];             /* mean linear RGB */
    float basis[9];            /* row-major 3x3: band_i = sum_j basis[3i+j] (rgb_j - mean_j);
                                  orthonormal, so rgb = mean + basis^T band */
    int levels;                /* pyramid levels, 1..BTF_MAX_LEVELS; level 0 is the finest */
    btf_car_band bands[3][BTF_MAX_LEVELS]; /* [spectral band][level] */
    btf_marginal marginal;     /* knots 0: none (btf_texture_fit and btf_analyse
                                  fit it for every subspace) */
} btf_subspace_model;

typedef struct btf_model {
    btf_dirset views, lights;  /* count 0 for a single texture */
    int n_subspaces;
    uint8_t *index;            /* [view * lights.count + light] -> subspace; NULL for a texture */
    btf_subspace_model *subspaces;
    /* The range map (paper section II.B) as a small periodic tile: heights in
     * texel units of the analysed images; NULL when absent. Normals follow
     * from it. */
    int range_width, range_height;
    float *range;
    float range_texel;         /* analysed-image texels per range-tile texel,
                                  along both axes (the tile keeps the image's
                                  aspect ratio) */
    /* The structure layer (docs/model.md, "Structure"): on the range map's
     * grid (texel 1 only), the albedo's luminance pattern (mean 1) that the
     * photometric stereo recovered. When present, every subspace's CAR
     * fields model the remainder: the exemplar divided by this pattern and
     * by the range map's relit shading (a + max(0, n.l)) / (a + l_z) under
     * the subspace's light, a = ambient. Synthesis multiplies the pattern
     * back, the renderer the shading; both through one quilting map of the
     * range map and the pattern (btf_structure_maps). NULL: none. */
    float *albedo;
    /* The colour of that pattern (docs/model.md, "Colour layer"): per texel
     * of the range map's grid three factors (R, G, B; each of mean 1 over
     * the grid) of the albedo's colour over its luminance, which multiply
     * the pattern channel by channel. Kept only where the colour varies
     * across the sample (a weave of two yarns); NULL: the pattern is grey. */
    float *chroma;
    float ambient;             /* a >= 0 of the shading above (0 without structure) */
    int shadows;               /* 1: that shading holds the relief's cast shadows,
                                  a + vis max(0, n.l) with vis from the range
                                  map's horizons (docs/model.md, "Shadows");
                                  0 before format 1.5 */
    /* The pair gains (docs/model.md, "Pair gains"): per measured pair
     * [(view * lights.count + light) * 3 + c], the ratio of the measured
     * image's mean colour to the render's of that pair from its subspace
     * image, so that every pair keeps its own brightness and colour (the
     * first-order statistics a subspace shares); the renderer interpolates
     * them with the images' weights. NULL: 1 everywhere. */
    float *gain;
    /* The library's own data about a model it read or fitted (the
     * synthesis margins computed then, docs/synthesis.md) and, since
     * format 1.7, the remainders' periodic cells (docs/model.md, "Periodic
     * cells"): opaque, freed by btf_model_free; NULL in a model built by
     * hand, which is fine. A copy of the struct that sets it to NULL
     * drops the cells (the copy then synthesises without them). */
    struct btf_model_internal *internal;
} btf_model;

/* Frees what the model owns and zeroes it; NULL and a zeroed model are fine. */
void btf_model_free(btf_model *m);
/* The provenance of a synthesis of subspace `subspace` of m, read from
 * model_path with seed: the subspace's representative (view, light) when it
 * has one (has_dirs 0 for a texture model or an out-of-range subspace). */
btf_exr_meta btf_model_exr_meta(const btf_model *m, const char *model_path, int subspace,
                                uint64_t seed);

/* Neighbourhood SPEC: comma-separated causal "row:col" offsets, e.g.
 * "0:-1,-1:0,-1:-1,-1:1". A non-causal or repeated offset is an error. */
btf_status btf_neighbourhood_parse(const char *spec, btf_offset *offsets, int *n,
                                   btf_error *err);
void btf_neighbourhood_format(const btf_offset *offsets, int n, char *buf, size_t len);

/* The model file MODEL.btfcar (docs/model-format.md): little-endian,
 * versioned, CRC-32 checked. Writing is atomic; reading a corrupt, truncated
 * or foreign file is an error naming it, never a crash. */
btf_status btf_model_write(const char *path, const btf_model *m, btf_error *err);
btf_status btf_model_read(const char *path, btf_model *m, btf_error *err);
/* The same to and from memory: encode's buffer is malloc'd (the caller
 * frees it); decode's name starts its messages (NULL: "model"). The file
 * forms are these plus the atomic write or the whole-file read. */
btf_status btf_model_encode(const btf_model *m, unsigned char **data, size_t *size,
                            btf_error *err);
btf_status btf_model_decode(const unsigned char *data, size_t size, const char *name,
                            btf_model *m, btf_error *err);

/* Makes a range tile periodic in place (analysis does, reading a model file
 * of format 1.0 does, and a program that builds a model by hand should):
 * its mean slope removed, then a variance-preserving cross-fade with itself
 * shifted by half a period along each axis (docs/render.md), which keeps
 * the tile's mean and variance and removes the jumps between opposite
 * edges; the result lies on the model file's 16-bit height grid, so
 * writing it loses nothing. Heights must be finite (BTF_E_DATA). */
btf_status btf_range_make_periodic(float *heights, int width, int height, btf_error *err);

/* The largest magnitude of a band's sigma and mean and of a subspace's
 * colour mean that a model holds: within it, synthesis stays inside the
 * float range (src/model/model_check.c derives it); the model validator
 * refuses more. */
#define BTF_MODEL_MAX_VALUE 1e30f
/* The largest pixel magnitude `btfcar texture-fit` models: the bands of
 * such an exemplar (differences of colours, projected on a unit basis,
 * split into pyramid levels) stay far inside BTF_MODEL_MAX_VALUE. */
#define BTF_EXEMPLAR_MAX_VALUE 1e28f

/* ----------------------------------------- the reflectance-field model */

/* The pixel-wise alternative to the CAR model, the accuracy end of the
 * speed/accuracy trade (Meseth, Müller & Klein 2003, "Preserving realism in
 * real-time rendering of bidirectional texture functions"; docs/rf.md):
 * per measured view v and texel x a reflectance field RF_v(x, l) is fitted
 * over the light directions l (paper section 3.1), on luminance, with the
 * colour from the per-view, per-texel average chromaticity (section 4.2);
 * rendering interpolates the four closest measured views (section 5.4).
 *
 *  - BTF_RF_PTM: a biquadratic polynomial texture map in the light's (lu, lv)
 *    = (lx, ly), linear least squares: a0 lu^2 + a1 lv^2 + a2 lu lv + a3 lu
 *    + a4 lv + a5 (6 parameters).
 *  - BTF_RF_LOBES: k non-linear lobes, equation (1), <(a,b,c), l>^n, fitted
 *    by Levenberg-Marquardt, kept as rho <d, l>^n with the unit direction
 *    d = (x, y, 1) / |(x, y, 1)| and rho = |(a,b,c)|^n (the same function;
 *    this form cannot overflow): 4 parameters per lobe (rho, x, y, log2 n).
 *  - BTF_RF_LAFORTUNE: for contrast, one Lafortune model per texel over all
 *    views (Table 1's first column): rho_d l_z + sum of k lobes
 *    rho (cx lx vx + cy ly vy + cz lz vz)^n, 1 + 5k parameters, one colour
 *    per texel.
 *
 * Every parameter is kept as a 16-bit code with a per-field (per-view)
 * scale and offset per parameter slot: v = lo + code (hi - lo) / 65535, an
 * error of at most (hi - lo) / 131070 (docs/rf.md, "Quantisation").
 * Clamps keep every evaluation finite: rho in [0, BTF_RF_MAX_RHO], n in
 * [BTF_RF_MIN_EXPONENT, BTF_RF_MAX_EXPONENT], |x|, |y| <= 16 and
 * |cx|, |cy|, |cz| <= 1, so no lobe exceeds its rho. */
typedef enum btf_rf_fit_kind {
    BTF_RF_PTM = 0,       /* default */
    BTF_RF_LOBES = 1,
    BTF_RF_LAFORTUNE = 2
} btf_rf_fit_kind;
#define BTF_RF_MAX_LOBES 4
#define BTF_RF_MAX_RHO 1.0e4f
#define BTF_RF_MIN_EXPONENT 0.25f
#define BTF_RF_MAX_EXPONENT 1024.0f
/* The parameter slots of a texel in one field: its luminance parameters,
 * then 3 chromaticity factors (rgb = chroma x luminance). */
#define BTF_RF_MAX_SLOTS (1 + 5 * BTF_RF_MAX_LOBES + 3)

/* The name of a fit ("ptm", "lobes", "lafortune"); NULL if out of range. */
const char *btf_rf_fit_name(int fit);

/* A fitted model. codes[(field * height * width + texel) * slots + s] is
 * slot s of a texel (texel = y * width + x) in field `field` (a view, or
 * the one field of a Lafortune model); lo/hi[field * slots + s] its range. */
typedef struct btf_rf_model {
    int fit;                   /* btf_rf_fit_kind */
    int lobes;                 /* k */
    int width, height;         /* texels */
    btf_dirset views, lights;  /* the measured directions */
    int params;                /* luminance parameters per texel and field */
    int slots;                 /* params + 3 */
    int fields;                /* views.count (ptm, lobes) or 1 (lafortune) */
    float *lo, *hi;            /* [fields * slots] */
    uint16_t *codes;           /* [fields * width * height * slots] */
    /* Memory reduction (paper section 6; btf_rf_fit_sampled): map NULL (the
     * model describes its width x height texels), or the texture coordinates
     * of a surface of surface_width x surface_height texels into the fitted
     * width x height sample: surface texel (x, y) is sample texel
     * (map[2 (y surface_width + x)], map[2 (y surface_width + x) + 1]).
     * (sample_x, sample_y): where the sample lies in the dataset's images,
     * and in the surface, whose texels there map to themselves. */
    int surface_width, surface_height;
    int sample_x, sample_y;
    uint16_t *map;             /* [surface_height * surface_width * 2], or NULL */
} btf_rf_model;
void btf_rf_model_free(btf_rf_model *m);
/* The texels the model describes: the coordinate map's size when it has one,
 * else width x height. Every evaluation (flat and scene render, btf__rf_eval,
 * the fits' error) wraps coordinates into this surface. */
void btf_rf_surface_size(const btf_rf_model *m, int *width, int *height);

/* What a model costs (docs/rf.md, "Memory reduction"): in memory, the
 * coefficients (fields x slots x (2 bytes per texel + 8 for the range)) and
 * the coordinate map (4 bytes per surface texel; 0 without one), and in
 * the file (btf_rf_encode, deflated) in all and for the map alone (the
 * file's bytes less those of the same model without its map). */
typedef struct btf_rf_bytes {
    uint64_t coefficients, map;   /* in memory */
    uint64_t file, file_map;      /* the file; of which the map */
} btf_rf_bytes;
btf_status btf_rf_model_bytes(const btf_rf_model *m, btf_rf_bytes *out, btf_error *err);

/* The file (docs/rf.md, "File"): the container of MODEL.btfcar (version,
 * zlib, CRC-32) with its own signature "\x89BTFRFL\r\n\x1a\n" and sections.
 * name (NULL: "buffer") names the buffer in messages. The decoder checks
 * everything and never trusts a size it has not bounded. */
btf_status btf_rf_encode(const btf_rf_model *m, unsigned char **data, size_t *size,
                         btf_error *err);
btf_status btf_rf_decode(const unsigned char *data, size_t size, const char *name,
                         btf_rf_model *out, btf_error *err);
btf_status btf_rf_write(const char *path, const btf_rf_model *m, btf_error *err);
/* (A file of either family is read with btf_material_read, btfcar/material.h.) */

#ifdef __cplusplus
}
#endif

#pragma GCC visibility pop
#endif /* BTFCAR_MODEL_H */
