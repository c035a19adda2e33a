/* test_hemisphere.c -- interpolation over the hemisphere (src/render/
 * hemisphere.c, delaunay.c, btf__hemisphere_lookup.h; docs/render.md): the
 * weight rules over thousands of random directions on ubo81, ubo151 and a
 * random custom set; measured directions, pole, edges, vertices, the hull
 * boundary and below the horizon; the grid against a brute-force search;
 * Delaunay validity, coverage, independence from floating noise; bad sets. */
#include "testutil.h"
#include "render/render.h"
#include "render/btf_hemisphere_lookup.h"
#include "hemisphere_check_spv.h" /* gpu/hemisphere_check.comp: the lookup as GLSL */
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
#define N_RANDOM 4000

/* xorshift64*: the test's own deterministic random numbers. */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct fixture {
    btf_dirset set;
    btf_hemisphere *h;
    btf_hemisphere_table t;
    double *xy; /* the set projected in double */
    double outer; /* the largest projected radius */
} fixture;

static void project_d(double theta, double phi, double *x, double *y)
{
    double r = sqrt(1.0 - cos(theta * PI / 180.0)); /* btf_hemi_project */
    *x = r * cos(phi * PI / 180.0);
    *y = r * sin(phi * PI / 180.0);
}

/* The direction whose projection is (x, y) (|(x, y)| <= 1). */
static void unproject(double x, double y, float v[3])
{
    /* r = sqrt(1 - cos theta) (btf_hemi_project), so cos theta = 1 - r^2 */
    double r = hypot(x, y), th = acos(fmax(-1.0, 1.0 - r * r)), ph = atan2(y, x);
    v[0] = (float)(sin(th) * cos(ph));
    v[1] = (float)(sin(th) * sin(ph));
    v[2] = (float)cos(th);
}

static void random_custom(btf_dirset *s)
{
    btf_dir d[64];
    for (int i = 0; i < 60; i++) {
        d[i].theta = 88.0 * urand();
        d[i].phi = 360.0 * urand();
    }
    d[60] = (btf_dir){90.0, 10.0};
    d[61] = (btf_dir){90.0, 200.0};
    btf_error e = {0};
    TU_OK(btf_dirset_from_list(s, d, 62, &e), &e);
}

static void fixture_open(fixture *f, int which)
{
    btf_error e = {0};
    memset(f, 0, sizeof *f);
    if (which == 0)
        TU_OK(btf_dirset_ubo81(&f->set, &e), &e);
    else if (which == 1)
        TU_OK(btf__dirset_ubo151(&f->set, &e), &e);
    else
        random_custom(&f->set);
    TU_OK(btf_hemisphere_build(&f->set, &f->h, &e), &e);
    btf__hemisphere_get_table(f->h, &f->t);
    f->xy = malloc(sizeof(double) * 2 * (size_t)f->set.count);
    assert_non_null(f->xy);
    for (int i = 0; i < f->set.count; i++) {
        project_d(f->set.dirs[i].theta, f->set.dirs[i].phi, &f->xy[2 * i], &f->xy[2 * i + 1]);
        f->outer = fmax(f->outer, hypot(f->xy[2 * i], f->xy[2 * i + 1]));
    }
}

static void fixture_close(fixture *f)
{
    btf_hemisphere_free(f->h);
    btf_dirset_free(&f->set);
    free(f->xy);
}

/* The weights of v as a dense vector over the set (the interpolant). */
static void dense(const fixture *f, const float v[3], double *W)
{
    int idx[3];
    float w[3];
    btf__hemisphere_lookup(f->h, v, idx, w);
    for (int i = 0; i < f->set.count; i++)
        W[i] = 0.0;
    for (int k = 0; k < 3; k++) {
        assert_true(idx[k] >= 0 && idx[k] < f->set.count);
        assert_true(isfinite(w[k]) && w[k] >= -1e-6f);
        W[idx[k]] += w[k];
    }
    assert_true(fabs((double)w[0] + w[1] + w[2] - 1.0) <= 1e-5);
}

