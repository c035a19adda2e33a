/*
 * linalg3.c — symmetric 3x3 algebra for photometric stereo (Haindl & Filip
 * 2007, section II.B): every pixel's least-squares fit solves the 3x3
 * normal equations (sum l l^T) g = sum I l of its lights, and must first
 * know whether those lights determine g at all. Closed forms throughout:
 * the matrices are tiny and there are millions of them, so no iteration and
 * no allocation.
 */
#include "range/range.h"

#include <math.h>

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

double btf_sym3_condition(const btf_sym3 *m)
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
void btf_sym3_weakest_axis(const btf_sym3 *m, double axis[3])
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
int btf_sym3_solve(const btf_sym3 *m, const double rhs[3], double max_condition, double x[3],
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
        !(btf_sym3_condition(m) <= max_condition))
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
