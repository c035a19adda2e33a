/*
 * delaunay.c -- the Delaunay triangulation of a projected direction set
 * (src/render/render.h): incremental insertion with Lawson flips, in double,
 * with distance tolerances so that the rings of a measured set (exactly
 * cocircular, and collinear along shared azimuths) give a triangulation
 * that depends on the set's order only, never on the last bits of the
 * projection.
 */
#include "render/render.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>

typedef struct dt {
    const double *xy;
    int n;
    int32_t (*tri)[3];
    int n_tri, cap_tri;
    int32_t *edge;    /* [n * n]: the triangle holding directed edge a -> b, or -1 */
    int32_t (*stack)[2];
    int n_stack;
} dt;

static const double *pt(const dt *d, int i)
{
    return d->xy + 2 * i;
}

/* Signed distance of p from the line a -> b (> 0: p on the left). */
static double side(const dt *d, int a, int b, int p)
{
    const double *A = pt(d, a), *B = pt(d, b), *P = pt(d, p);
    double ex = B[0] - A[0], ey = B[1] - A[1];
    return (ex * (P[1] - A[1]) - ey * (P[0] - A[0])) / hypot(ex, ey);
}

double btf__incircle(const double *a, const double *b, const double *c, const double *d,
                     double *bound)
{
    double adx = a[0] - d[0], ady = a[1] - d[1];
    double bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    double al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy;
    double m = fmax(al, fmax(bl, cl));
    *bound = m * m;
    return al * (bdx * cdy - cdx * bdy) + bl * (cdx * ady - adx * cdy) +
           cl * (adx * bdy - bdx * ady);
}

static void set_tri(dt *d, int t, int a, int b, int c)
{
    d->tri[t][0] = a;
    d->tri[t][1] = b;
    d->tri[t][2] = c;
    d->edge[a * d->n + b] = t;
    d->edge[b * d->n + c] = t;
    d->edge[c * d->n + a] = t;
}

static void clear_tri(dt *d, int t)
{
    for (int k = 0; k < 3; k++) {
        int a = d->tri[t][k], b = d->tri[t][(k + 1) % 3];
        if (d->edge[a * d->n + b] == t)
            d->edge[a * d->n + b] = -1;
    }
}

static int third(const dt *d, int t, int a, int b)
{
    for (int k = 0; k < 3; k++)
        if (d->tri[t][k] != a && d->tri[t][k] != b)
            return d->tri[t][k];
    return -1;
}

/* Edge a -> b, whose triangle has apex p, is to be checked. The stack holds
 * at most every directed edge once per flip round; it is sized for 3 per
 * triangle plus the new ones and grown never: each flip pops one and pushes
 * two, so it is bounded by the triangles' edges (checked). */
static int push(dt *d, int a, int b, int cap)
{
    if (d->n_stack >= cap)
        return -1;
    d->stack[d->n_stack][0] = a;
    d->stack[d->n_stack][1] = b;
    d->n_stack++;
    return 0;
}

/* Lawson's flips around new point p: an edge whose opposite vertex lies
 * strictly inside the circumcircle of (a, b, p) is replaced by the other
 * diagonal of the quadrilateral; ties (cocircular) are kept. */
static int legalize(dt *d, int p, int cap)
{
    while (d->n_stack > 0) {
        d->n_stack--;
        int a = d->stack[d->n_stack][0], b = d->stack[d->n_stack][1];
        int t = d->edge[a * d->n + b];
        if (t < 0 || third(d, t, a, b) != p)
            continue;
        int s = d->edge[b * d->n + a];
        if (s < 0)
            continue; /* a hull edge */
        int q = third(d, s, b, a);
        double bound;
        double in = btf__incircle(pt(d, a), pt(d, b), pt(d, p), pt(d, q), &bound);
        if (!(in > BTF_DELAUNAY_CIRCLE_EPS * bound))
            continue;
        clear_tri(d, t);
        clear_tri(d, s);
        set_tri(d, t, a, q, p);
        set_tri(d, s, q, b, p);
        if (push(d, a, q, cap) || push(d, q, b, cap))
            return -1;
    }
    return 0;
}

/* Inserts point p: inside a triangle (split in three), on an edge (the one
 * or two triangles beside it split in two each) or beyond the hull (joined
 * to every hull edge it sees). Returns 0, or -1 when p fits none of these
 * (a duplicate that escaped the check, or numerical trouble). */
