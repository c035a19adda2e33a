/*
 * linalg.c — the small dense linear algebra every stage shares (declared in
 * core/linalg.h): cyclic Jacobi for symmetric eigenproblems (the spectral
 * PCA of car/decorrelate.c, the report's per-view PCA, the Bonn .btf
 * writers' truncated SVD), Cholesky for the symmetric positive definite
 * solves (the CAR estimates of car/car_fit.c, the reflectance-field fits,
 * the .btf writers' least-squares factors), and the symmetric 3x3 closed
 * forms of photometric stereo (Haindl & Filip 2007, section II.B).
 *
 * One copy of each, so that a fix reaches every caller; the callers'
 * different stopping rules are parameters, so each keeps its bits.
 */
#include "core/linalg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------ cyclic Jacobi */

void btf__linalg_jacobi(double *a, int n, const btf_linalg_jacobi_rule *rule, double *val,
                        double *vec)
{
    size_t un = (size_t)n;
    for (size_t i = 0; i < un; i++)
        for (size_t j = 0; j < un; j++)
            vec[i * un + j] = i == j;
    for (int sweep = 0; sweep < rule->max_sweeps; sweep++) {
        double off = 0, diag = 0;
        for (size_t i = 0; i < un; i++) {
            double d = a[i * un + i];
            diag += rule->abs_sums ? fabs(d) : d * d;
            for (size_t j = i + 1; j < un; j++) {
                double o = a[i * un + j];
                off += rule->abs_sums ? fabs(o) : o * o;
            }
        }
        if (off <= rule->tiny || off <= rule->relative * diag)
            break;
        for (size_t p = 0; p < un; p++)
            for (size_t q = p + 1; q < un; q++) {
                double apq = a[p * un + q];
                if (apq == 0)
                    continue;
                double app = a[p * un + p], aqq = a[q * un + q];
                double theta = (aqq - app) / (2 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
                if (rule->finite_tangent && !isfinite(t))
                    t = 0.0;
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (size_t r = 0; r < un; r++) { /* columns p, q: A J */
                    double arp = a[r * un + p], arq = a[r * un + q];
                    a[r * un + p] = c * arp - s * arq;
                    a[r * un + q] = s * arp + c * arq;
                }
                for (size_t r = 0; r < un; r++) { /* rows p, q: J^T (A J) */
                    double apr = a[p * un + r], aqr = a[q * un + r];
                    a[p * un + r] = c * apr - s * aqr;
                    a[q * un + r] = s * apr + c * aqr;
                }
                for (size_t r = 0; r < un; r++) {
                    double vrp = vec[r * un + p], vrq = vec[r * un + q];
                    vec[r * un + p] = c * vrp - s * vrq;
                    vec[r * un + q] = s * vrp + c * vrq;
                }
            }
    }
    for (size_t i = 0; i < un; i++)
        val[i] = a[i * un + i];
}

int btf__linalg_sym_eigen(double *a, int n, const btf_linalg_jacobi_rule *rule, double *val,
                          double *vec)
{
    size_t un = (size_t)n;
    /* Allocated first, so that running out of memory leaves a untouched. */
    int *order = malloc(un * sizeof *order);
    double *tmp = malloc(un * un * sizeof *tmp);
    if (!order || !tmp) {
        free(order);
        free(tmp);
        return -1;
    }
    btf__linalg_jacobi(a, n, rule, val, vec);
    /* An insertion sort, descending: equal values keep their index order. */
    for (int i = 0; i < n; i++) {
        int j = i;
        while (j > 0 && val[order[j - 1]] < val[i]) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = i;
    }
    memcpy(tmp, vec, un * un * sizeof *tmp);
    for (size_t k = 0; k < un; k++) {
        val[k] = a[(size_t)order[k] * un + (size_t)order[k]];
        for (size_t i = 0; i < un; i++)
            vec[i * un + k] = tmp[i * un + (size_t)order[k]];
    }
    free(order);
    free(tmp);
    return 0;
}

/* ------------------------------------------------------------ Cholesky */

/* Row by row: entry (i, j), j <= i, is a_ij less the dot product of rows i
 * and j of l so far, then its square root (the pivot, j == i) or divided
 * by pivot j. Each entry needs only entries of earlier rows and earlier
 * columns, so the column-by-column order gives the same operations on the
 * same values, the same bits. */
int btf__linalg_cholesky(const double *a, int lda, int upper, int n, double *l)
{
    size_t un = (size_t)n, ua = (size_t)lda;
    for (size_t i = 0; i < un; i++)
        for (size_t j = 0; j <= i; j++) {
            double s = upper ? a[j * ua + i] : a[i * ua + j];
            for (size_t k = 0; k < j; k++)
                s -= l[i * un + k] * l[j * un + k];
            if (i == j) {
                if (!(s > 0.0))
                    return -1;
                l[i * un + i] = sqrt(s);
            } else {
                l[i * un + j] = s / l[j * un + j];
            }
        }
    return 0;
}

void btf__linalg_cholesky_solve(const double *l, int n, double *x)
{
    size_t un = (size_t)n;
    for (size_t i = 0; i < un; i++) { /* l y = b */
        double s = x[i];
        for (size_t k = 0; k < i; k++)
            s -= l[i * un + k] * x[k];
        x[i] = s / l[i * un + i];
    }
    for (size_t i = un; i-- > 0;) { /* l^T x = y */
        double s = x[i];
        for (size_t k = i + 1; k < un; k++)
            s -= l[k * un + i] * x[k];
        x[i] = s / l[i * un + i];
    }
}

/* ---------------------------------------------------- symmetric 3 x 3 */

#define LINALG_PI 3.14159265358979323846
/* Eigenvalues, descending, in closed form for symmetric 3x3 matrices
 * (Smith 1961, "Eigenvalues of a symmetric 3x3 matrix"): cheap enough to
 * check every pixel's conditioning. */
static void sym3_eigenvalues(const btf_sym3 *m, double ev[3])
{
    double off = m->xy * m->xy + m->xz * m->xz + m->yz * m->yz;
    double mean = (m->xx + m->yy + m->zz) / 3.0;
    double dx = m->xx - mean, dy = m->yy - mean, dz = m->zz - mean;
    double spread2 = dx * dx + dy * dy + dz * dz + 2.0 * off;
    if (!(spread2 > 0.0)) {
        ev[0] = ev[1] = ev[2] = mean;
        return;
    }
    double spread = sqrt(spread2 / 6.0);
    /* B = (A - mean I) / spread has eigenvalues 2 cos(phi + 2 pi k / 3)
     * with cos(3 phi) = det(B) / 2. */
    double bxx = dx / spread, byy = dy / spread, bzz = dz / spread;
    double bxy = m->xy / spread, bxz = m->xz / spread, byz = m->yz / spread;
    double det = bxx * (byy * bzz - byz * byz) - bxy * (bxy * bzz - byz * bxz) +
                 bxz * (bxy * byz - byy * bxz);
    double half_det = det / 2.0;
    half_det = half_det < -1.0 ? -1.0 : half_det > 1.0 ? 1.0 : half_det;
    double phi = acos(half_det) / 3.0;
    ev[0] = mean + 2.0 * spread * cos(phi);
    ev[2] = mean + 2.0 * spread * cos(phi + 2.0 * LINALG_PI / 3.0);
    ev[1] = 3.0 * mean - ev[0] - ev[2];
}

double btf__sym3_condition(const btf_sym3 *m)
{
    double ev[3];
    sym3_eigenvalues(m, ev);
    if (!(ev[2] > 0.0) || !isfinite(ev[0]))
        return INFINITY;
    return ev[0] / ev[2];
}

/* The cross product of two rows of A - lambda_min I is orthogonal to both,
 * hence an eigenvector of lambda_min; the longest of the three such
 * products is the best conditioned. */
void btf__sym3_weakest_axis(const btf_sym3 *m, double axis[3])
{
    double ev[3];
    sym3_eigenvalues(m, ev);
    double lmin = ev[2];
    double shifted[3][3] = {{m->xx - lmin, m->xy, m->xz},
                            {m->xy, m->yy - lmin, m->yz},
                            {m->xz, m->yz, m->zz - lmin}};
    double best = -1.0;
    axis[0] = 0.0, axis[1] = 0.0, axis[2] = 1.0;
    for (int i = 0; i < 3; i++) {
        const double *a = shifted[i], *b = shifted[(i + 1) % 3];
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (len > best && len > 0.0) {
            best = len;
            axis[0] = c[0] / len, axis[1] = c[1] / len, axis[2] = c[2] / len;
        }
    }
}

/* By the adjugate: A^-1 = adj(A) / det(A). */
int btf__sym3_solve(const btf_sym3 *m, const double rhs[3], double max_condition, double x[3],
                    btf_sym3 *inverse)
{
    double cxx = m->yy * m->zz - m->yz * m->yz;
    double cxy = m->xz * m->yz - m->xy * m->zz;
    double cxz = m->xy * m->yz - m->xz * m->yy;
    double cyy = m->xx * m->zz - m->xz * m->xz;
    double cyz = m->xy * m->xz - m->xx * m->yz;
    double czz = m->xx * m->yy - m->xy * m->xy;
    double det = m->xx * cxx + m->xy * cxy + m->xz * cxz;
    if (!(det > 0.0) || !isfinite(det))
        return 0;
    /* For a positive definite A, lambda_min >= det / lambda_max^2, so the
     * condition number is at most trace^3 / det: when that bound passes,
     * the eigenvalues need not be computed (most pixels). */
    double trace = m->xx + m->yy + m->zz;
    if (!(trace * trace * trace <= max_condition * det) &&
        !(btf__sym3_condition(m) <= max_condition))
        return 0;
    x[0] = (cxx * rhs[0] + cxy * rhs[1] + cxz * rhs[2]) / det;
    x[1] = (cxy * rhs[0] + cyy * rhs[1] + cyz * rhs[2]) / det;
    x[2] = (cxz * rhs[0] + cyz * rhs[1] + czz * rhs[2]) / det;
    if (inverse) {
        inverse->xx = cxx / det, inverse->yy = cyy / det, inverse->zz = czz / det;
        inverse->xy = cxy / det, inverse->xz = cxz / det, inverse->yz = cyz / det;
    }
    return isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]);
}