static double l1(const double *a, const double *b, int n)
{
    double s = 0.0;
    for (int i = 0; i < n; i++)
        s += fabs(a[i] - b[i]);
    return s;
}

/* Inside the hull (convex, counter-clockwise) up to tol? */
static int inside_hull(const fixture *f, double x, double y, double tol)
{
    for (int i = 0; i < f->t.n_hull; i++) {
        const double *a = f->xy + 2 * f->t.hull[i];
        const double *b = f->xy + 2 * f->t.hull[(i + 1) % f->t.n_hull];
        double ex = b[0] - a[0], ey = b[1] - a[1];
        if ((ex * (y - a[1]) - ey * (x - a[0])) / hypot(ex, ey) < -tol)
            return 0;
    }
    return 1;
}

/* The nearest point of the hull's boundary to (x, y). */
static void nearest_on_hull(const fixture *f, double x, double y, double *nx, double *ny)
{
    double best = INFINITY;
    for (int i = 0; i < f->t.n_hull; i++) {
        const double *a = f->xy + 2 * f->t.hull[i];
        const double *b = f->xy + 2 * f->t.hull[(i + 1) % f->t.n_hull];
        double ex = b[0] - a[0], ey = b[1] - a[1];
        double u = ((x - a[0]) * ex + (y - a[1]) * ey) / (ex * ex + ey * ey);
        u = fmin(1.0, fmax(0.0, u));
        double px = a[0] + u * ex, py = a[1] + u * ey, d = hypot(x - px, y - py);
        if (d < best) {
            best = d;
            *nx = px;
            *ny = py;
        }
    }
}

/* A random direction: upper hemisphere, beyond the outer ring or below the
 * horizon, at a random length from 1e-30 to 1e30. */
static void random_dir(const fixture *f, int kind, float v[3])
{
    double th, ph = 360.0 * urand();
    if (kind == 0)
        th = 90.0 * acos(urand()) / (PI / 2);
    else if (kind == 1)
        th = 90.0 * (f->outer + (1.0 - f->outer) * urand());
    else
        th = 90.0 + 90.0 * urand();
    double len = pow(10.0, -30.0 + 60.0 * urand());
    double t = th * PI / 180.0, p = ph * PI / 180.0;
    v[0] = (float)(len * sin(t) * cos(p));
    v[1] = (float)(len * sin(t) * sin(p));
    v[2] = (float)(len * cos(t));
}

static void weight_rules(void **state)
{
    (void)state;
    for (int which = 0; which < 3; which++) {
        fixture f;
        fixture_open(&f, which);
        int n = f.set.count, inside = 0, beyond = 0;
        double *W = malloc(sizeof(double) * (size_t)n);
        double worst_in = 0.0, worst_out = 0.0;
        for (int r = 0; r < 3 * N_RANDOM; r++) {
            float v[3];
            random_dir(&f, r % 3, v);
            dense(&f, v, W);
            btf_vec2 q = btf_hemi_project(v[0], v[1], v[2]);
            double sx = 0.0, sy = 0.0;
            for (int i = 0; i < n; i++) {
                sx += W[i] * f.xy[2 * i];
                sy += W[i] * f.xy[2 * i + 1];
            }
            double tx = q.x, ty = q.y;
            if (inside_hull(&f, q.x, q.y, 0.0)) {
                inside++;
                worst_in = fmax(worst_in, hypot(sx - tx, sy - ty));
            } else {
                beyond++;
                nearest_on_hull(&f, q.x, q.y, &tx, &ty);
                worst_out = fmax(worst_out, hypot(sx - tx, sy - ty));
            }
        }
        print_message("%s: %d triangles, hull %d, grid %d (%d entries); %d inside, %d beyond; "
                      "reproduction error %.2g inside, %.2g to the nearest hull point\n",
                      f.set.name, f.t.n_triangles, f.t.n_hull, f.t.grid, f.t.n_cell_tris, inside,
                      beyond, worst_in, worst_out);
        assert_true(inside > N_RANDOM / 2 && beyond > N_RANDOM);
        assert_true(worst_in <= 1e-5);
        assert_true(worst_out <= 1e-5);
        free(W);
        fixture_close(&f);
    }
}

