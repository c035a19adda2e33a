/*
 * integrate.c — from a normal map to a height field (the range map of the
 * paper, Haindl & Filip 2007, section II.B, which drives parallax bump
 * mapping later).
 *
 * A unit normal n gives the surface slopes p = dz/dcolumn = -n_x / n_z and
 * q = dz/drow = +n_y / n_z (the frame has y UP in the image while the row
 * index grows downwards; see src/generate/material.c). Measured slopes are noisy and
 * not exactly integrable, so both methods find the surface whose gradient is
 * closest to them in the least-squares sense:
 *
 *  - Frankot & Chellappa (1988), "A method for enforcing integrability in
 *    shape from shading algorithms": project the gradient field onto the
 *    integrable fields spanned by the Fourier basis. With P, Q the DFTs of p,
 *    q and (i su, i sv) the Fourier symbol of the derivative, the height is
 *        Z = (-i su P - i sv Q) / (su^2 + sv^2),   Z(0, 0) = 0.
 *    The derivative is taken as the central difference, su = sin(2 pi u / W)
 *    rather than the continuous 2 pi u / W: a normal estimated per pixel is
 *    the slope across its neighbours, and btf_procedural's normals are exactly
 *    central differences of its heights, which FC then inverts without
 *    loss (the continuous symbol damps fine relief by sin(w)/w: 5x the height
 *    error on the built-in materials). Bins where su = sv = 0 (the mean and,
 *    for even sizes, the Nyquist bins that central differences cannot see)
 *    get no height. FC treats the surface as periodic, which a procedural
 *    BTF tile is (its images tile seamlessly); a measured patch is not, and
 *    FC then bends its borders to meet: use Poisson there.
 *
 *  - Poisson, least squares with a Neumann (free) boundary: minimise
 *        sum over neighbouring pixel pairs (z_j - z_i - g_ij)^2
 *    with g_ij the mean of the two pixels' slopes along the pair. Its normal
 *    equations are L z = b with L the graph Laplacian of the pixel grid (no
 *    pairs cross the border, hence Neumann) and b the divergence of g. The
 *    DCT-II diagonalises L (Simchony, Chellappa & Shao 1990, "Direct
 *    analytical methods for solving Poisson equations in computer vision
 *    problems"), eigenvalue (2 - 2 cos(pi k / W)) + (2 - 2 cos(pi l / H)).
 *    OpenCV's DCT needs even sizes; for odd sizes the same problem is solved
 *    exactly as the periodic one on the even-symmetric (mirrored) extension,
 *    2W x 2H, by the DFT. No periodicity is assumed, so it also suits
 *    ordinary (non-tiling) photometric-stereo data. It is the default.
 *
 * A mask: FC sets the slopes outside it to zero (it cannot leave pixels out).
 * Poisson drops every pair that leaves the mask, so the valid region has a
 * free boundary of any shape; the graph Laplacian is then no longer
 * diagonal in the DCT basis and is solved by conjugate gradients,
 * preconditioned by the full-grid DCT solve (a close operator: only the
 * pairs at the mask's border differ), which needs tens of iterations where
 * plain CG would need thousands. Heights are zero-mean over the valid
 * pixels and 0 outside them; separate parts of a mask get independent offsets
 * (nothing links them).
 */
#include "io/io.h"
#include "core/core.h"
#include "range/range.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define INT_PI 3.14159265358979323846

/* ------------------------------------------------------------------ slopes */

static int mask_at(const btf_image *mask, size_t k)
{
    if (!mask)
        return 1;
    const float *p = mask->data + k * (size_t)mask->channels;
    for (int c = 0; c < mask->channels; c++)
        if (p[c] != 0.0f && isfinite(p[c]))
            return 1;
    return 0;
}

static double clamp_slope(double s, double max_slope)
{
    if (!isfinite(s))
        return 0.0;
    return s > max_slope ? max_slope : s < -max_slope ? -max_slope : s;
}

/* Slopes p (along columns) and q (along rows) of every pixel; 0 outside the
 * mask and for zero or non-finite normals. n_z is kept away from 0 so a
 * normal at the horizon gives the steepest allowed slope, not a division by
 * zero. */
