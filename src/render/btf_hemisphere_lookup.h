/*
 * btf__hemisphere_lookup.h -- the lookup of a local direction on a
 * triangulated direction set (Haindl & Filip 2007, section III, "BTF
 * Interpolation": the three measured directions enclosing a view or light
 * direction and their barycentric weights; angles as in Fig. 1). ONE text
 * shared by the C library (src/render/hemisphere.c, btf__hemisphere_lookup)
 * and the GPU render pass (GLSL 4.50), reading the flat arrays of
 * btf_hemisphere_table (render/render.h). The rules are in docs/render.md,
 * "Interpolation over the hemisphere".
 *
 * The arithmetic is float, each result BTF_PRECISE, in one written order.
 * Unlike btf_noise.h the lookup needs sqrt and division, whose last
 * bits GPU drivers do not pin down, so the two sides agree to a few ulp
 * (weights within ~1e-6), not bit for bit; where a point lies on an edge
 * shared by two triangles either side may pick either, and the weights
 * agree there.
 *
 * Table access goes through accessor macros, so that the same functions can
 * read C arrays or GLSL storage buffers. Every function takes a first
 * parameter `tab` of type BTF_HEMI_TABLE. On the C side BTF_HEMI_TABLE is
 * `const btf_hemisphere_table *` and the accessors read its arrays; a GLSL
 * shader defines, BEFORE including this file (after btf_noise.h's block is
 * chosen by BTF_GLSL or VULKAN):
 *
 *   #define BTF_HEMI_TABLE int            // e.g. 0: the views, 1: the lights
 *   #define BTF_HEMI_POINT(tab, i, k)     // float: points[2 * i + k]
 *   #define BTF_HEMI_TRIANGLE(tab, t, k)  // int: triangles[3 * t + k]
 *   #define BTF_HEMI_GRID(tab)            // int: grid
 *   #define BTF_HEMI_CELL_START(tab, c)   // int: cell_start[c]
 *   #define BTF_HEMI_CELL_TRI(tab, j)     // int: cell_tris[j]
 *   #define BTF_HEMI_N_HULL(tab)          // int: n_hull
 *   #define BTF_HEMI_HULL(tab, i)         // int: hull[i]
 *   #define BTF_HEMI_HULL_APEX(tab, i)    // int: hull_apex[i]
 *
 * typically as reads of std430 buffers with per-table offsets (two tables
 * concatenated, offsets in a uniform). The result is a btf_hemi_weights
 * struct; in GLSL it is declared here too.
 *
 * Keep this file in the common subset of C11 and GLSL 4.50 (the rules of
 * src/synth/btf_noise.h, except for the library calls named above, which
 * go through BTF_HEMI_SQRT): ASCII only, no pointers or
 * arrays in the shared part, no casts "(T)x" (BTF_HEMI_F2I, BTF_U2F-like
 * BTF_HEMI_I2F), float constants with the f suffix.
 */
#ifndef BTF_HEMISPHERE_LOOKUP_H
#define BTF_HEMISPHERE_LOOKUP_H

#include "btf_noise.h" /* BTF_FN, BTF_PRECISE, btf_vec2, BTF_VEC2 */

#if defined(BTF_GLSL) || defined(VULKAN) || defined(GL_core_profile) || defined(GL_ES)
/* ------------------------------------------------------------------ GLSL */
#define BTF_HEMI_SQRT(x) sqrt(x)
#define BTF_HEMI_F2I(f) int(f)
#define BTF_HEMI_I2F(i) float(i)
struct btf_hemi_weights {
    int i0, i1, i2;
    float w0, w1, w2;
};
#define BTF_HEMI_WEIGHTS(a, b, c, x, y, z) btf_hemi_weights(a, b, c, x, y, z)

#else
/* --------------------------------------------------------------------- C */
#include <math.h>
#include "btfcar.h"
#include "render/render.h" /* btf_hemisphere_table */

