/*
 * rf_cut.c — the minimum-error boundary cut of image quilting (Efros &
 * Freeman 2001, "Image quilting for texture synthesis and transfer",
 * section 2.1; the synthesis Meseth, Müller & Klein 2003, section 6, cite
 * as reference 6): where a new block overlaps what is already placed, the
 * seam follows the path of least cumulative squared difference through
 * the overlap (dynamic programming, each step to one of the three
 * neighbours in the next row), instead of the straight block edge, so that
 * the texture's own structures carry across it. A block overlapping on
 * several sides gets a cut on each (on a torus the last block of a row
 * also overlaps the row's first, on its right); it covers what lies inside
 * all of them. Ties go to the smaller index, so the cut is deterministic.
 */
#include "rf/rf_sample.h"

/* The least-cost path through the first `span` columns of a rows x cols
 * cost grid (cost(r, c) = e[r * rs + c * cs]) from row 0 to the last;
 * path[r] its column. acc: rows * span doubles. */
static void min_path(const double *e, int rows, int span, int rs, int cs, double *acc,
                     int *path)
{
    for (int c = 0; c < span; c++)
        acc[c] = e[c * cs];
    for (int r = 1; r < rows; r++)
        for (int c = 0; c < span; c++) {
            const double *prev = acc + (size_t)(r - 1) * span;
            double m = prev[c];
            if (c > 0 && prev[c - 1] < m)
                m = prev[c - 1];
            if (c + 1 < span && prev[c + 1] < m)
                m = prev[c + 1];
            acc[(size_t)r * span + c] = e[(size_t)r * rs + (size_t)c * cs] + m;
        }
    const double *last = acc + (size_t)(rows - 1) * span;
    int best = 0;
    for (int c = 1; c < span; c++)
        if (last[c] < last[best])
            best = c;
    path[rows - 1] = best;
    for (int r = rows - 1; r > 0; r--) {
        const double *prev = acc + (size_t)(r - 1) * span;
        int c = path[r], pick = c;
        if (c > 0 && prev[c - 1] < prev[pick])
            pick = c - 1;
        if (c + 1 < span && prev[c + 1] < prev[pick])
            pick = c + 1;
        path[r - 1] = pick;
    }
}

void rf_cut(const double *e, int bw, int bh, const int ov[4], unsigned char *take,
            double *scratch, int *path)
{
    int *pl = path, *pr = path + bh, *pt = path + 2 * bh, *pb = path + 2 * bh + bw;
    int left = ov[0] < bw ? ov[0] : bw, right = ov[2] < bw ? ov[2] : bw;
    int top = ov[1] < bh ? ov[1] : bh, bottom = ov[3] < bh ? ov[3] : bh;
    if (left > 0)
        min_path(e, bh, left, bw, 1, scratch, pl);
    if (right > 0) {
        min_path(e + (bw - right), bh, right, bw, 1, scratch, pr);
        for (int r = 0; r < bh; r++)
            pr[r] += bw - right;
    }
    if (top > 0)
        min_path(e, bw, top, 1, bw, scratch, pt);
    if (bottom > 0) {
        min_path(e + (size_t)(bh - bottom) * bw, bw, bottom, 1, bw, scratch, pb);
        for (int c = 0; c < bw; c++)
            pb[c] += bh - bottom;
    }
    for (int r = 0; r < bh; r++)
        for (int c = 0; c < bw; c++)
            take[(size_t)r * bw + c] = (left == 0 || c >= pl[r]) && (right == 0 || c <= pr[r]) &&
                                       (top == 0 || r >= pt[c]) && (bottom == 0 || r <= pb[c]);
}