static void normals_to_slopes(const btf_image *nm, const unsigned char *valid,
                              double max_slope, double *p, double *q)
{
    size_t count = (size_t)nm->width * nm->height;
    for (size_t k = 0; k < count; k++) {
        const float *n = nm->data + 3 * k;
        double nx = n[0], ny = n[1], nz = n[2];
        p[k] = q[k] = 0.0;
        if (!valid[k] || !isfinite(nx) || !isfinite(ny) || !isfinite(nz))
            continue;
        if (nx == 0.0 && ny == 0.0)
            continue;
        double z = nz > 1e-12 ? nz : 1e-12;
        p[k] = clamp_slope(-nx / z, max_slope);
        q[k] = clamp_slope(ny / z, max_slope);
    }
}

/* ------------------------------------------------------ Frankot-Chellappa */

/* The Fourier symbol of the central difference (z(k+1) - z(k-1)) / 2 along
 * an axis of n samples at DFT bin k: i sin(2 pi k / n). */
static double cd_symbol(int k, int n)
{
    return sin(2.0 * INT_PI * (double)k / (double)n);
}

static btf_status integrate_fc(int w, int h, const double *p, const double *q, double *z,
                               btf_error *err)
{
    size_t count = (size_t)w * h;
    double *re = btf__alloc(count * 2, sizeof(double), err);
    if (!re)
        return BTF_E_NOMEM;
    double *im = re + count;
    /* One complex transform carries both real fields: F = DFT(p + i q), and
     * P(k) = (F(k) + conj F(-k)) / 2, Q(k) = (F(k) - conj F(-k)) / 2i. */
    memcpy(re, p, count * sizeof(double));
    memcpy(im, q, count * sizeof(double));
    char msg[256];
    if (btfcv_dft2(re, im, w, h, 0, msg, sizeof msg) != 0) {
        free(re);
        return btf__fail(err, BTF_E_NUMERIC, "integrate (Frankot-Chellappa): DFT failed: %s", msg);
    }
    double *zr = btf__alloc(count * 2, sizeof(double), err);
    if (!zr) {
        free(re);
        return BTF_E_NOMEM;
    }
    double *zi = zr + count;
    for (int v = 0; v < h; v++) {
        int vm = v == 0 ? 0 : h - v;
        double sv = cd_symbol(v, h);
        for (int u = 0; u < w; u++) {
            int um = u == 0 ? 0 : w - u;
            size_t k = (size_t)v * w + u, km = (size_t)vm * w + um;
            double su = cd_symbol(u, w), d = su * su + sv * sv;
            double pr = 0.5 * (re[k] + re[km]), pi = 0.5 * (im[k] - im[km]);
            double qr = 0.5 * (im[k] + im[km]), qi = -0.5 * (re[k] - re[km]);
            if (d < 1e-12) {
                /* The mean (and, for even sizes, the Nyquist bins, which
                 * central differences cannot see): no height. */
                zr[k] = zi[k] = 0.0;
                continue;
            }
            /* Z = (-i su P - i sv Q) / d */
            zr[k] = (su * pi + sv * qi) / d;
            zi[k] = -(su * pr + sv * qr) / d;
        }
    }
    free(re);
    if (btfcv_dft2(zr, zi, w, h, 1, msg, sizeof msg) != 0) {
        free(zr);
        return btf__fail(err, BTF_E_NUMERIC, "integrate (Frankot-Chellappa): inverse DFT failed: %s",
                         msg);
    }
    memcpy(z, zr, count * sizeof(double));
    free(zr);
    return BTF_OK;
}

/* ------------------------------------------------------------------ Poisson */

/* The divergence right-hand side b of L z = b for the pairs inside the
 * valid set: b_i = sum over pairs (i, j) of g(j <- i) taken with the sign
 * that makes L the positive graph Laplacian. */
