/*
 * order.c — order statistics of one pixel's samples for robust photometric
 * stereo (Haindl & Filip 2007, section II.B): the quantiles of the shadow
 * and trim rules and the median of the robust scale. A pixel has tens to a
 * few hundred samples and there are millions of pixels, so both routines
 * work in place and never allocate.
 */
#include "range/range.h"

/* Quickselect (Hoare's partition): the median of the residuals costs O(N)
 * per reweighting step, not a sort. */
double btf__select_kth(double *a, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        double pivot = a[lo + (hi - lo) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot)
                i++;
            while (a[j] > pivot)
                j--;
            if (i <= j) {
                double t = a[i];
                a[i] = a[j];
                a[j] = t;
                i++;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return a[k];
}

/* Shell sort with fixed gaps: the shadow rules need the whole order once
 * per pixel; n is small, and this sorts in place without qsort's call per
 * comparison. */
void btf__sort_small(double *a, int n)
{
    static const int gaps[] = {57, 23, 10, 4, 1};
    for (int g = 0; g < 5; g++) {
        int h = gaps[g];
        for (int i = h; i < n; i++) {
            double t = a[i];
            int j = i;
            for (; j >= h && a[j - h] > t; j -= h)
                a[j] = a[j - h];
            a[j] = t;
        }
    }
}
