/*
 * structure_lattice.c — the lattice of a periodic structure (a weave's
 * repeat): two shortest independent offsets at which the range map's
 * autocorrelation peaks. The structure map's quilting then draws only
 * blocks whose offset from the sample's own place is a lattice vector
 * (model/structure_map.c, src/rf/rf_quilt.c), so a weave enlarged by
 * quilting keeps its threads in step across every block joint instead of
 * jumping by a fraction of a repeat at each cut (docs/model.md, "Lattice").
 *
 * The autocorrelation is the inverse DFT of the power spectrum
 * (Wiener-Khinchin) of each layer's periodic component (Moisan 2011, so
 * that the jumps between the sample's opposite borders add no false
 * peaks); a peak counts when it is a local maximum of at least
 * LATTICE_MIN_CORR of the zero-offset value and LATTICE_REL_CORR of the
 * strongest peak.
 */
#include "model/model.h"
#include "io/io.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LATTICE_MIN_CORR 0.5
#define LATTICE_REL_CORR 0.85
/* Offsets shorter than this are the peak at 0's own slope, not a repeat. */
#define LATTICE_MIN_LEN 3.0
/* The sample must hold this many repeats along each lattice vector. */
#define LATTICE_MIN_REPEATS 3.0

typedef struct peak {
    int dx, dy;
    double r, len;
} peak;

static int cmp_peak(const void *a, const void *b)
{
    const peak *p = a, *q = b;
    if (p->len != q->len)
        return p->len < q->len ? -1 : 1;
    if (p->r != q->r)
        return p->r > q->r ? -1 : 1;
    return p->dy != q->dy ? p->dy - q->dy : p->dx - q->dx;
}

/* The circular autocorrelation of one layer (the heights, or the albedo
 * pattern's log when log_of is set), mean-free, normalised by its value at
 * 0 (re receives it). */
static btf_status autocorrelation(const btf_model *m, const float *layer, int log_of, double *re,
                                  double *im, btf_error *err)
{
    int w = m->range_width, h = m->range_height;
    size_t n = (size_t)w * h;
    double mean = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += re[i] = log_of ? log(layer[i]) : layer[i];
    mean /= (double)n;
    for (size_t i = 0; i < n; i++)
        re[i] -= mean, im[i] = 0.0;
    btf_status rc = ms_periodic_component(re, w, h, err);
    char why[256];
    if (rc == BTF_OK && btfcv_dft2(re, im, w, h, 0, why, sizeof why) != 0)
        rc = btf__fail(err, BTF_E_UNSUPPORTED, "lattice: DFT failed: %s", why);
    for (size_t i = 0; rc == BTF_OK && i < n; i++)
        re[i] = re[i] * re[i] + im[i] * im[i], im[i] = 0.0;
    if (rc == BTF_OK && btfcv_dft2(re, im, w, h, 1, why, sizeof why) != 0)
        rc = btf__fail(err, BTF_E_UNSUPPORTED, "lattice: DFT failed: %s", why);
    if (rc == BTF_OK) {
        double r0 = re[0] > 0.0 ? re[0] : 1.0;
        for (size_t i = 0; i < n; i++)
            re[i] /= r0;
    }
    return rc;
}

/* The local maxima of r at or above the threshold, as signed offsets. */
static int find_peaks(const double *r, int w, int h, peak *out, int max)
{
    int n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double v = r[(size_t)y * w + x];
            if (v < LATTICE_MIN_CORR)
                continue;
            int top = 1;
            for (int j = -1; j <= 1 && top; j++)
                for (int i = -1; i <= 1 && top; i++) {
                    int xx = (x + i + w) % w, yy = (y + j + h) % h;
                    if ((i || j) && r[(size_t)yy * w + xx] > v)
                        top = 0;
                }
            int dx = x > w / 2 ? x - w : x, dy = y > h / 2 ? y - h : y;
            double len = sqrt((double)dx * dx + (double)dy * dy);
            if (!top || len < LATTICE_MIN_LEN || n == max)
                continue;
            out[n++] = (peak){dx, dy, v, len};
        }
    return n;
}

int btf__structure_lattice(const btf_model *m, int lattice[4])
{
    memset(lattice, 0, 4 * sizeof *lattice);
    /* (btf__structure_quilted's test, written out: that file calls this one) */
    if (!m || !m->range || m->range_texel != 1.0f || m->range_width < 1 || m->range_height < 1)
        return 0;
    int w = m->range_width, h = m->range_height;
    size_t n = (size_t)w * h;
    double *re = malloc(2 * n * sizeof *re), *im = malloc(n * sizeof *im);
    peak *pk = malloc(256 * sizeof *pk);
    btf_error e = {0};
    int found = 0;
    /* the heights' and the albedo's autocorrelations averaged: a plain
     * weave's threads all look alike in height, and only the albedo tells
     * the yarn on top (its repeat is diagonal) */
    if (re && im && pk && autocorrelation(m, m->range, 0, re, im, &e) == BTF_OK &&
        (!m->albedo || autocorrelation(m, m->albedo, 1, re + n, im, &e) == BTF_OK)) {
        for (size_t i = 0; m->albedo && i < n; i++)
            re[i] = 0.5 * (re[i] + re[n + i]);
        int np = find_peaks(re, w, h, pk, 256);
        /* a repeat is as strong as the strongest: a weaker peak is a
         * partial match (a plain weave shifted by one thread matches in
         * height, not in which yarn lies on top) */
        double top = 0.0;
        for (int i = 0; i < np; i++)
            top = pk[i].r > top ? pk[i].r : top;
        int kept = 0;
        for (int i = 0; i < np; i++)
            if (pk[i].r >= LATTICE_REL_CORR * top)
                pk[kept++] = pk[i];
        np = kept;
        qsort(pk, (size_t)np, sizeof *pk, cmp_peak);
        for (int i = 0; i < np && !found; i++)
            for (int j = i + 1; j < np && !found; j++) {
                double cross = (double)pk[i].dx * pk[j].dy - (double)pk[i].dy * pk[j].dx;
                /* independent: the pair spans a cell of at least half the
                 * square on the shorter vector */
                if (fabs(cross) < 0.5 * pk[i].len * pk[j].len)
                    continue;
                int side = w < h ? w : h;
                if (pk[j].len * LATTICE_MIN_REPEATS > side)
                    break;
                lattice[0] = pk[i].dx, lattice[1] = pk[i].dy;
                lattice[2] = pk[j].dx, lattice[3] = pk[j].dy;
                found = 1;
            }
    }
    BTF_FREE_ALL(re, im, pk);
    return found;
}