static void measured_directions(void **state)
{
    (void)state;
    for (int which = 0; which < 3; which++) {
        fixture f;
        fixture_open(&f, which);
        double *W = malloc(sizeof(double) * (size_t)f.set.count);
        for (int i = 0; i < f.set.count; i++) {
            double d[3];
            btf_dir_to_vec(f.set.dirs[i], d);
            float v[3] = {(float)d[0], (float)d[1], (float)d[2]};
            dense(&f, v, W);
            assert_true(fabs(W[i] - 1.0) <= 1e-5);
        }
        free(W);
        fixture_close(&f);
    }
}

static void pole_and_degenerate_vectors(void **state)
{
    (void)state;
    fixture f;
    fixture_open(&f, 0);
    double W[81], P[81];
    /* ubo81 measures the pole (direction 0). */
    const float pole[3] = {0.0f, 0.0f, 1.0f};
    dense(&f, pole, P);
    assert_true(P[0] == 1.0);
    /* Zero, NaN, Inf and huge or subnormal lengths along the normal. */
    const float zero[3] = {0.0f, 0.0f, 0.0f}, nanv[3] = {NAN, 0.0f, 1.0f};
    const float infv[3] = {INFINITY, 1.0f, 1.0f}, big[3] = {0.0f, 0.0f, 3e38f};
    const float tiny[3] = {0.0f, 0.0f, 1e-44f};
    const float *poles[] = {zero, nanv, infv, big, tiny};
    for (int k = 0; k < 5; k++) {
        dense(&f, poles[k], W);
        assert_true(W[0] == 1.0);
    }
    /* Huge and subnormal components in general position: the same weights
     * as the unit vector. */
    const float unit[3] = {0.3f, -0.4f, 0.5f};
    double U[81];
    dense(&f, unit, U);
    const float scaled_big[3] = {0.3e38f, -0.4e38f, 0.5e38f};
    const float scaled_tiny[3] = {0.3e-40f, -0.4e-40f, 0.5e-40f};
    dense(&f, scaled_big, W);
    assert_true(l1(W, U, 81) <= 1e-5);
    dense(&f, scaled_tiny, W);
    assert_true(l1(W, U, 81) <= 1e-3); /* subnormals carry few digits */
    /* Straight down: the horizon at phi = 0; the horizon (z = 0) and below
     * give the theta = 90 weights of that azimuth. */
    const float down[3] = {0.0f, 0.0f, -1.0f}, east[3] = {1.0f, 0.0f, 0.0f};
    const float below[3] = {0.5f, 0.5f, -2.0f}, horizon[3] = {0.5f, 0.5f, 0.0f};
    dense(&f, down, W);
    dense(&f, east, U);
    assert_true(l1(W, U, 81) <= 1e-6);
    dense(&f, below, W);
    dense(&f, horizon, U);
    assert_true(l1(W, U, 81) <= 1e-6);
    /* Through the pole: the interpolant moves by a tiny amount. */
    for (int a = 0; a < 360; a += 7) {
        double c = cos(a * PI / 180.0), s = sin(a * PI / 180.0);
        const float v[3] = {(float)(1e-4 * c), (float)(1e-4 * s), 1.0f};
        dense(&f, v, W);
        assert_true(l1(W, P, 81) <= 2e-3);
    }
    fixture_close(&f);
}

/* Continuity: random small steps, steps across interior edges (from one
 * triangle to its neighbour) and across the hull boundary, and the weights
 * on an edge's midpoint and on a vertex. */