#define BTF_HEMI_SQRT(x) sqrtf(x)
#define BTF_HEMI_F2I(f) ((int)(f))
#define BTF_HEMI_I2F(i) ((float)(i))
typedef struct btf_hemi_weights {
    int i0, i1, i2;
    float w0, w1, w2;
} btf_hemi_weights;
static inline btf_hemi_weights btf_make_hemi_weights(int a, int b, int c, float x, float y,
                                                     float z)
{
    btf_hemi_weights r = {a, b, c, x, y, z};
    return r;
}
#define BTF_HEMI_WEIGHTS(a, b, c, x, y, z) btf_make_hemi_weights(a, b, c, x, y, z)
#define BTF_HEMI_TABLE const btf_hemisphere_table *
#define BTF_HEMI_POINT(tab, i, k) ((tab)->points[2 * (i) + (k)])
#define BTF_HEMI_TRIANGLE(tab, t, k) ((int)(tab)->triangles[3 * (t) + (k)])
#define BTF_HEMI_GRID(tab) ((tab)->grid)
#define BTF_HEMI_CELL_START(tab, c) ((int)(tab)->cell_start[c])
#define BTF_HEMI_CELL_TRI(tab, j) ((int)(tab)->cell_tris[j])
#define BTF_HEMI_N_HULL(tab) ((tab)->n_hull)
#define BTF_HEMI_HULL(tab, i) ((int)(tab)->hull[i])
#define BTF_HEMI_HULL_APEX(tab, i) ((int)(tab)->hull_apex[i])
#endif

/* ============================================== shared part: C and GLSL */

/* A point belongs to a triangle when its smallest barycentric weight is at
 * least -BTF_HEMI_INSIDE_EPS: well above the float rounding of the weights
 * (~1e-6 for triangles of the sets the project knows), so no point inside
 * the hull is ever lost, and small enough that the clamped weights of a
 * point just outside differ from the hull rule's by at most ~1e-5. */
#define BTF_HEMI_INSIDE_EPS 1e-5f
/* Larger components are taken as non-finite (NaN fails every comparison). */
#define BTF_HEMI_FLT_BIG 3.0e38f

BTF_FN float btf_hemi_abs(float a)
{
    return a < 0.0f ? -a : a;
}

/* The projection of local direction (vx, vy, vz) to the unit disk:
 * Lambert's azimuthal equal-area projection scaled so that the horizon is
 * the unit circle, radius sqrt(1 - cos theta) along azimuph phi. For a
 * vector of length L that is (vx, vy) / sqrt(L (L + vz)): two square roots
 * and no arc tangent (the lookup runs twice per pixel per light). theta is
 * clamped to 90 degrees at and below the horizon (vz taken as 0). Zero or
 * non-finite vectors: the pole; straight down (no azimuth): the horizon at
 * phi = 0. The vector is first divided by its largest component, so no
 * length overflows or underflows the squares. */
BTF_FN btf_vec2 btf_hemi_project(float vx, float vy, float vz)
{
    float ax = btf_hemi_abs(vx);
    float ay = btf_hemi_abs(vy);
    float az = btf_hemi_abs(vz);
    float m = ax > ay ? ax : ay;
    m = m > az ? m : az;
    if (!(m > 0.0f) || !(m <= BTF_HEMI_FLT_BIG))
        return BTF_VEC2(0.0f, 0.0f);
    BTF_PRECISE float a = vx / m;
    BTF_PRECISE float b = vy / m;
    BTF_PRECISE float c = vz / m;
    c = c > 0.0f ? c : 0.0f;
    BTF_PRECISE float aa = a * a;
    BTF_PRECISE float bb = b * b;
    BTF_PRECISE float rr = aa + bb;
    if (!(rr > 0.0f))
        return vz >= 0.0f ? BTF_VEC2(0.0f, 0.0f) : BTF_VEC2(1.0f, 0.0f);
    BTF_PRECISE float cc = c * c;
    BTF_PRECISE float ll = rr + cc;
    BTF_PRECISE float l = BTF_HEMI_SQRT(ll);
    BTF_PRECISE float lc = l + c;
    BTF_PRECISE float q = l * lc;
    BTF_PRECISE float d = BTF_HEMI_SQRT(q);
    BTF_PRECISE float x = a / d;
    BTF_PRECISE float y = b / d;
    return BTF_VEC2(x, y);
}

