/*
 * rf_sample.h — what the files of the memory reduction share (Meseth,
 * Müller & Klein 2003, section 6; docs/rf.md, "Memory reduction"): the
 * representative image (rf_feature.c), the choice of the sample
 * (rf_sample.c) and the synthesis of the coordinate map by image quilting
 * (rf_quilt.c, rf_cut.c), put together by btf_rf_fit_sampled
 * (rf_sampled.c). Private to the library (and the tests).
 */
#ifndef BTF_RF_SAMPLE_H
#define BTF_RF_SAMPLE_H

#include "btfcar.h"
#include "core/core.h"

#include <stdint.h>

/* Channels of the representative image. */
#define RF_FEATURES 3

/* rf_feature.c: the representative image of the dataset, width x height x
 * RF_FEATURES floats (*out, malloc'd): per texel the head-on view's
 * Lambertian fit b = rho n over its lights (least squares, Woodham's
 * photometric stereo). *view: the view used (the smallest theta). */
btf_status rf_feature_image(const btf_dataset *ds, int threads, float **out, int *view,
                            btf_error *err);

/* rf_sample.c: the sw x sh window of the width x height representative
 * image whose channels' means and spreads are closest to the whole
 * image's (the first in row-major order on ties) into (*x, *y). */
btf_status rf_sample_choose(const float *feat, int width, int height, int sw, int sh, int *x,
                            int *y, btf_error *err);

/* rf_quilt.c: image quilting (Efros & Freeman 2001) of a surface of
 * q->surface_w x q->surface_h texels from the sample, the window
 * (q->sx, q->sy, q->sw, q->sh) of the representative image feat (stride
 * q->feat_w texels): map[2 (y surface_w + x) + {0, 1}] the sample texel
 * of each surface texel. The surface's texels under the sample's own place
 * (q->sx, q->sy) map to themselves and are never overwritten; every other
 * block is chosen by its overlap error with what is already there, drawn
 * among those within (1 + tolerance) of the best, and joined along the
 * minimum-error boundary cut (rf_cut.c). */
typedef struct rf_quilt_args {
    const float *feat;
    int feat_w;
    int sx, sy, sw, sh;
    int surface_w, surface_h;
    int block, overlap;      /* resolved: 1 <= block <= min(sw, sh), 0 <= overlap <= block / 2 */
    double tolerance;
    uint64_t seed;
    int threads;
    /* 0: every position of the sample is a candidate; n > 0: n positions
     * drawn (seeded) per block, which bounds the work on large surfaces
     * (the structure map, render/structure_map.c) */
    int candidates;
    /* With drawn candidates: two lattice vectors (x0, y0, x1, y1; all 0:
     * none). Each drawn position is moved to the nearest one whose offset
     * from the block's own place in the sample is a lattice vector, so a
     * periodic structure stays in step across the joints
     * (model/structure_lattice.c). */
    int lattice[4];
} rf_quilt_args;
btf_status rf_quilt(const rf_quilt_args *q, uint16_t *map, btf_error *err);

/* rf_cut.c: the minimum-error boundary cuts of one block (Efros & Freeman
 * 2001, section 2.1): e[bh * bw] the squared feature difference between
 * what is there and the new block (0 where nothing is). ov: the overlaps
 * on the left, top, right and bottom (columns or rows; 0: none). Through
 * each a path of least cumulative error across the block; take[bh * bw]
 * is 1 where the new block goes: on the inner side of every path (the
 * paths included). scratch: bw * bh doubles; path: 2 (bw + bh) ints. */
void rf_cut(const double *e, int bw, int bh, const int ov[4], unsigned char *take,
            double *scratch, int *path);

#endif
