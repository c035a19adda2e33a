/*
 * pareto.c — the Pareto-optimal subset of a set of points: the settings of
 * a sweep that no other setting beats on both axes at once (the report's
 * speed/accuracy plot joins them by a step line).
 */
#include "report/report.h"

#include <math.h>

/* a at least as good as b on both axes and better on one. */
static int dominates(double ax, double ay, double bx, double by, int xh, int yh)
{
    double dx = xh ? ax - bx : bx - ax; /* > 0: a better in x */
    double dy = yh ? ay - by : by - ay;
    return dx >= 0 && dy >= 0 && (dx > 0 || dy > 0);
}

int btf__pareto_front(const double *x, const double *y, int n, int x_higher_better,
                      int y_higher_better, int *idx)
{
    if (n <= 0 || !x || !y || !idx)
        return 0;
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(x[i]) || !isfinite(y[i]))
            continue;
        int beaten = 0;
        for (int j = 0; j < n && !beaten; j++)
            beaten = j != i && isfinite(x[j]) && isfinite(y[j]) &&
                     dominates(x[j], y[j], x[i], y[i], x_higher_better, y_higher_better);
        if (!beaten)
            idx[k++] = i;
    }
    /* Insertion sort by (x, y, index): the front is short, and this keeps
     * the call free of a comparison function's context. */
    for (int a = 1; a < k; a++) {
        int v = idx[a], b = a - 1;
        while (b >= 0 && (x[idx[b]] > x[v] || (x[idx[b]] == x[v] && y[idx[b]] > y[v])))
            idx[b + 1] = idx[b], b--;
        idx[b + 1] = v;
    }
    return k;
}