/* Twice the signed area of (p, q, r): > 0 counter-clockwise. */
BTF_FN float btf_hemi_cross(float px, float py, float qx, float qy, float rx, float ry)
{
    BTF_PRECISE float ux = qx - px;
    BTF_PRECISE float uy = qy - py;
    BTF_PRECISE float wx = rx - px;
    BTF_PRECISE float wy = ry - py;
    BTF_PRECISE float a = ux * wy;
    BTF_PRECISE float b = uy * wx;
    BTF_PRECISE float d = a - b;
    return d;
}

/* The barycentric weights of (x, y) in triangle t, unclamped, as edge
 * functions not yet divided by their sum s (twice the triangle's area):
 * each is measured from the start of the edge opposite its vertex, so at a
 * vertex the two others are exactly 0. The caller divides by their sum
 * (btf_hemi_normalise) only for the triangle it keeps. */
BTF_FN btf_hemi_weights btf_hemi_edges(BTF_HEMI_TABLE tab, int t, float x, float y)
{
    int i0 = BTF_HEMI_TRIANGLE(tab, t, 0);
    int i1 = BTF_HEMI_TRIANGLE(tab, t, 1);
    int i2 = BTF_HEMI_TRIANGLE(tab, t, 2);
    float ax = BTF_HEMI_POINT(tab, i0, 0);
    float ay = BTF_HEMI_POINT(tab, i0, 1);
    float bx = BTF_HEMI_POINT(tab, i1, 0);
    float by = BTF_HEMI_POINT(tab, i1, 1);
    float cx = BTF_HEMI_POINT(tab, i2, 0);
    float cy = BTF_HEMI_POINT(tab, i2, 1);
    BTF_PRECISE float e0 = btf_hemi_cross(bx, by, cx, cy, x, y);
    BTF_PRECISE float e1 = btf_hemi_cross(cx, cy, ax, ay, x, y);
    BTF_PRECISE float e2 = btf_hemi_cross(ax, ay, bx, by, x, y);
    return BTF_HEMI_WEIGHTS(i0, i1, i2, e0, e1, e2);
}

/* The edge functions divided by their sum; the weights of t. */
BTF_FN btf_hemi_weights btf_hemi_normalise(btf_hemi_weights r)
{
    BTF_PRECISE float s01 = r.w0 + r.w1;
    BTF_PRECISE float s = s01 + r.w2;
    BTF_PRECISE float w0 = r.w0 / s;
    BTF_PRECISE float w1 = r.w1 / s;
    BTF_PRECISE float w2 = r.w2 / s;
    return BTF_HEMI_WEIGHTS(r.i0, r.i1, r.i2, w0, w1, w2);
}

/* The barycentric weights of (x, y) in triangle t, unclamped. */
BTF_FN btf_hemi_weights btf_hemi_barycentric(BTF_HEMI_TABLE tab, int t, float x, float y)
{
    return btf_hemi_normalise(btf_hemi_edges(tab, t, x, y));
}

BTF_FN float btf_hemi_min3(float a, float b, float c)
{
    float m = a < b ? a : b;
    return m < c ? m : c;
}

/* Negative weights (rounding, or a point within the inside epsilon outside)
 * to 0, the rest scaled to sum 1. */
BTF_FN btf_hemi_weights btf_hemi_clamp(btf_hemi_weights r)
{
    float w0 = r.w0 > 0.0f ? r.w0 : 0.0f;
    float w1 = r.w1 > 0.0f ? r.w1 : 0.0f;
    float w2 = r.w2 > 0.0f ? r.w2 : 0.0f;
    BTF_PRECISE float s01 = w0 + w1;
    BTF_PRECISE float s = s01 + w2;
    /* s >= 1 up to rounding: only negative weights were dropped. */
    BTF_PRECISE float q0 = w0 / s;
    BTF_PRECISE float q1 = w1 / s;
    BTF_PRECISE float q2 = w2 / s;
    return BTF_HEMI_WEIGHTS(r.i0, r.i1, r.i2, q0, q1, q2);
}