static void continuity_edges_and_hull(void **state)
{
    (void)state;
    const double step = 1e-5; /* projected units */
    for (int which = 0; which < 3; which++) {
        fixture f;
        fixture_open(&f, which);
        int n = f.set.count;
        double *A = malloc(sizeof(double) * (size_t)n), *B = malloc(sizeof(double) * (size_t)n);
        double worst = 0.0;
        float v[3];
        for (int r = 0; r < 2 * N_RANDOM; r++) {
            double x = 2.2 * urand() - 1.1, y = 2.2 * urand() - 1.1;
            if (hypot(x, y) > 1.0)
                continue;
            double a = 2 * PI * urand();
            unproject(x, y, v);
            dense(&f, v, A);
            unproject(fmin(1.0, x + step * cos(a)), y + step * sin(a), v);
            dense(&f, v, B);
            worst = fmax(worst, l1(A, B, n));
        }
        /* Across every edge at its midpoint, and the midpoint's weights. */
        double worst_edge = 0.0;
        for (int t = 0; t < f.t.n_triangles; t++)
            for (int k = 0; k < 3; k++) {
                int i = f.t.triangles[3 * t + k], j = f.t.triangles[3 * t + (k + 1) % 3];
                double mx = 0.5 * (f.xy[2 * i] + f.xy[2 * j]);
                double my = 0.5 * (f.xy[2 * i + 1] + f.xy[2 * j + 1]);
                double ex = f.xy[2 * j] - f.xy[2 * i], ey = f.xy[2 * j + 1] - f.xy[2 * i + 1];
                double len = hypot(ex, ey), nx = ey / len, ny = -ex / len; /* outward */
                unproject(mx, my, v);
                dense(&f, v, A);
                assert_true(fabs(A[i] - 0.5) <= 2e-3 && fabs(A[j] - 0.5) <= 2e-3);
                assert_true(A[i] + A[j] >= 1.0 - 1e-5);
                unproject(mx + step * nx, my + step * ny, v);
                dense(&f, v, B);
                unproject(mx - step * nx, my - step * ny, v);
                dense(&f, v, A);
                worst_edge = fmax(worst_edge, l1(A, B, n));
            }
        print_message("%s: largest L1 change of the weights for a step of %g: %.3g (random), "
                      "%.3g (across edges and the hull)\n",
                      f.set.name, step, worst, worst_edge);
        /* A jump (a discontinuity) would be of order 1; the bound is the
         * steepest triangle's gradient times the step, with a margin (the
         * random set has slivers). */
        double bound = which < 2 ? 2e-3 : 5e-2;
        assert_true(worst <= bound);
        assert_true(worst_edge <= bound);
        free(A);
        free(B);
        fixture_close(&f);
    }
}

/* A table with one cell holding every triangle: the brute-force search. */
static void grid_matches_brute_force(void **state)
{
    (void)state;
    for (int which = 0; which < 3; which++) {
        fixture f;
        fixture_open(&f, which);
        btf_hemisphere_table all = f.t;
        int32_t start[2] = {0, f.t.n_triangles};
        int32_t *tris = malloc(sizeof(int32_t) * (size_t)f.t.n_triangles);
        for (int t = 0; t < f.t.n_triangles; t++)
            tris[t] = t;
        all.grid = 1;
        all.cell_start = start;
        all.cell_tris = tris;
        all.n_cell_tris = f.t.n_triangles;
        int n = f.set.count;
        double *A = calloc((size_t)n, sizeof(double)), *B = calloc((size_t)n, sizeof(double));
        double worst = 0.0;
        for (int r = 0; r < 5 * N_RANDOM; r++) {
            float x = (float)(2.4 * urand() - 1.2), y = (float)(2.4 * urand() - 1.2);
            /* On a measured point and an edge too. */
            if (r % 10 == 0) {
                int i = (int)(urand() * n);
                x = f.t.points[2 * i];
                y = f.t.points[2 * i + 1];
            }
            btf_hemi_weights g = btf_hemi_locate(&f.t, x, y), b = btf_hemi_locate(&all, x, y);
            memset(A, 0, sizeof(double) * (size_t)n);
            memset(B, 0, sizeof(double) * (size_t)n);
            A[g.i0] += g.w0;
            A[g.i1] += g.w1;
            A[g.i2] += g.w2;
            B[b.i0] += b.w0;
            B[b.i1] += b.w1;
            B[b.i2] += b.w2;
            worst = fmax(worst, l1(A, B, n));
        }
        assert_true(worst <= 1e-6);
        free(A);
        free(B);
        free(tris);
        fixture_close(&f);
    }
}

