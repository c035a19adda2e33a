/*
 * model.h — the model's rules shared by its files (src/model/): the limits
 * of docs/model-format.md, which a model in memory must meet to be written
 * and a file must meet to be read, the validator that checks them all, and
 * the synthesis margins a model keeps for its CAR bands (paper section
 * II.C). Private to the library.
 */
#ifndef BTF_MODEL_H
#define BTF_MODEL_H

#include "core/core.h"

/* The parts of an encoded model file (docs/report-compression.md). */
typedef enum btf_model_part {
    BTF_MODEL_PART_CONTAINER = 0, /* the 26-byte file header and the CRC-32 */
    BTF_MODEL_PART_DEFLATE,       /* zlib's header and Adler-32, deflate's block
                                     headers, code tables, end-of-block codes
                                     and final padding (0 when stored) */
    BTF_MODEL_PART_FRAMING,       /* section tags and lengths, the subspace and
                                     marginal counts, each subspace's
                                     representative pair and analysed size */
    BTF_MODEL_PART_DIRECTIONS,    /* VIEW and LGHT: names, counts, directions */
    BTF_MODEL_PART_INDEX,         /* INDX: the index table */
    BTF_MODEL_PART_SPECTRAL,      /* per subspace: the mean colour and the 3 x 3 basis */
    BTF_MODEL_PART_LEVELS,        /* per subspace: the pyramid level count */
    BTF_MODEL_PART_NEIGHBOURHOODS,/* per band: neighbour count and offsets */
    BTF_MODEL_PART_GAMMAS,        /* per band: the CAR coefficients */
    BTF_MODEL_PART_SIGMAS,        /* per band: the noise deviation */
    BTF_MODEL_PART_BAND_MEANS,    /* per band: the sub-band mean */
    BTF_MODEL_PART_MARGINALS,     /* MARG: per subspace its knot count and transfer */
    BTF_MODEL_PART_RANGE,         /* RANG: the range/normal tile, all of its body */
    BTF_MODEL_PART_STRUCTURE,     /* STRC: the albedo pattern and the shading's ambient */
    BTF_MODEL_PART_GAINS,         /* GAIN: the pair gains */
    BTF_MODEL_PART_CELLS,         /* CELL: the remainders' periodic cells */
    BTF_MODEL_PART_COUNT
} btf_model_part;

/* Limits (docs/model-format.md, "Validation"). */
#define BTF_MODEL_MAX_DIRS 4096
#define BTF_MODEL_MAX_SUBSPACES 255 /* the index table stores uint8 ids; 255 is
                                       BTF_PAIR_NONE (a pair not measured) */
#define BTF_MODEL_MAX_IMAGE_SIDE (1 << 20)
#define BTF_MODEL_MAX_RANGE_SIDE 65535
#define BTF_MODEL_MAX_RANGE_SAMPLES (1L << 24)
#define BTF_MODEL_MAX_NAME 31       /* bytes of a direction set's name */

/* Every rule of docs/model-format.md that a model in memory must meet. code
 * is BTF_E_DATA when writing (the caller's model is wrong) and BTF_E_FORMAT
 * when reading (the file is). One validator serves both directions, so
 * whatever btfcar writes it can read. */
btf_status btf__model_validate(const btf_model *m, const char *name, btf_status code,
                               btf_error *err);

/* The synthesis margins of a model's bands (model/model_margins.c; each
 * computed by btf__car_margin_within, car/car.h), kept in m->internal so that
 * synthesis need not compute them at every call: reading a model file
 * computes them all within a work budget (in the order subspace, band,
 * level), fitting one without (budget < 0). BTF_E_NOMEM when out of
 * memory. */
btf_status btf__model_keep_margins(btf_model *m, double budget);
void btf__model_internal_free(struct btf_model_internal *in);

/* The remainders' periodic cells (model/structure_cells.c, docs/model.md,
 * "Periodic cells"): on a lattice's cell in Hermite normal form (w x h
 * texels; texel (x, y) of the range grid is cell texel
 * ((x - t shift) mod w, y - t h), t = floor(y / h)), per subspace three
 * factors per cell texel, each channel of mean 1, on the albedo pattern's
 * one-byte grid; a subspace not kept holds 1s. Kept in m->internal (the
 * public struct's layout is the ABI's). */
