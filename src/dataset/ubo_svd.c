/*
 * ubo_svd.c — the writers' eigenpairs. The k largest eigenpairs of a
 * symmetric matrix, for the truncated SVD of DFMF and FMF
 * (dataset/ubo_factor.c) and the per-view PCA of PVF
 * (dataset/ubo_write_pvf.c): the Gram matrix of the smaller side of a
 * channel's (view, light) x pixel matrix has the squared singular values
 * as eigenvalues and the singular vectors of that side as eigenvectors
 * (the factorisation the notes' §3 stores as U and S x V).
 *
 * Small matrices (n <= 256) are diagonalised whole by cyclic Jacobi
 * rotations (core/linalg.c); larger ones by subspace iteration with a
 * block of k + 8 vectors from a fixed start, and a Rayleigh-Ritz step
 * (Jacobi on the block) at the end. Both are deterministic: the same
 * matrix gives the same bits. Each eigenvector's sign is fixed so that
 * its largest component is positive.
 */
#include <stdio.h>
#include "core/core.h"
#include "core/linalg.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The writers' Jacobi rule: sums of squares, at most 60 sweeps; another
 * rule could change the bits of the files written. */
static void jacobi(double *a, int n, double *val, double *vec)
{
    static const btf_linalg_jacobi_rule rule = {.max_sweeps = 60, .relative = 1e-30};
    btf__linalg_jacobi(a, n, &rule, val, vec);
}

/* Orthonormalises the b columns of q (n x b) by modified Gram-Schmidt,
 * twice; a column that vanishes becomes a unit vector not yet spanned. */
static void orthonormalise(double *q, int n, int b)
{
    for (int pass = 0; pass < 2; pass++)
        for (int j = 0; j < b; j++) {
            for (int i = 0; i < j; i++) {
                double d = 0;
                for (int r = 0; r < n; r++)
                    d += q[(size_t)r * b + i] * q[(size_t)r * b + j];
                for (int r = 0; r < n; r++)
                    q[(size_t)r * b + j] -= d * q[(size_t)r * b + i];
            }
            double s = 0;
            for (int r = 0; r < n; r++)
                s += q[(size_t)r * b + j] * q[(size_t)r * b + j];
            s = sqrt(s);
            if (s > 1e-300) {
                for (int r = 0; r < n; r++)
                    q[(size_t)r * b + j] /= s;
            } else { /* rank deficient: restart the column deterministically */
                for (int r = 0; r < n; r++)
                    q[(size_t)r * b + j] = r == (j * 7919) % n;
                if (pass == 1)
                    j--; /* orthogonalise the new column again */
            }
        }
}

/* out (n x b) = g (n x n) x q (n x b). */
/* The block's Rayleigh quotient t = q^T z (b x b) with z = g q: its
 * eigenvalues are the Ritz values of the subspace iteration. */
static void project_block(const double *q, const double *z, int n, int b, double *t)
{
    for (int i = 0; i < b; i++)
        for (int j = 0; j < b; j++) {
            double d = 0;
            for (int r = 0; r < n; r++)
                d += q[(size_t)r * b + i] * z[(size_t)r * b + j];
            t[(size_t)i * b + j] = d;
        }
}

static void multiply(const double *g, const double *q, int n, int b, double *out)
{
    for (int i = 0; i < n; i++) {
        double *o = out + (size_t)i * b;
        for (int j = 0; j < b; j++)
            o[j] = 0;
        for (int r = 0; r < n; r++) {
            double a = g[(size_t)i * n + r];
            const double *qr = q + (size_t)r * b;
            for (int j = 0; j < b; j++)
                o[j] += a * qr[j];
        }
    }
}

/* Sorts the pairs descending, keeps k, fixes the signs: vals[m], vecs n x m
 * (columns) into val[k], vec n x k. */
static void take_top(const double *vals, const double *vecs, int n, int m, int k, double *val,
                     double *vec)
{
    int *idx = malloc((size_t)m * sizeof *idx);
    char *used = calloc((size_t)m, 1);
    for (int j = 0; j < k; j++) {
        int best = -1;
        for (int i = 0; i < m; i++)
            if (!used[i] && (best < 0 || vals[i] > vals[best]))
                best = i;
        used[best] = 1;
        idx[j] = best;
    }
    for (int j = 0; j < k; j++) {
        int c = idx[j];
        val[j] = vals[c];
        int big = 0;
        for (int r = 1; r < n; r++)
            if (fabs(vecs[(size_t)r * m + c]) > fabs(vecs[(size_t)big * m + c]))
                big = r;
        double sign = vecs[(size_t)big * m + c] < 0 ? -1.0 : 1.0;
        for (int r = 0; r < n; r++)
            vec[(size_t)r * k + j] = sign * vecs[(size_t)r * m + c];
    }
    free(idx);
    free(used);
}

