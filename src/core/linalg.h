/*
 * linalg.h — the library's small dense linear algebra (core/linalg.c): the
 * cyclic Jacobi eigen-solver, the Cholesky factorisation and its solve, and
 * the closed forms for symmetric 3x3 matrices. Private to the library.
 *
 * Each caller's results are bit for bit what its own copy gave before the
 * copies were merged (model files, rf models, .btf files and reports are
 * compared byte for byte): where the copies differed in their stopping rule
 * the difference is a parameter (btf_linalg_jacobi_rule), and the Cholesky
 * factor computes every entry with the same operations in the same order
 * whatever triangle it reads.
 */
#ifndef BTF_LINALG_H
#define BTF_LINALG_H

/* ------------------------------------------------------ cyclic Jacobi */

/* When the sweeps of btf__linalg_jacobi stop. Each sweep first measures the
 * off-diagonal part `off` against the diagonal `diag` (with abs_sums, the
 * sums of |a_ij| over i < j and of |a_ii|; otherwise the sums of their
 * squares) and stops when off <= tiny or off <= relative * diag, or after
 * max_sweeps sweeps. finite_tangent: a rotation whose tangent is not
 * finite (theta overflowed) uses tangent 0 instead, so that it cannot
 * spread a NaN. */
typedef struct btf_linalg_jacobi_rule {
    int max_sweeps;
    int abs_sums;
    double tiny, relative;
    int finite_tangent;
} btf_linalg_jacobi_rule;

/* Eigenvalues of the symmetric n x n matrix a (row-major, overwritten; its
 * diagonal ends as the eigenvalues) into val, unsorted, and the unit
 * eigenvectors as the columns of vec (n x n row-major: vec[i * n + k] is
 * component i of vector k), by cyclic Jacobi rotations (Golub & Van Loan,
 * section 8.5): slow for a large n but accurate for the small eigenvalues
 * too, and deterministic. */
void btf__linalg_jacobi(double *a, int n, const btf_linalg_jacobi_rule *rule, double *val,
                        double *vec);

/* btf__linalg_jacobi with the eigenpairs sorted by decreasing eigenvalue
 * (equal values keep their index order). -1 when out of memory. */
int btf__linalg_sym_eigen(double *a, int n, const btf_linalg_jacobi_rule *rule, double *val,
                          double *vec);

/* ------------------------------------------------------------ Cholesky */

/* The lower-triangular factor l (n x n, row-major, the upper triangle left
 * alone) of the symmetric positive definite n x n matrix a (row stride
 * lda), read from its lower triangle, or with `upper` from its upper one
 * (for callers that only fill that one). l may be a itself (lda == n).
 * 0, or -1 when a pivot is not positive (nor a NaN): not positive
 * definite. A pivot of +infinity is not refused; a caller that must refuse
 * it checks l's diagonal. */
int btf__linalg_cholesky(const double *a, int lda, int upper, int n, double *l);

/* Solves (l l^T) x = b in place: x holds b on entry, the solution on
 * return; l from btf__linalg_cholesky. */
void btf__linalg_cholesky_solve(const double *l, int n, double *x);

/* ---------------------------------------------------- symmetric 3 x 3 */

/* A symmetric 3x3 matrix, such as the Gram matrix sum l l^T of a pixel's
 * light directions in photometric stereo, by its six distinct entries.
 * Closed forms throughout: such matrices are tiny and there are millions
 * of them, so no iteration and no allocation. */
typedef struct btf_sym3 {
    double xx, yy, zz, xy, xz, yz;
} btf_sym3;

/* m += v v^T. Inline: it runs once per sample of every fit. */
static inline void btf_sym3_add_outer(btf_sym3 *m, const double v[3])
{
    m->xx += v[0] * v[0];
    m->yy += v[1] * v[1];
    m->zz += v[2] * v[2];
    m->xy += v[0] * v[1];
    m->xz += v[0] * v[2];
    m->yz += v[1] * v[2];
}

/* v^T m v: with m the inverse Gram matrix, a sample's leverage. */
static inline double btf_sym3_quadratic(const btf_sym3 *m, const double v[3])
{
    return m->xx * v[0] * v[0] + m->yy * v[1] * v[1] + m->zz * v[2] * v[2] +
           2.0 * (m->xy * v[0] * v[1] + m->xz * v[0] * v[2] + m->yz * v[1] * v[2]);
}

/* Condition number lambda_max / lambda_min; infinity when singular. */
double btf__sym3_condition(const btf_sym3 *m);
/* The unit eigenvector of the smallest eigenvalue: the direction a set of
 * lights resolves worst. */
void btf__sym3_weakest_axis(const btf_sym3 *m, double axis[3]);
/* Solves m x = rhs when m is positive definite with a condition number of
 * at most max_condition; 0 when rejected. inverse (may be NULL) receives
 * m^-1. */
int btf__sym3_solve(const btf_sym3 *m, const double rhs[3], double max_condition, double x[3],
                    btf_sym3 *inverse);

#endif