#define BTF_CELLS_MAX_TEXELS 4096
/* A subspace keeps its cell when it explains this share of the remainder's
 * variance. */
#define BTF_CELLS_MIN_EXPLAINED 0.2
/* ... and does no harm to the member of its subspace it serves worst at
 * the exemplar's view (the share it explains there is not negative). */
#define BTF_CELLS_PROBE_MIN 0.0
typedef struct btf_cells {
    int w, h, shift, n_subspaces;
    unsigned char *kept; /* [k] 1: subspace k has a cell */
    float *value;        /* [k][h][w][3] */
} btf_cells;
/* The cell of a lattice (x0, y0, x1, y1) in Hermite normal form; 0 when
 * degenerate or larger than BTF_CELLS_MAX_TEXELS. */
int btf__cells_from_lattice(const int lattice[4], int *w, int *h, int *shift);
int btf__cell_index(const btf_cells *c, int x, int y);
/* Cells of 1s (none kept) for n subspaces; NULL (err set) when the geometry
 * is out of bounds or out of memory. */
btf_cells *btf__cells_new(int w, int h, int shift, int n_subspaces, btf_error *err);
void btf__cells_free(btf_cells *c);
const float *btf__cells_of(const btf_cells *c, int k);
int btf__cells_any(const btf_cells *c);
/* The model's cells (NULL: none) and setting them (taking c over). */
const btf_cells *btf__model_cells(const btf_model *m);
btf_status btf__model_set_cells(btf_model *m, btf_cells *c, btf_error *err);
/* btf__structure_apply_row for subspace k: a base pattern of 4 channels
 * (RGB and the cell index) times k's cell, texel by texel, with the bits
 * btf__structure_for gives (the product first), so that the CPU's rows
 * need no whole pattern per subspace; any other pattern as it is. */
void btf__structure_apply_row_for(const btf_model *m, int k, const btf_image *a, int y,
                                  float *rgb, int width);
/* The structure pattern of subspace k: base as btf__structure_albedo makes
 * it (with cells: RGB and the cell index per texel) times k's cell, into
 * tmp (allocated here when used; the caller frees it); *use is base itself
 * when it has no cell index. */
btf_status btf__structure_for(const btf_model *m, int k, const btf_image *base, btf_image *tmp,
                              const btf_image **use, btf_error *err);
/* The margin synthesis uses for band b, level l of subspace k: the kept
 * one while the band's neighbourhood and coefficients are those it was
 * computed for, else btf__car_margin; -1 when out of memory. */
int btf__model_margin(const btf_model *m, int k, int b, int l);

/* For the report's accounting (src/report/model_bytes.c): btf_model_encode
 * (the same file bytes in *data, *size), also handing out the payload
 * before deflate and, per payload byte, the btf_model_part it belongs to
 * (both malloc'd, n bytes each; the caller frees them with free). On
 * failure nothing is handed out. */
typedef struct btf_model_payload_parts {
    unsigned char *payload;
    unsigned char *part;
    size_t n;
} btf_model_payload_parts;
btf_status btf__model_encode_parts(const btf_model *m, unsigned char **data, size_t *size,
                                   btf_model_payload_parts *parts, btf_error *err);

/* The structure layer on a surface (model/structure_map.c, docs/model.md
 * "Structure"). Whether m's range map is at the analysed resolution
 * (texel 1), the case that is quilted. */
int btf__structure_quilted(const btf_model *m);
/* The period a surface side of n texels repeats (n up to 2048, else its
 * largest divisor in 512..2048, else n). */
int btf__structure_period(int n);
/* The quilting map of a pw x ph torus: map[2 i], map[2 i + 1] the column
 * and row of the model's range grid at surface texel i (malloc'd). */
btf_status btf__structure_coords(const btf_model *m, int pw, int ph, uint64_t seed,
                                 uint16_t **map, btf_error *err);
/* Channels of the albedo pattern: 3 with a colour layer, else 1. */
int btf__structure_channels(const btf_model *m);
/* The albedo pattern over width x height, as its period (periodic: read
 * (x mod width, y mod height) of out); with periodic cells the base of
 * every subspace's pattern (btf__structure_for). */
btf_status btf__structure_albedo(const btf_model *m, int width, int height, uint64_t seed,
                                 btf_image *out, btf_error *err);