static int insert(dt *d, int p, int cap)
{
    const double eps = BTF_DELAUNAY_LINE_EPS;
    d->n_stack = 0;
    for (int t = 0; t < d->n_tri; t++) {
        int v[3] = {d->tri[t][0], d->tri[t][1], d->tri[t][2]};
        double s[3];
        int on = 0, k_on = -1, out = 0;
        for (int k = 0; k < 3; k++) {
            /* s[k]: distance from the edge opposite vertex k. */
            s[k] = side(d, v[(k + 1) % 3], v[(k + 2) % 3], p);
            if (s[k] < -eps)
                out = 1;
            else if (s[k] <= eps) {
                on++;
                k_on = k;
            }
        }
        if (out)
            continue;
        if (on >= 2)
            return -1; /* on a vertex */
        if (on == 0) {
            int a = v[0], b = v[1], c = v[2];
            clear_tri(d, t);
            set_tri(d, t, a, b, p);
            set_tri(d, d->n_tri, b, c, p);
            set_tri(d, d->n_tri + 1, c, a, p);
            d->n_tri += 2;
            if (push(d, a, b, cap) || push(d, b, c, cap) || push(d, c, a, cap))
                return -1;
            return legalize(d, p, cap);
        }
        /* On edge a -> b (opposite c); u the triangle across it, if any. */
        int c = v[k_on], a = v[(k_on + 1) % 3], b = v[(k_on + 2) % 3];
        int u = d->edge[b * d->n + a];
        int q = u >= 0 ? third(d, u, b, a) : -1;
        clear_tri(d, t);
        if (u >= 0)
            clear_tri(d, u);
        set_tri(d, t, a, p, c);
        set_tri(d, d->n_tri++, p, b, c);
        if (push(d, c, a, cap) || push(d, b, c, cap))
            return -1;
        if (u >= 0) {
            set_tri(d, u, b, p, q);
            set_tri(d, d->n_tri++, p, a, q);
            if (push(d, q, b, cap) || push(d, a, q, cap))
                return -1;
        }
        return legalize(d, p, cap);
    }
    /* Beyond the hull: the hull edges a -> b that p sees (p on their right
     * by more than eps). Collinear extensions are not seen, so no flat
     * triangle is made. The triangles are added after the scan. */
    int n_old = d->n_tri, added = 0;
    for (int t = 0; t < n_old; t++)
        for (int k = 0; k < 3; k++) {
            int a = d->tri[t][k], b = d->tri[t][(k + 1) % 3];
            if (d->edge[b * d->n + a] >= 0 || side(d, a, b, p) >= -eps)
                continue;
            if (d->n_tri >= d->cap_tri)
                return -1;
            d->tri[d->n_tri][0] = b; /* recorded; the map is set below */
            d->tri[d->n_tri][1] = a;
            d->tri[d->n_tri][2] = p;
            d->n_tri++;
            added++;
        }
    if (added == 0)
        return -1;
    for (int t = n_old; t < d->n_tri; t++) {
        set_tri(d, t, d->tri[t][0], d->tri[t][1], d->tri[t][2]);
        if (push(d, d->tri[t][0], d->tri[t][1], cap))
            return -1;
    }
    return legalize(d, p, cap);
}

/* The first triangle: the farthest pair (i, j) and the point k farthest from
 * their line, each the first in set order within BTF_DELAUNAY_SAME_EPS of
 * the largest (a ring has many farthest pairs; the last bits must not
 * choose). Returns -1 when every point is within that of the line. */
static double dist(const dt *d, int a, int b)
{
    return hypot(pt(d, b)[0] - pt(d, a)[0], pt(d, b)[1] - pt(d, a)[1]);
}

static int first_triangle(const dt *d, int *i_out, int *j_out, int *k_out)
{
    const double tol = BTF_DELAUNAY_SAME_EPS;
    double best = 0.0;
    for (int a = 0; a < d->n; a++)
        for (int b = a + 1; b < d->n; b++)
            best = fmax(best, dist(d, a, b));
    int i = -1, j = -1, k = -1;
    for (int a = 0; a < d->n && i < 0; a++)
        for (int b = a + 1; b < d->n; b++)
            if (dist(d, a, b) >= best - tol) {
                i = a;
                j = b;
                break;
            }
    double far = 0.0;
    for (int c = 0; c < d->n; c++)
        far = fmax(far, fabs(side(d, i, j, c)));
    if (far <= tol)
        return -1;
    for (int c = 0; c < d->n && k < 0; c++)
        if (fabs(side(d, i, j, c)) >= far - tol)
            k = c;
    if (side(d, i, j, k) < 0.0) {
        int t = i;
        i = j;
        j = t;
    }
    *i_out = i;
    *j_out = j;
    *k_out = k;
    return 0;
}