/* The hull rule: the nearest point of the hull's boundary (a convex polygon,
 * so the nearest point moves continuously with (x, y)); weights 1 - u and u
 * on the edge's ends and 0 on the apex of the triangle that owns the edge.
 * The nearest point is found structurally, not by comparing distances
 * (which near a vertex differ by O(u^2) and would let rounding pick a point
 * O(sqrt(ulp)) away): a point outside an edge's line whose foot falls on
 * the edge has that foot as its nearest point; otherwise (a vertex's
 * region, or rounding inside the hull) the nearest of the edges' clamped
 * feet, the first on a tie (at a vertex both give the same weights). */
BTF_FN btf_hemi_weights btf_hemi_hull_rule(BTF_HEMI_TABLE tab, float x, float y)
{
    int n = BTF_HEMI_N_HULL(tab);
    int best = -1;
    float best_u = 0.0f;
    /* The edge whose outer strip holds the point (at most one, convex). */
    for (int i = 0; i < n; i++) {
        int ia = BTF_HEMI_HULL(tab, i);
        int ib = BTF_HEMI_HULL(tab, i + 1 < n ? i + 1 : 0);
        float ax = BTF_HEMI_POINT(tab, ia, 0);
        float ay = BTF_HEMI_POINT(tab, ia, 1);
        BTF_PRECISE float ex = BTF_HEMI_POINT(tab, ib, 0) - ax;
        BTF_PRECISE float ey = BTF_HEMI_POINT(tab, ib, 1) - ay;
        BTF_PRECISE float px = x - ax;
        BTF_PRECISE float py = y - ay;
        BTF_PRECISE float epy = ex * py;
        BTF_PRECISE float epx = ey * px;
        BTF_PRECISE float side = epy - epx; /* < 0: outside this edge */
        if (!(side < 0.0f))
            continue;
        BTF_PRECISE float pex = px * ex;
        BTF_PRECISE float pey = py * ey;
        BTF_PRECISE float pe = pex + pey;
        BTF_PRECISE float exx = ex * ex;
        BTF_PRECISE float eyy = ey * ey;
        BTF_PRECISE float ee = exx + eyy;
        if (pe >= 0.0f && pe <= ee) {
            BTF_PRECISE float u = pe / ee;
            best = i;
            best_u = u < 1.0f ? u : 1.0f;
            break;
        }
    }
    /* Otherwise: the nearest of the edges' clamped feet. */
    float best_d = 3.0e38f;
    int fallback = best < 0 ? n : 0;
    for (int i = 0; i < fallback; i++) {
        int ia = BTF_HEMI_HULL(tab, i);
        int ib = BTF_HEMI_HULL(tab, i + 1 < n ? i + 1 : 0);
        float ax = BTF_HEMI_POINT(tab, ia, 0);
        float ay = BTF_HEMI_POINT(tab, ia, 1);
        BTF_PRECISE float ex = BTF_HEMI_POINT(tab, ib, 0) - ax;
        BTF_PRECISE float ey = BTF_HEMI_POINT(tab, ib, 1) - ay;
        BTF_PRECISE float px = x - ax;
        BTF_PRECISE float py = y - ay;
        BTF_PRECISE float exx = ex * ex;
        BTF_PRECISE float eyy = ey * ey;
        BTF_PRECISE float ee = exx + eyy;
        BTF_PRECISE float pex = px * ex;
        BTF_PRECISE float pey = py * ey;
        BTF_PRECISE float pe = pex + pey;
        BTF_PRECISE float u = pe / ee;
        u = u > 0.0f ? u : 0.0f;
        u = u < 1.0f ? u : 1.0f;
        BTF_PRECISE float uex = u * ex;
        BTF_PRECISE float uey = u * ey;
        BTF_PRECISE float dx = px - uex;
        BTF_PRECISE float dy = py - uey;
        BTF_PRECISE float dxx = dx * dx;
        BTF_PRECISE float dyy = dy * dy;
        BTF_PRECISE float d = dxx + dyy;
        if (d < best_d) {
            best_d = d;
            best = i;
            best_u = u;
        }
    }
    int ja = BTF_HEMI_HULL(tab, best);
    int jb = BTF_HEMI_HULL(tab, best + 1 < n ? best + 1 : 0);
    BTF_PRECISE float wa = 1.0f - best_u;
    return BTF_HEMI_WEIGHTS(ja, jb, BTF_HEMI_HULL_APEX(tab, best), wa, best_u, 0.0f);
}