static void poisson_rhs(int w, int h, const double *p, const double *q,
                        const unsigned char *valid, double *b)
{
    size_t count = (size_t)w * h;
    memset(b, 0, count * sizeof(double));
    for (int r = 0; r < h; r++) {
        for (int c = 0; c < w; c++) {
            size_t k = (size_t)r * w + c;
            if (!valid[k])
                continue;
            if (c + 1 < w && valid[k + 1]) {
                double g = 0.5 * (p[k] + p[k + 1]); /* z(c+1) - z(c) */
                b[k] -= g;
                b[k + 1] += g;
            }
            if (r + 1 < h && valid[k + w]) {
                double g = 0.5 * (q[k] + q[k + w]); /* z(r+1) - z(r) */
                b[k] -= g;
                b[k + w] += g;
            }
        }
    }
}

/* Eigenvalue of the 1-D Neumann Laplacian of n points for DCT bin k. */
static double neumann_eig(int k, int n)
{
    return 2.0 - 2.0 * cos(INT_PI * (double)k / (double)n);
}

/* Solves L z = b on the full w x h grid (Neumann), in place, choosing the
 * solution of zero mean (the pseudo-inverse: L's null space is the
 * constants). Even sizes: OpenCV's DCT-II; odd: mirrored DFT. scratch holds
 * 8 w h doubles. */
static btf_status poisson_full(int w, int h, double *a, double *scratch, btf_error *err)
{
    char msg[256];
    int even = (w == 1 || w % 2 == 0) && (h == 1 || h % 2 == 0);
    if (even) {
        if (btfcv_dct2(a, w, h, 0, msg, sizeof msg) != 0)
            return btf__fail(err, BTF_E_NUMERIC, "integrate (Poisson): DCT failed: %s", msg);
        for (int l = 0; l < h; l++) {
            double el = neumann_eig(l, h);
            for (int k = 0; k < w; k++) {
                double d = el + neumann_eig(k, w);
                size_t i = (size_t)l * w + k;
                a[i] = d > 0.0 ? a[i] / d : 0.0;
            }
        }
        if (btfcv_dct2(a, w, h, 1, msg, sizeof msg) != 0)
            return btf__fail(err, BTF_E_NUMERIC, "integrate (Poisson): inverse DCT failed: %s", msg);
        return BTF_OK;
    }
    /* The even-symmetric extension about the half-pixel borders turns the
     * Neumann problem into a periodic one of twice the size whose solution is
     * the mirrored Neumann solution. */
    int W = 2 * w, H = 2 * h;
    size_t n2 = (size_t)W * H;
    double *re = scratch, *im = scratch + n2;
    for (int r = 0; r < H; r++) {
        int rs = r < h ? r : H - 1 - r;
        for (int c = 0; c < W; c++) {
            int cs = c < w ? c : W - 1 - c;
            re[(size_t)r * W + c] = a[(size_t)rs * w + cs];
            im[(size_t)r * W + c] = 0.0;
        }
    }
    if (btfcv_dft2(re, im, W, H, 0, msg, sizeof msg) != 0)
        return btf__fail(err, BTF_E_NUMERIC, "integrate (Poisson): DFT failed: %s", msg);
    for (int l = 0; l < H; l++) {
        double el = 2.0 - 2.0 * cos(2.0 * INT_PI * (double)l / (double)H);
        for (int k = 0; k < W; k++) {
            double d = el + 2.0 - 2.0 * cos(2.0 * INT_PI * (double)k / (double)W);
            size_t i = (size_t)l * W + k;
            if (d > 0.0) {
                re[i] /= d;
                im[i] /= d;
            } else {
                re[i] = im[i] = 0.0;
            }
        }
    }
    if (btfcv_dft2(re, im, W, H, 1, msg, sizeof msg) != 0)
        return btf__fail(err, BTF_E_NUMERIC, "integrate (Poisson): inverse DFT failed: %s", msg);
    for (int r = 0; r < h; r++)
        for (int c = 0; c < w; c++)
            a[(size_t)r * w + c] = re[(size_t)r * W + c];
    return BTF_OK;
}