/* cache holds the pattern of width x height (btf__structure_albedo) when
 * this returns BTF_OK: kept if it already did (one seed per cache),
 * quilted again for another size; the caller frees it. */
btf_status btf__structure_pattern(const btf_model *m, int width, int height, uint64_t seed,
                                  btf_image *cache, btf_error *err);
/* RGB row y of an image times the pattern (a from btf__structure_albedo). */
void btf__structure_apply_row(const btf_image *a, int y, float *rgb, int width);
/* A whole synthesised image times the pattern; nothing without one. cache
 * (NULL: none) keeps the pattern between calls of one seed: it is quilted
 * again only for another size; the caller frees it. */
btf_status btf__structure_apply(const btf_model *m, int subspace, uint64_t seed, btf_image *img,
                                btf_image *cache, btf_error *err);
/* The quilted layers over width x height, placed by one quilting map:
 * heights and albedo (each NULL or width x height floats of the caller's;
 * albedo 1 without a pattern). The albedo has btf__structure_channels(m)
 * channels, or with with_cells btf__structure_base_channels(m): 4 (RGB and
 * the cell index) when the model keeps periodic cells. */
btf_status btf__structure_layers(const btf_model *m, int width, int height, uint64_t seed,
                                 float *heights, float *albedo, int with_cells, btf_error *err);
int btf__structure_base_channels(const btf_model *m);
/* The heights of the pw x ph torus placed by the quilting map (from
 * btf__structure_coords) into out, the quilting's joins relaxed in the
 * gradient domain (model/structure_seams.c); the identity map gives the
 * range map itself. */
btf_status btf__structure_heights(const btf_model *m, const uint16_t *map, int pw, int ph,
                                  float *out, btf_error *err);
/* btf_structure_maps, whose albedo with with_cells is the base pattern
 * (btf__structure_base_channels; src/range/range_map.c). */
btf_status btf__structure_maps(const btf_model *m, int width, int height, uint64_t seed,
                               btf_image *height_out, btf_image *normal_out,
                               btf_image *albedo_out, int with_cells, btf_error *err);

/* The largest ambient term a model may hold (the analysis clamps its fit
 * there; the validator refuses more). */
#define BTF_STRUCTURE_AMBIENT_MAX 4.0f

/* The structure layer's analysis (analyse/structure_fit.c). The albedo
 * pattern's one-byte code (log2 grid of 1/32 over [-4, 4]) and its value. */
unsigned btf__albedo_code(float a);
float btf__albedo_value(unsigned q);
/* m->albedo from photometric stereo's albedo (range_width x range_height):
 * its luminance over its mean, on the file's grid. */
btf_status btf__structure_albedo_from(const btf_image *albedo, btf_model *m, double *spread,
                                      btf_error *err);
/* A colour layer is kept when some channel's log2 spread across the sample
 * reaches this (analyse/structure_fit.c). */
#define BTF_CHROMA_MIN_SPREAD 0.1
/* The normals of m's range map at its own size (as the renderer's). */
btf_status btf__structure_normals(const btf_model *m, btf_image *normal, btf_error *err);
/* The ambient term a of n exemplars under their lights (the median of each
 * one's least-squares fit). */
/* What the structure layer's shading of one exemplar reads: the range
 * map's normals and horizons, and per exemplar pixel the texel it shows
 * (the renderer's parallax under the exemplar's view, btf__structure_warp;
 * NULL: the pixel itself). */
typedef struct btf_structure_tap {
    int i[4];                  /* the four texels of a bilinear lookup */
    float w[4];                /* and their weights */
} btf_structure_tap;
typedef struct btf_structure_geom {
    const btf_image *normal;
    const uint32_t *horizon;   /* NULL: no shadows */
    const btf_structure_tap *taps; /* per exemplar pixel; NULL: the pixel itself */
} btf_structure_geom;
/* taps[pixel] for an exemplar seen from view: where the renderer's
 * parallax shift (btf_shade_parallax at relief 1) reads for that pixel,
 * bilinear, held inside the sample. */
btf_status btf__structure_warp(const btf_model *m, btf_dir view, btf_structure_tap **taps,
                               btf_error *err);
/* At exemplar pixel i under light l (unit): vis max(0, n . l), and the
 * albedo pattern of channel c (with the colour layer), as the warp reads
 * them. */