/* The weights of a projected point (x, y): the first triangle of its grid
 * cell (in the cell's list, which is in triangle order) that contains it
 * (smallest weight >= 0), else the one whose smallest weight is largest;
 * if even that one's smallest weight is below -BTF_HEMI_INSIDE_EPS the
 * point is beyond the hull (or in a cell no triangle reaches), and the hull
 * rule applies. */
BTF_FN btf_hemi_weights btf_hemi_locate(BTF_HEMI_TABLE tab, float x, float y)
{
    int g = BTF_HEMI_GRID(tab);
    BTF_PRECISE float gh = BTF_HEMI_I2F(g) * 0.5f;
    BTF_PRECISE float x1 = x + 1.0f;
    BTF_PRECISE float y1 = y + 1.0f;
    BTF_PRECISE float fx = x1 * gh;
    BTF_PRECISE float fy = y1 * gh;
    /* Clamped before the conversion, so that truncation is the floor. */
    fx = fx > 0.0f ? fx : 0.0f;
    fy = fy > 0.0f ? fy : 0.0f;
    int cx = BTF_HEMI_F2I(fx < BTF_HEMI_I2F(g - 1) ? fx : BTF_HEMI_I2F(g - 1));
    int cy = BTF_HEMI_F2I(fy < BTF_HEMI_I2F(g - 1) ? fy : BTF_HEMI_I2F(g - 1));
    int c = cy * g + cx;
    int j0 = BTF_HEMI_CELL_START(tab, c);
    int j1 = BTF_HEMI_CELL_START(tab, c + 1);
    btf_hemi_weights best = BTF_HEMI_WEIGHTS(0, 0, 0, 1.0f, 0.0f, 0.0f);
    float best_m = -3.0e38f;
    for (int j = j0; j < j1; j++) {
        btf_hemi_weights r = btf_hemi_edges(tab, BTF_HEMI_CELL_TRI(tab, j), x, y);
        BTF_PRECISE float s01 = r.w0 + r.w1;
        BTF_PRECISE float s = s01 + r.w2;
        /* A sliver whose float area is not positive is skipped. */
        if (!(s > 0.0f))
            continue;
        BTF_PRECISE float e = btf_hemi_min3(r.w0, r.w1, r.w2);
        BTF_PRECISE float m = e / s;
        if (m > best_m) {
            best_m = m;
            best = r;
        }
        /* Inside or on an edge: no other triangle does better (a neighbour
         * sharing the edge ties at 0), so the first one found is kept. */
        if (m >= 0.0f)
            break;
    }
    best = btf_hemi_normalise(best);
    if (best_m >= -BTF_HEMI_INSIDE_EPS)
        return btf_hemi_clamp(best);
    return btf_hemi_hull_rule(tab, x, y);
}

/* The three measured directions enclosing local direction (vx, vy, vz) and
 * their weights (>= 0, summing to 1). */
BTF_FN btf_hemi_weights btf_hemi_lookup(BTF_HEMI_TABLE tab, float vx, float vy, float vz)
{
    btf_vec2 p = btf_hemi_project(vx, vy, vz);
    return btf_hemi_locate(tab, p.x, p.y);
}

#endif /* BTF_HEMISPHERE_LOOKUP_H */
