/*
 * jacobi.c — eigenvalues and eigenvectors of a small symmetric matrix by
 * cyclic Jacobi rotations (Golub & Van Loan, section 8.5): slow for large
 * n but accurate for the small eigenvalues too, and deterministic. The
 * report's per-view PCA (report/pca_views.c) diagonalises its n_lights x
 * n_lights Gram matrices with it.
 */
#include "report/report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int btf_sym_eigen(double *a, int n, double *val, double *vec)
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            vec[i * n + j] = i == j;
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0, diag = 0;
        for (int i = 0; i < n; i++) {
            diag += a[i * n + i] * a[i * n + i];
            for (int j = i + 1; j < n; j++)
                off += a[i * n + j] * a[i * n + j];
        }
        if (off <= 1e-30 * diag || off == 0)
            break;
        for (int p = 0; p < n; p++)
            for (int q = p + 1; q < n; q++) {
                double apq = a[p * n + q];
                if (apq == 0)
                    continue;
                double app = a[p * n + p], aqq = a[q * n + q];
                double theta = (aqq - app) / (2 * apq);
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < n; k++) { /* columns p, q */
                    double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; k++) { /* rows p, q */
                    double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for (int k = 0; k < n; k++) {
                    double vkp = vec[k * n + p], vkq = vec[k * n + q];
                    vec[k * n + p] = c * vkp - s * vkq;
                    vec[k * n + q] = s * vkp + c * vkq;
                }
            }
    }
    /* Sorted descending; an insertion sort keeps equal values in index order. */
    int *order = malloc((size_t)n * sizeof *order);
    double *tmp = malloc((size_t)n * n * sizeof *tmp);
    if (!order || !tmp) {
        free(order);
        free(tmp);
        return -1;
    }
    for (int i = 0; i < n; i++) {
        int j = i;
        while (j > 0 && a[order[j - 1] * n + order[j - 1]] < a[i * n + i]) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = i;
    }
    memcpy(tmp, vec, (size_t)n * n * sizeof *tmp);
    for (int k = 0; k < n; k++) {
        val[k] = a[order[k] * n + order[k]];
        for (int i = 0; i < n; i++)
            vec[i * n + k] = tmp[i * n + order[k]];
    }
    free(order);
    free(tmp);
    return 0;
}
