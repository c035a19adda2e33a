/*
 * rf_interp.c — the four closest measured views of a view direction and
 * their weights (Meseth, Müller & Klein 2003, section 5.4): "we choose the
 * closest theta values from the existing measurement data. Next, for each
 * such theta, we determine the closest phi values. These four samples
 * determine the four closest measured view directions [...] The according
 * weights are computed via bilinear interpolation (please note that the
 * measured samples are non-uniformly spread)". The weights sum to 1 and
 * change continuously with the direction; at a measured view the weight
 * is 1 on that view.
 *
 * The direction set is ring by ring (theta ascending, phi ascending within
 * a ring), as every btf_dirset is. Above the last ring (theta past 75 in
 * ubo81) and below the first the nearest ring alone is used; a ring of one
 * direction (the pole) gives it both azimuth weights.
 */
#include "rf/rf.h"

#include <math.h>

#define RING_TOL 1e-6

/* The ring starting at view index `start`: its end (exclusive). */
static int ring_end(const btf_dirset *s, int start)
{
    int e = start + 1;
    while (e < s->count && fabs(s->dirs[e].theta - s->dirs[start].theta) < RING_TOL)
        e++;
    return e;
}

/* Within the ring [a, b): the two views around phi and the weight of the
 * second. */
static void ring_pair(const btf_dirset *s, int a, int b, double phi, int *i0, int *i1, double *t)
{
    int m = b - a;
    if (m == 1) {
        *i0 = *i1 = a;
        *t = 0.0;
        return;
    }
    phi = fmod(phi, 360.0);
    if (phi < 0.0)
        phi += 360.0;
    /* the last view whose phi <= phi, circularly (before the first: the last) */
    int j = b - 1;
    for (int k = a; k < b; k++)
        if (s->dirs[k].phi <= phi)
            j = k;
    int j1 = j + 1 < b ? j + 1 : a;
    double gap = fmod(s->dirs[j1].phi - s->dirs[j].phi + 360.0, 360.0);
    double off = fmod(phi - s->dirs[j].phi + 360.0, 360.0);
    if (gap <= 0.0) /* two views on one azimuth: cannot happen in a dirset */
        gap = 360.0;
    *i0 = j, *i1 = j1;
    *t = rf_clampd(off / gap, 0.0, 1.0);
}

void btf_rf_view_weights(const btf_dirset *views, btf_dir view, int idx[4], double w[4])
{
    for (int i = 0; i < 4; i++)
        idx[i] = 0, w[i] = 0.0;
    if (!views || views->count < 1)
        return;
    /* the rings around theta */
    int r0 = 0, r1 = -1;
    for (int a = 0; a < views->count; a = ring_end(views, a)) {
        if (views->dirs[a].theta <= view.theta)
            r0 = a;
        else {
            r1 = a;
            break;
        }
    }
    double wt = 0.0;
    if (views->dirs[r0].theta > view.theta) /* below the first ring */
        r1 = -1;
    else if (r1 >= 0)
        wt = (view.theta - views->dirs[r0].theta) /
             (views->dirs[r1].theta - views->dirs[r0].theta);
    double t0, t1 = 0.0;
    ring_pair(views, r0, ring_end(views, r0), view.phi, &idx[0], &idx[1], &t0);
    if (r1 >= 0)
        ring_pair(views, r1, ring_end(views, r1), view.phi, &idx[2], &idx[3], &t1);
    else
        idx[2] = idx[0], idx[3] = idx[1];
    w[0] = (1.0 - wt) * (1.0 - t0);
    w[1] = (1.0 - wt) * t0;
    w[2] = wt * (1.0 - t1);
    w[3] = wt * t1;
}