/* y = L_valid x: the graph Laplacian restricted to pairs inside the mask. */
static void apply_laplacian(int w, int h, const unsigned char *valid, const double *x, double *y)
{
    for (int r = 0; r < h; r++) {
        for (int c = 0; c < w; c++) {
            size_t k = (size_t)r * w + c;
            if (!valid[k]) {
                y[k] = 0.0;
                continue;
            }
            double s = 0.0;
            if (c > 0 && valid[k - 1])
                s += x[k] - x[k - 1];
            if (c + 1 < w && valid[k + 1])
                s += x[k] - x[k + 1];
            if (r > 0 && valid[k - w])
                s += x[k] - x[k - w];
            if (r + 1 < h && valid[k + w])
                s += x[k] - x[k + w];
            y[k] = s;
        }
    }
}

static double dot(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++)
        s += a[i] * b[i];
    return s;
}

/* The preconditioner: the full-grid pseudo-inverse applied to r (zero
 * outside the mask), restricted to the mask. r sums to zero over every
 * part of the mask, so the full-grid constant it discards is no loss. */
static btf_status precondition(int w, int h, const unsigned char *valid, const double *r,
                               double *z, double *scratch, btf_error *err)
{
    size_t count = (size_t)w * h;
    memcpy(z, r, count * sizeof(double));
    btf_status rc = poisson_full(w, h, z, scratch, err);
    if (rc)
        return rc;
    for (size_t k = 0; k < count; k++)
        if (!valid[k])
            z[k] = 0.0;
    return BTF_OK;
}

/* Preconditioned conjugate gradients on L_valid z = b (consistent and
 * positive semi-definite: CG stays in the range of L). */
static btf_status poisson_masked(int w, int h, const unsigned char *valid, const double *b,
                                 double *x, double tol, int max_iter, btf_error *err)
{
    size_t count = (size_t)w * h;
    double *buf = btf__alloc(count * 12, sizeof(double), err);
    if (!buf)
        return BTF_E_NOMEM;
    double *r = buf, *z = buf + count, *pd = buf + 2 * count, *ap = buf + 3 * count;
    double *scratch = buf + 4 * count;
    memset(x, 0, count * sizeof(double));
    memcpy(r, b, count * sizeof(double));
    double bnorm = sqrt(dot(b, b, count));
    btf_status rc = BTF_OK;
    if (!(bnorm > 0.0) || !isfinite(bnorm))
        goto done;
    if ((rc = precondition(w, h, valid, r, z, scratch, err)))
        goto done;
    memcpy(pd, z, count * sizeof(double));
    double rz = dot(r, z, count);
    for (int it = 0; it < max_iter && rz > 0.0 && isfinite(rz); it++) {
        apply_laplacian(w, h, valid, pd, ap);
        double pap = dot(pd, ap, count);
        if (!(pap > 0.0) || !isfinite(pap))
            break;
        double alpha = rz / pap;
        for (size_t k = 0; k < count; k++) {
            x[k] += alpha * pd[k];
            r[k] -= alpha * ap[k];
        }
        if (sqrt(dot(r, r, count)) <= tol * bnorm)
            break;
        if ((rc = precondition(w, h, valid, r, z, scratch, err)))
            break;
        double rz_new = dot(r, z, count);
        double beta = rz_new / rz;
        rz = rz_new;
        for (size_t k = 0; k < count; k++)
            pd[k] = z[k] + beta * pd[k];
    }
done:
    free(buf);
    return rc;
}

static btf_status integrate_poisson(int w, int h, const double *p, const double *q,
                                    const unsigned char *valid, int all_valid, double tol,
                                    int max_iter, double *z, btf_error *err)
{
    size_t count = (size_t)w * h;
    double *b = btf__alloc(count * 9, sizeof(double), err);
    if (!b)
        return BTF_E_NOMEM;
    poisson_rhs(w, h, p, q, valid, b);
    btf_status rc;
    if (all_valid) {
        rc = poisson_full(w, h, b, b + count, err);
        if (rc == 0)
            memcpy(z, b, count * sizeof(double));
    } else {
        rc = poisson_masked(w, h, valid, b, z, tol, max_iter, err);
    }
    free(b);
    return rc;
}

/* ----------------------------------------------------------------- public */