btf_status ubo_top_eigen(double *g, int n, int k, double *val, double *vec, btf_error *err)
{
    if (k < 1 || k > n)
        return btf__fail(err, BTF_E_ARG, "eigenpairs: %d of a %d x %d matrix", k, n, n);
    if (n <= 256) {
        double *vals = btf__alloc((size_t)n, sizeof *vals, err);
        double *vecs = btf__alloc((size_t)n * n, sizeof *vecs, err);
        if (!vals || !vecs) {
            free(vals);
            free(vecs);
            return BTF_E_NOMEM;
        }
        jacobi(g, n, vals, vecs);
        take_top(vals, vecs, n, n, k, val, vec);
        free(vals);
        free(vecs);
        return BTF_OK;
    }
    int b = k + 8 < n ? k + 8 : n;
    double *q = btf__alloc((size_t)n * b, sizeof *q, err);
    double *z = btf__alloc((size_t)n * b, sizeof *z, err);
    double *t = btf__alloc((size_t)b * b, sizeof *t, err);
    double *tv = btf__alloc((size_t)b * b, sizeof *tv, err);
    double *tval = btf__alloc((size_t)b, sizeof *tval, err);
    double *prev = btf__calloc((size_t)b, sizeof *prev, err);
    btf_status rc = q && z && t && tv && tval && prev ? BTF_OK : BTF_E_NOMEM;
    if (rc == BTF_OK) {
        uint64_t s = 0x9e3779b97f4a7c15ull; /* a fixed start: splitmix64 */
        for (size_t i = 0; i < (size_t)n * b; i++) {
            uint64_t x = (s += 0x9e3779b97f4a7c15ull);
            x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
            x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
            x ^= x >> 31;
            q[i] = (double)(x >> 11) * 0x1.0p-53 - 0.5;
        }
        orthonormalise(q, n, b);
        int converged = 0;
        for (int it = 0; it < 1000 && !converged; it++) {
            multiply(g, q, n, b, z);
            if (it % 5 == 4) { /* Ritz values of the block: stop when the top k settle */
                project_block(q, z, n, b, t);
                jacobi(t, b, tval, tv);
                double top = 0, change = 0;
                for (int i = 0; i < b; i++)
                    top = fmax(top, fabs(tval[i]));
                /* compare sorted values */
                double sorted[512];
                int m = b < 512 ? b : 512;
                for (int i = 0; i < m; i++)
                    sorted[i] = tval[i];
                for (int i = 1; i < m; i++)
                    for (int j = i; j > 0 && sorted[j] > sorted[j - 1]; j--) {
                        double x = sorted[j];
                        sorted[j] = sorted[j - 1];
                        sorted[j - 1] = x;
                    }
                for (int i = 0; i < k && i < m; i++)
                    change = fmax(change, fabs(sorted[i] - prev[i]));
                for (int i = 0; i < m; i++)
                    prev[i] = sorted[i];
                converged = top == 0 || change <= 1e-12 * top;
            }
            memcpy(q, z, (size_t)n * b * sizeof *q);
            orthonormalise(q, n, b);
        }
        /* Rayleigh-Ritz on the final block. */
        multiply(g, q, n, b, z);
        project_block(q, z, n, b, t);
        for (int i = 0; i < b; i++) /* symmetrise rounding */
            for (int j = i + 1; j < b; j++)
                t[(size_t)i * b + j] = t[(size_t)j * b + i] =
                    0.5 * (t[(size_t)i * b + j] + t[(size_t)j * b + i]);
        jacobi(t, b, tval, tv);
        for (int r = 0; r < n; r++) /* z = q (n x b) x tv (b x b) */
            for (int j = 0; j < b; j++) {
                double d = 0;
                for (int i = 0; i < b; i++)
                    d += q[(size_t)r * b + i] * tv[(size_t)i * b + j];
                z[(size_t)r * b + j] = d;
            }
        take_top(tval, z, n, b, k, val, vec);
        if (!converged)
            rc = btf__fail(err, BTF_E_NUMERIC,
                           "the eigenpairs of a %d x %d Gram matrix did not converge in 1000 "
                           "subspace iterations", n, n);
    }
    BTF_FREE_ALL(q, z, t, tv, tval, prev);
    return rc;
}

int ubo_keep_components(const double *val, int k)
{
    int kc = 0;
    double top = val[0] > 0 ? sqrt(val[0]) : 0;
    while (kc < k && val[kc] > 0 && sqrt(val[kc]) > 1e-7 * top)
        kc++;
    return kc ? kc : 1;
}