/* The hull from the boundary edges (those without a twin), walked
 * counter-clockwise from the smallest point index that is on it. */
static btf_status walk_hull(const dt *d, const char *name, int32_t **hull, int32_t **apex,
                            int *n_hull, btf_error *err)
{
    int n = d->n;
    int32_t *next = btf__alloc((size_t)n, sizeof *next, err);
    int32_t *nexta = btf__alloc((size_t)n, sizeof *nexta, err);
    *hull = btf__alloc((size_t)n, sizeof **hull, err);
    *apex = btf__alloc((size_t)n, sizeof **apex, err);
    if (!next || !nexta || !*hull || !*apex) {
        BTF_FREE_ALL(next, nexta, *hull, *apex);
        *hull = *apex = NULL;
        return BTF_E_NOMEM;
    }
    for (int i = 0; i < n; i++)
        next[i] = -1;
    int edges = 0, start = -1;
    for (int t = 0; t < d->n_tri; t++)
        for (int k = 0; k < 3; k++) {
            int a = d->tri[t][k], b = d->tri[t][(k + 1) % 3];
            if (d->edge[b * n + a] >= 0)
                continue;
            next[a] = b;
            nexta[a] = d->tri[t][(k + 2) % 3];
            edges++;
            if (start < 0 || a < start)
                start = a;
        }
    int m = 0;
    for (int a = start; a >= 0 && m < n;) {
        (*hull)[m] = a;
        (*apex)[m] = nexta[a];
        m++;
        a = next[a];
        if (a == start)
            break;
    }
    free(next);
    free(nexta);
    if (start < 0 || m != edges || m < 3) {
        free(*hull);
        free(*apex);
        *hull = *apex = NULL;
        return btf__fail(err, BTF_E_NUMERIC, "%s: the triangulation's boundary is not one loop",
                         name);
    }
    *n_hull = m;
    return BTF_OK;
}

btf_status btf__delaunay(const double *xy, int n, const char *name, int32_t **tris, int *n_tris,
                         int32_t **hull, int32_t **hull_apex, int *n_hull, btf_error *err)
{
    *tris = NULL;
    *hull = *hull_apex = NULL;
    *n_tris = *n_hull = 0;
    dt d = {xy, n, NULL, 0, 0, NULL, NULL, 0};
    int i, j, k;
    if (first_triangle(&d, &i, &j, &k) != 0)
        return btf__fail(err, BTF_E_ARG,
                         "%s: all %d directions lie on one line after the projection "
                         "(one great circle through the pole): no triangle to interpolate in",
                         name, n);
    /* Euler: at most 2n - 5 triangles; every split adds at most 2. */
    int cap_tri = 2 * n + 4, cap_stack = 6 * cap_tri + 16;
    d.cap_tri = cap_tri;
    d.tri = btf__alloc((size_t)cap_tri, sizeof *d.tri, err);
    d.edge = btf__alloc((size_t)n * (size_t)n, sizeof *d.edge, err);
    d.stack = btf__alloc((size_t)cap_stack, sizeof *d.stack, err);
    btf_status st = BTF_OK;
    if (!d.tri || !d.edge || !d.stack) {
        st = BTF_E_NOMEM;
        goto done;
    }
    for (size_t e = 0; e < (size_t)n * (size_t)n; e++)
        d.edge[e] = -1;
    set_tri(&d, 0, i, j, k);
    d.n_tri = 1;
    for (int p = 0; p < n; p++) {
        if (p == i || p == j || p == k)
            continue;
        if (d.n_tri + 2 > cap_tri || insert(&d, p, cap_stack) != 0) {
            st = btf__fail(err, BTF_E_NUMERIC,
                           "%s: direction %d could not be inserted into the triangulation", name,
                           p);
            goto done;
        }
    }
    st = walk_hull(&d, name, hull, hull_apex, n_hull, err);
    if (st != BTF_OK)
        goto done;
    *tris = (int32_t *)d.tri;
    *n_tris = d.n_tri;
    d.tri = NULL;
done:
    BTF_FREE_ALL(d.tri, d.edge, d.stack);
    return st;
}
