/* test_linalg.c — the shared linear algebra (src/core/linalg.c): Jacobi
 * eigenpairs, Cholesky factor and solve, and the promises its callers'
 * bits rest on (the upper and lower triangles, in place or not, give the
 * same factor to the bit). */
#include "testutil.h"
#include "core/linalg.h"

#include <math.h>
#include <string.h>

static const btf_linalg_jacobi_rule SQUARES = {.max_sweeps = 100, .relative = 1e-30};
static const btf_linalg_jacobi_rule ABSOLUTE = {
    .max_sweeps = 64, .abs_sums = 1, .tiny = 1e-300, .relative = 1e-17, .finite_tangent = 1};

/* A symmetric positive definite 5 x 5: M^T M + I for a fixed M. */
static void spd5(double a[25])
{
    double m[25];
    for (int i = 0; i < 25; i++)
        m[i] = sin(1.0 + 0.7 * i) * (i % 3 + 1);
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 5; j++) {
            double s = i == j;
            for (int k = 0; k < 5; k++)
                s += m[k * 5 + i] * m[k * 5 + j];
            a[i * 5 + j] = s;
        }
}

static void jacobi_eigenpairs(void **state)
{
    (void)state;
    const btf_linalg_jacobi_rule *rules[] = {&SQUARES, &ABSOLUTE};
    for (int r = 0; r < 2; r++) {
        double a0[25], a[25], val[5], vec[25];
        spd5(a0);
        memcpy(a, a0, sizeof a);
        assert_int_equal(btf__linalg_sym_eigen(a, 5, rules[r], val, vec), 0);
        for (int k = 0; k < 5; k++) {
            if (k > 0)
                assert_true(val[k] <= val[k - 1]); /* descending */
            double norm = 0;
            for (int i = 0; i < 5; i++) { /* A v = lambda v */
                double av = 0;
                for (int j = 0; j < 5; j++)
                    av += a0[i * 5 + j] * vec[j * 5 + k];
                assert_true(fabs(av - val[k] * vec[i * 5 + k]) < 1e-10 * val[0]);
                norm += vec[i * 5 + k] * vec[i * 5 + k];
            }
            assert_true(fabs(norm - 1) < 1e-12);
        }
    }
    /* Equal eigenvalues keep their index order; a diagonal matrix needs no
     * rotation and its eigenvectors are the unit vectors. */
    double d[9] = {2, 0, 0, 0, 5, 0, 0, 0, 2}, val[3], vec[9];
    assert_int_equal(btf__linalg_sym_eigen(d, 3, &SQUARES, val, vec), 0);
    assert_true(val[0] == 5 && val[1] == 2 && val[2] == 2);
    assert_true(vec[1 * 3 + 0] == 1 && vec[0 * 3 + 1] == 1 && vec[2 * 3 + 2] == 1);
}

static void cholesky_triangles_and_solve(void **state)
{
    (void)state;
    double a[25], upper[25], lower[25], l_lo[25] = {0}, l_up[25] = {0}, in_place[25];
    spd5(a);
    /* Each triangle alone, the other one garbage. */
    memcpy(upper, a, sizeof a);
    memcpy(lower, a, sizeof a);
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < i; j++)
            upper[i * 5 + j] = lower[j * 5 + i] = -1e9;
    assert_int_equal(btf__linalg_cholesky(lower, 5, 0, 5, l_lo), 0);
    assert_int_equal(btf__linalg_cholesky(upper, 5, 1, 5, l_up), 0);
    memcpy(in_place, lower, sizeof a);
    assert_int_equal(btf__linalg_cholesky(in_place, 5, 0, 5, in_place), 0);
    for (int i = 0; i < 5; i++)
        for (int j = 0; j <= i; j++) {
            assert_memory_equal(&l_lo[i * 5 + j], &l_up[i * 5 + j], sizeof(double));
            assert_memory_equal(&l_lo[i * 5 + j], &in_place[i * 5 + j], sizeof(double));
        }
    double b[5] = {1, -2, 3, 0.5, 4}, x[5];
    memcpy(x, b, sizeof b);
    btf__linalg_cholesky_solve(l_lo, 5, x);
    for (int i = 0; i < 5; i++) {
        double ax = 0;
        for (int j = 0; j < 5; j++)
            ax += a[i * 5 + j] * x[j];
        assert_true(fabs(ax - b[i]) < 1e-10);
    }
    /* A leading block of a larger matrix (row stride lda). */
    double l3[9];
    assert_int_equal(btf__linalg_cholesky(a, 5, 0, 3, l3), 0);
    assert_memory_equal(&l3[2 * 3 + 1], &l_lo[2 * 5 + 1], sizeof(double));
}

static void cholesky_refuses(void **state)
{
    (void)state;
    double indefinite[4] = {1, 2, 2, 1}, zero[4] = {0}, nan[4] = {NAN, 0, 0, 1}, l[4];
    assert_int_equal(btf__linalg_cholesky(indefinite, 2, 0, 2, l), -1);
    assert_int_equal(btf__linalg_cholesky(zero, 2, 0, 2, l), -1);
    assert_int_equal(btf__linalg_cholesky(nan, 2, 0, 2, l), -1);
    /* An infinite pivot is not refused here; it stays on the diagonal for
     * the callers that refuse it. */
    double inf[4] = {INFINITY, 0, 0, 1};
    assert_int_equal(btf__linalg_cholesky(inf, 2, 0, 2, l), 0);
    assert_true(isinf(l[0]));
}

static void sym3_closed_forms(void **state)
{
    (void)state;
    btf_sym3 m = {0};
    const double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0.6, 0, 0.8}};
    for (int i = 0; i < 3; i++)
        btf_sym3_add_outer(&m, v[i]);
    double rhs[3] = {1, 2, 3}, x[3];
    btf_sym3 inv;
    assert_int_equal(btf__sym3_solve(&m, rhs, 1e6, x, &inv), 1);
    assert_true(fabs(m.xx * x[0] + m.xy * x[1] + m.xz * x[2] - 1) < 1e-12);
    assert_true(fabs(m.xz * x[0] + m.yz * x[1] + m.zz * x[2] - 3) < 1e-12);
    assert_true(btf__sym3_condition(&m) > 1);
    /* Lights in one plane leave its normal undetermined. */
    btf_sym3 flat = {0};
    for (int i = 0; i < 2; i++)
        btf_sym3_add_outer(&flat, v[i]);
    assert_true(isinf(btf__sym3_condition(&flat)));
    assert_int_equal(btf__sym3_solve(&flat, rhs, 1e6, x, NULL), 0);
    double axis[3];
    btf__sym3_weakest_axis(&flat, axis);
    assert_true(fabs(fabs(axis[2]) - 1) < 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(jacobi_eigenpairs),
        cmocka_unit_test(cholesky_triangles_and_solve),
        cmocka_unit_test(cholesky_refuses),
        cmocka_unit_test(sym3_closed_forms),
    };
    return cmocka_run_group_tests_name("linalg", tests, NULL, NULL);
}