static double area2(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

static void delaunay_valid_and_covering(void **state)
{
    (void)state;
    for (int which = 0; which < 3; which++) {
        fixture f;
        fixture_open(&f, which);
        double tri_area = 0.0, worst_in = 0.0;
        int n = f.set.count;
        int *used = calloc((size_t)n, sizeof(int));
        for (int t = 0; t < f.t.n_triangles; t++) {
            const int32_t *v = f.t.triangles + 3 * t;
            const double *a = f.xy + 2 * v[0], *b = f.xy + 2 * v[1], *c = f.xy + 2 * v[2];
            double s = area2(a, b, c);
            assert_true(s > 0.0); /* counter-clockwise, not flat */
            tri_area += 0.5 * s;
            for (int k = 0; k < 3; k++)
                used[v[k]] = 1;
            for (int p = 0; p < n; p++) {
                if (p == v[0] || p == v[1] || p == v[2])
                    continue;
                double bound, in = btf__incircle(a, b, c, f.xy + 2 * p, &bound);
                worst_in = fmax(worst_in, in / bound);
            }
        }
        double hull_area = 0.0;
        for (int i = 0; i < f.t.n_hull; i++) {
            const double *a = f.xy + 2 * f.t.hull[i];
            const double *b = f.xy + 2 * f.t.hull[(i + 1) % f.t.n_hull];
            const double *c = f.xy + 2 * f.t.hull[(i + 2) % f.t.n_hull];
            hull_area += 0.5 * (a[0] * b[1] - b[0] * a[1]);
            assert_true(area2(a, b, c) >= -1e-12); /* convex */
        }
        for (int p = 0; p < n; p++)
            assert_true(used[p]); /* every direction is a vertex */
        /* Euler: 2n - 2 - h triangles for n points, h on the hull. */
        assert_int_equal(f.t.n_triangles, 2 * n - 2 - f.t.n_hull);
        print_message("%s: no point inside a circumcircle beyond %.2g of the bound; "
                      "triangles cover %.12f of the hull's area %.12f\n",
                      f.set.name, worst_in, tri_area, hull_area);
        assert_true(worst_in <= 1e-9);
        assert_true(fabs(tri_area - hull_area) <= 1e-12);
        free(used);
        fixture_close(&f);
    }
}

/* Ties among cocircular ring points are broken by the set's order, not by
 * the last bits: noise of 1e-12 degree gives the very same table, and two
 * builds give the same bytes. */
static void independent_of_floating_noise(void **state)
{
    (void)state;
    for (int which = 0; which < 2; which++) {
        fixture f;
        fixture_open(&f, which);
        btf_dirset noisy;
        btf_error e = {0};
        TU_OK(btf__dirset_copy(&noisy, &f.set, &e), &e);
        for (int i = 0; i < noisy.count; i++) {
            noisy.dirs[i].theta = fmin(90.0, fmax(0.0, noisy.dirs[i].theta + 1e-12 * (urand() - 0.5)));
            noisy.dirs[i].phi += 1e-12 * (urand() - 0.5);
        }
        btf_hemisphere *h2;
        TU_OK(btf_hemisphere_build(&noisy, &h2, &e), &e);
        btf_hemisphere_table t2;
        btf__hemisphere_get_table(h2, &t2);
        assert_int_equal(t2.n_triangles, f.t.n_triangles);
        assert_memory_equal(t2.triangles, f.t.triangles, sizeof(int32_t) * 3 * (size_t)t2.n_triangles);
        assert_int_equal(t2.n_hull, f.t.n_hull);
        assert_memory_equal(t2.hull, f.t.hull, sizeof(int32_t) * (size_t)t2.n_hull);
        assert_int_equal(t2.n_cell_tris, f.t.n_cell_tris);
        assert_memory_equal(t2.cell_tris, f.t.cell_tris, sizeof(int32_t) * (size_t)t2.n_cell_tris);
        btf_hemisphere_free(h2);
        btf_dirset_free(&noisy);
        fixture_close(&f);
    }
}

static void expect_error(btf_dir *d, int count, const char *words)
{
    btf_dirset s = {"custom", count, d};
    btf_hemisphere *h = (btf_hemisphere *)&s; /* must be reset to NULL */
    btf_error e = {0};
    assert_int_equal(btf_hemisphere_build(&s, &h, &e), BTF_E_ARG);
    assert_null(h);
    assert_non_null(strstr(e.msg, "custom"));
    if (!strstr(e.msg, words))
        print_error("message \"%s\" lacks \"%s\"\n", e.msg, words);
    assert_non_null(strstr(e.msg, words));
    assert_null(strchr(e.msg, '\n'));
}

static void bad_sets(void **state)
{
    (void)state;
    btf_dir two[] = {{10, 0}, {20, 90}};
    expect_error(two, 2, "at least 3");
    expect_error(two, 0, "at least 3");
    btf_dir same[] = {{30, 40}, {30, 40}, {30, 40}};
    expect_error(same, 3, "same direction");
    btf_dir pole_twice[] = {{0, 0}, {0, 90}, {30, 0}};
    expect_error(pole_twice, 3, "same direction");
    btf_dir line[] = {{10, 0}, {20, 0}, {45, 180}, {90, 0}, {0, 0}};
    expect_error(line, 5, "one line");
    btf_dir slanted[] = {{30, 45}, {60, 225}, {15, 225}};
    expect_error(slanted, 3, "one line");
    btf_dir bad_theta[] = {{10, 0}, {95, 90}, {20, 180}};
    expect_error(bad_theta, 3, "theta");
    btf_dir nan_phi[] = {{10, 0}, {40, NAN}, {20, 180}};
    expect_error(nan_phi, 3, "theta");
    btf_hemisphere *h;
    btf_error e = {0};
    assert_int_equal(btf_hemisphere_build(NULL, &h, &e), BTF_E_ARG);
    assert_null(h);
    /* The same direction merged by btf_dirset_from_list: 1 left. */
    btf_dirset m;
    TU_OK(btf_dirset_from_list(&m, same, 3, &e), &e);
    assert_int_equal(btf_hemisphere_build(&m, &h, &e), BTF_E_ARG);
    btf_dirset_free(&m);
    /* The smallest valid set: one triangle; every direction gets weights. */
    btf_dir three[] = {{0, 0}, {45, 0}, {45, 90}};
    btf_dirset s3 = {"three", 3, three};
    TU_OK(btf_hemisphere_build(&s3, &h, &e), &e);
    btf_hemisphere_table t;
    btf__hemisphere_get_table(h, &t);
    assert_int_equal(t.n_triangles, 1);
    assert_int_equal(t.n_hull, 3);
    for (int r = 0; r < 1000; r++) {
        float v[3] = {(float)(urand() - 0.5), (float)(urand() - 0.5), (float)(urand() - 0.5)};
        int idx[3];
        float w[3];
        btf__hemisphere_lookup(h, v, idx, w);
        assert_true(w[0] >= 0.0f && w[1] >= 0.0f && w[2] >= 0.0f);
        assert_true(fabs(w[0] + w[1] + w[2] - 1.0) <= 1e-6);
    }
    btf_hemisphere_free(h);
    btf_hemisphere_free(NULL);
}

/* The build compiled the same lookup text as GLSL and spirv-val passed it. */
static void lookup_compiles_as_glsl(void **state)
{
    (void)state;
    assert_true(sizeof hemisphere_check_spv > 64);
    assert_int_equal(hemisphere_check_spv[0], 0x07230203u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(weight_rules),
        cmocka_unit_test(measured_directions),
        cmocka_unit_test(pole_and_degenerate_vectors),
        cmocka_unit_test(continuity_edges_and_hull),
        cmocka_unit_test(grid_matches_brute_force),
        cmocka_unit_test(delaunay_valid_and_covering),
        cmocka_unit_test(independent_of_floating_noise),
        cmocka_unit_test(bad_sets),
        cmocka_unit_test(lookup_compiles_as_glsl),
    };
    return cmocka_run_group_tests_name("hemisphere", tests, NULL, NULL);
}
