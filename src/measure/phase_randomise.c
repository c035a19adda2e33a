/*
 * phase_randomise.c — the baseline a texture model must beat 
 * (docs/measure.md, "Phase-randomisation baseline"): random phase noise
 * (van Wijk 1991; Galerne, Gousseau & Morel, "Random phase textures",
 * IEEE TIP 2011), a Gaussian texture with exactly the exemplar's power
 * spectrum and nothing else. It is what a stationary Gaussian model such as
 * the paper's CAR field (section II.C) can reach at best with unlimited
 * parameters, so a model that scores worse than it wastes its structure.
 *
 * Colours are decorrelated as the model does (car/decorrelate.c, section
 * II.C): mean removed, PCA basis. Each decorrelated channel's periodic
 * component (measure/periodic.c) is transformed; its amplitude is kept and
 * its phase replaced by the phase of the DFT of real Gaussian white noise,
 * which is uniform and Hermitian-symmetric (phi(-k) = -phi(k)), so the
 * inverse is real. The channels get independent phases: they are
 * uncorrelated after the PCA, as the model assumes. The DC term is kept.
 */
#include "core/core.h"
#include "io/io.h"
#include "car/car.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

uint64_t btf_phase_randomise_bytes(int width, int height)
{
    if (width < 1 || height < 1)
        return 0;
    uint64_t half = (uint64_t)height * (uint64_t)(width / 2 + 1);
    return 4u * (3u * half + 12u);
}

/* Standard normal by Box-Muller (u1 in (0, 1], so the log is finite). */
static double gaussian(btf_rng *r)
{
    double u1 = 1.0 - btf__rng_uniform(r), u2 = btf__rng_uniform(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}

/* One channel in place (band: w x h, zero mean): work holds 3 w x h. */
static btf_status randomise_band(double *band, int w, int h, btf_rng *rng, double *work,
                                 btf_error *err)
{
    size_t n = (size_t)w * h;
    double *im = work, *zr = im + n, *zi = zr + n;
    btf_status rc = ms_periodic_component(band, w, h, err);
    if (rc != BTF_OK)
        return rc;
    for (size_t i = 0; i < n; i++) {
        im[i] = zi[i] = 0.0;
        zr[i] = gaussian(rng);
    }
    char why[256];
    if (btfcv_dft2(band, im, w, h, 0, why, sizeof why) != 0 ||
        btfcv_dft2(zr, zi, w, h, 0, why, sizeof why) != 0)
        return btf__fail(err, BTF_E_UNSUPPORTED, "phase randomisation: DFT failed: %s", why);
    for (size_t i = 1; i < n; i++) {
        double amp = hypot(band[i], im[i]), mag = hypot(zr[i], zi[i]);
        band[i] = mag > 0.0 ? amp * zr[i] / mag : amp;
        im[i] = mag > 0.0 ? amp * zi[i] / mag : 0.0;
    }
    if (btfcv_dft2(band, im, w, h, 1, why, sizeof why) != 0)
        return btf__fail(err, BTF_E_UNSUPPORTED, "phase randomisation: DFT failed: %s", why);
    return BTF_OK; /* the imaginary part is rounding error: dropped */
}

static btf_status check_args(const btf_image *ex, int width, int height, btf_image *out,
                             btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "phase randomisation: no output image");
    if (!ex || !ex->data || ex->width < 1 || ex->height < 1)
        return btf__fail(err, BTF_E_ARG, "phase randomisation: no exemplar image");
    if (ex->channels != 1 && ex->channels != 3)
        return btf__fail(err, BTF_E_ARG, "phase randomisation: exemplar has %d channels, "
                         "expected 1 or 3", ex->channels);
    if (width < 1 || height < 1 || width > BTF_MAX_SIDE || height > BTF_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "phase randomisation: output size %dx%d out of "
                         "range 1..%d", width, height, BTF_MAX_SIDE);
    size_t n = (size_t)ex->width * ex->height * ex->channels;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(ex->data[i]))
            return btf__fail(err, BTF_E_DATA, "phase randomisation: exemplar pixel (%zu, %zu) "
                             "is not finite", i / ex->channels % ex->width,
                             i / ex->channels / ex->width);
    return BTF_OK;
}

/* The exemplar's decorrelated channels (nc of them, 1 or 3) into bands. */
static btf_status decorrelate(const btf_image *ex, float mean[3], float basis[9],
                              double *bands[3], btf_error *err)
{
    size_t n = (size_t)ex->width * ex->height;
    if (ex->channels == 3) {
        btf_status rc = btf__pca3(ex, mean, basis, NULL, err);
        if (rc == BTF_OK)
            btf__decorrelate(ex, mean, basis, bands);
        return rc;
    }
    double m = 0.0;
    for (size_t i = 0; i < n; i++)
        m += ex->data[i];
    mean[0] = (float)(m / (double)n);
    for (size_t i = 0; i < n; i++)
        bands[0][i] = (double)ex->data[i] - mean[0];
    basis[0] = 1.0f;
    return BTF_OK;
}

btf_status btf_phase_randomise(const btf_image *exemplar, int width, int height, uint64_t seed,
                               btf_image *out, btf_error *err)
{
    btf_status rc = check_args(exemplar, width, height, out, err);
    if (rc != BTF_OK) {
        if (out)
            memset(out, 0, sizeof *out);
        return rc;
    }
    int w = exemplar->width, h = exemplar->height, nc = exemplar->channels;
    size_t n = (size_t)w * h;
    double *mem = btf__alloc((size_t)(nc + 3) * n, sizeof(double), err);
    if (!mem) {
        memset(out, 0, sizeof *out);
        return BTF_E_NOMEM;
    }
    double *bands[3] = {mem, mem + n, mem + 2 * n}, *work = mem + (size_t)nc * n;
    float mean[3] = {0, 0, 0}, basis[9] = {0};
    btf_rng rng;
    btf__rng_seed(&rng, seed);
    rc = decorrelate(exemplar, mean, basis, bands, err);
    for (int c = 0; c < nc && rc == BTF_OK; c++)
        rc = randomise_band(bands[c], w, h, &rng, work, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, height, nc, err);
    if (rc != BTF_OK) {
        free(mem);
        memset(out, 0, sizeof *out);
        return rc;
    }
    /* Undo the decorrelation (the basis is orthonormal: its transpose);
     * the texture is periodic, so other sizes wrap it. */
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t s = (size_t)(y % h) * w + (size_t)(x % w);
            float *o = out->data + ((size_t)y * width + x) * nc;
            for (int k = 0; k < nc; k++) {
                double v = mean[k];
                for (int b = 0; b < nc; b++)
                    v += (double)basis[3 * b + k] * bands[b][s];
                o[k] = (float)v;
                if (!isfinite(o[k]))
                    rc = BTF_E_NUMERIC;
            }
        }
    free(mem);
    if (rc != BTF_OK) {
        btf_image_free(out);
        memset(out, 0, sizeof *out);
        return btf__fail(err, BTF_E_NUMERIC, "phase randomisation: the result is not finite "
                         "(exemplar values too large)");
    }
    return BTF_OK;
}
