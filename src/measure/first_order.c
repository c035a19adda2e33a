/*
 * first_order.c — component (b) of the texture distance (docs/measure.md,
 * "First order"): how far the colour histograms are, ignoring where the
 * pixels are. Per CIE Lab channel, the earth mover's distance between the
 * two images' value distributions, which in one dimension is exact and
 * needs no binning: W1 = integral over u in [0, 1] of |Qa(u) - Qb(u)|, Q
 * the quantile function (the sorted values). Its unit is the channel's own
 * (L*, a*, b*: about one just noticeable difference), and it is the mean
 * colour shift for a shifted image. Shuffling pixels leaves it 0.
 */
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

void ms_sort_channels(const ms_view *v, float *sorted[3])
{
    for (int c = 0; c < 3; c++) {
        size_t i = 0;
        for (int y = 0; y < v->h; y++)
            for (int x = 0; x < v->w; x++)
                sorted[c][i++] = v->lab[MS_CH * ((size_t)(v->y0 + y) * v->stride + v->x0 + x) + c];
        qsort(sorted[c], i, sizeof(float), cmp_float);
    }
}

/* Walks the two step quantile functions together: value a[i] holds on
 * u in [i/na, (i+1)/na), b[j] on [j/nb, (j+1)/nb). Breakpoints are compared
 * as (i+1)*nb against (j+1)*na, in integers, so equal samples of equal
 * counts give exactly 0. */
double ms_emd_1d(const float *a, size_t na, const float *b, size_t nb)
{
    size_t i = 0, j = 0;
    double u = 0.0, acc = 0.0;
    while (i < na && j < nb) {
        unsigned long long ea = (unsigned long long)(i + 1) * nb;
        unsigned long long eb = (unsigned long long)(j + 1) * na;
        double next = ea <= eb ? (double)(i + 1) / na : (double)(j + 1) / nb;
        acc += (next - u) * fabs((double)a[i] - (double)b[j]);
        u = next;
        if (ea <= eb)
            i++;
        if (eb <= ea)
            j++;
    }
    return acc;
}

double ms_first_order_distance(const ms_desc *a, const ms_desc *b, double per_channel[3])
{
    double sum = 0.0;
    for (int c = 0; c < 3; c++) {
        double d = ms_emd_1d(a->sorted[c], a->n, b->sorted[c], b->n);
        if (per_channel)
            per_channel[c] = d;
        sum += d;
    }
    return sum / 3.0;
}