btf_integrate_opts btf_integrate_defaults(void)
{
    btf_integrate_opts o = {
        .struct_size = sizeof o,
        .method = BTF_INTEGRATE_POISSON,
        .max_slope = 10.0,
        .tolerance = 1e-7,
        .max_iter = 2000,
    };
    return o;
}

static btf_status check_inputs(const btf_image *normals, const btf_image *mask,
                               const btf_integrate_opts *o, btf_error *err)
{
    if (!normals || !normals->data || normals->channels != 3 || normals->width < 1 ||
        normals->height < 1)
        return btf__fail(err, BTF_E_ARG, "integrate: the normal map must be a 3-channel image");
    if (mask && (!mask->data || mask->width != normals->width || mask->height != normals->height))
        return btf__fail(err, BTF_E_ARG,
                         "integrate: mask size %dx%d differs from the normal map's %dx%d",
                         mask->width, mask->height, normals->width, normals->height);
    if (o->method != BTF_INTEGRATE_DEFAULT && o->method != BTF_INTEGRATE_POISSON &&
        o->method != BTF_INTEGRATE_FC)
        return btf__fail(err, BTF_E_ARG, "integrate: unknown method %d", (int)o->method);
    if (!(o->max_slope >= 0.0) || !isfinite(o->max_slope) || !(o->tolerance >= 0.0) ||
        !isfinite(o->tolerance) || o->max_iter < 0)
        return btf__fail(err, BTF_E_ARG,
                         "integrate: max_slope %g, tolerance %g, max_iter %d: expected finite "
                         "values >= 0",
                         o->max_slope, o->tolerance, o->max_iter);
    return BTF_OK;
}

btf_status btf__integrate(const btf_image *normals, const btf_image *mask,
                          const btf_integrate_opts *opts, btf_image *height, btf_error *err)
{
    btf_integrate_opts zero = {0}, o;
    if (btf__opts_take(&o, sizeof o, opts, &zero, "btf_integrate", err))
        return BTF_E_ARG;
    if (!height)
        return btf__fail(err, BTF_E_ARG, "integrate: no output image given");
    memset(height, 0, sizeof *height);
    btf_status rc = check_inputs(normals, mask, &o, err);
    if (rc)
        return rc;
    /* 0 takes the default (check_inputs refused negative values). */
    const btf_integrate_opts def = btf_integrate_defaults();
    double max_slope = o.max_slope > 0.0 ? o.max_slope : def.max_slope;
    double tol = o.tolerance > 0.0 ? o.tolerance : def.tolerance;
    int max_iter = o.max_iter > 0 ? o.max_iter : def.max_iter;
    int w = normals->width, h = normals->height;
    size_t count = (size_t)w * h;
    if ((rc = btf_image_alloc(height, w, h, 1, err)))
        return rc;
    unsigned char *valid = btf__alloc(count, 1, err);
    double *buf = valid ? btf__alloc(count * 3, sizeof(double), err) : NULL;
    if (!buf) {
        free(valid);
        btf_image_free(height);
        return BTF_E_NOMEM;
    }
    double *p = buf, *q = buf + count, *z = buf + 2 * count;
    size_t n_valid = 0;
    for (size_t k = 0; k < count; k++) {
        valid[k] = (unsigned char)mask_at(mask, k);
        n_valid += valid[k];
    }
    if (n_valid > 0) {
        normals_to_slopes(normals, valid, max_slope, p, q);
        if (o.method == BTF_INTEGRATE_FC)
            rc = integrate_fc(w, h, p, q, z, err);
        else
            rc = integrate_poisson(w, h, p, q, valid, n_valid == count, tol, max_iter, z, err);
        if (rc == 0) {
            double mean = 0.0;
            for (size_t k = 0; k < count; k++)
                mean += valid[k] ? z[k] : 0.0;
            mean /= (double)n_valid;
            for (size_t k = 0; k < count; k++) {
                double v = valid[k] ? z[k] - mean : 0.0;
                height->data[k] = isfinite(v) ? (float)v : 0.0f;
            }
        }
    }
    free(buf);
    free(valid);
    if (rc)
        btf_image_free(height);
    return rc;
}