double btf__structure_lit(const btf_structure_geom *g, size_t i, const double l[3]);
/* taps[pixel] of a flat render of the sample at its own size from view, by
 * the renderer's view march of a relief that casts shadows
 * (btf_shade_march at relief 1, round the torus as the renderer wraps). */
btf_status btf__structure_march_taps(const btf_model *m, btf_dir view, btf_structure_tap **taps,
                                     btf_error *err);
/* pred[pair * 3 + c]: the mean colour the renderer gives each measured pair
 * of a model with a structure layer (m->subspaces[k].light set), from each
 * subspace's texture mean tex_mean[k * 3 + c] (the exemplar over its
 * shading): the albedo pattern where the pair's view sees it (its march,
 * or the one-step shift without shadows) times the shading under the
 * pair's light. */
btf_status btf__pair_predict_views(const btf_model *m, const double *tex_mean,
                                   const btf_image *normal, const uint32_t *horizon,
                                   double *pred, btf_error *err);
double btf__structure_albedo_at(const btf_structure_geom *g, const btf_model *m, size_t i, int c);
double btf__structure_fit_ambient(const btf_image *imgs, const btf_dir *lights,
                                  const btf_structure_geom *geoms, int n, const btf_model *m);
/* Light l's visibility (0..1) at texel i of a horizon map (NULL: 1), as
 * the renderer's btf_shade_shadow gives it on a flat sample at relief 1. */
float btf__structure_vis(const uint32_t *horizon, size_t i, const double l[3]);
/* The exemplar under light divided by the relit shading (a + vis max(0, n.l)) /
 * (a + l_z) (held at 0.1 and above) and, with albedo, by the pattern. */
void btf__structure_divide(btf_image *img, const btf_model *m, const btf_structure_geom *g,
                           btf_dir light, int albedo, double *mean_shade);
/* Subspace k's cell from its remainder img (the exemplar after
 * btf__structure_divide, on the range map's grid), in the exemplar's own
 * pixels: explained[0] the share of img's variance it explains,
 * explained[1] the share of probe's (the remainder of the subspace's
 * member at the exemplar's view whose light is farthest from the
 * exemplar's; NULL: img's). When the first reaches BTF_CELLS_MIN_EXPLAINED
 * and the second BTF_CELLS_PROBE_MIN, img is divided by the cell and c
 * keeps it for k (docs/model.md, "Periodic cells"). */
btf_status btf__cells_fit(btf_image *img, const btf_image *probe, btf_cells *c, int k,
                          double explained[2], btf_error *err);
/* btf__fit_marginals with the Lab histogram of lab_img (the exemplar as
 * synthesis gives it before colour matching: with the albedo pattern). */
btf_status btf__fit_marginals_lab(const btf_image *img, const btf_image *lab_img, btf_model *m,
                                  int subspace, btf_error *err);

/* The file's codes (model_codes.c): a Lab value of channel c as a 16-bit
 * code and back (monotone; decode(code(v)) is what a file keeps of v); a
 * pair gain (docs/model.md "Pair gains") as log2 on a grid of 1/64 octave,
 * -128..127, and its value. */
unsigned btf__lab_code(int c, float v);
float btf__lab_decode(int c, unsigned code);
int btf__gain_code(float g);
float btf__gain_value(int q);
/* m->gain from the images' mean colours (btf_segmentation.means) and the
 * renderer's predicted ones (pred[pair * 3 + c]). */
btf_status btf__pair_gains(btf_model *m, const float *means, const double *pred, btf_error *err);

/* The horizon map of heights (w x hh, texel units; model/horizon.c,
 * src/render/btf_horizon.h): two words per texel; wrap 1 marches round the
 * torus (a quilted surface), 0 stops at the edges (the analysed sample). */
btf_status btf__horizon_map(const float *h, int w, int hh, int wrap, int threads,
                            uint32_t **out, btf_error *err);

/* The lattice of a periodic range map (model/structure_lattice.c): two
 * shortest independent offsets (x0, y0, x1, y1) at which its
 * autocorrelation peaks; 1 when found, else 0 and zeros. */
int btf__structure_lattice(const btf_model *m, int lattice[4]);

/* 1 when the bytes start like a CAR model file (the signature's stem, as
 * btf__rf_sniff for the reflectance field's; model_file.c). */
int btf__model_sniff(const unsigned char *data, size_t size);

#endif
