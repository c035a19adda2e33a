/*
 * ps_passes.c — the two passes of photometric stereo over its images
 * (Haindl & Filip 2007, section II.B). Pass 1 turns every image into one
 * grey sample per pixel, the input of the normal fit. Pass 2, after the
 * fit, gives every channel its own albedo with the normal fixed: the
 * least-squares rho_c = sum I_ic n.l_i / sum (n.l_i)^2 over the samples the
 * pixel's fit kept. Splitting them lets the fit run on N floats per pixel
 * while each file is decoded only once per pass.
 */
#include "range/range.h"
#include "core/core.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

void btf__ps_report(const btf_photostereo_opts *o, double fraction, const char *what)
{
    if (o->progress)
        o->progress(o->progress_user, fraction, what);
}

/* Light i's intensity in channel c (a grey image sees the mean of r, g, b);
 * 1 without intensities. */
static double channel_intensity(const double *intensity, int i, int c, int channels)
{
    if (!intensity)
        return 1.0;
    if (channels == 1)
        return (intensity[3 * i] + intensity[3 * i + 1] + intensity[3 * i + 2]) / 3.0;
    return intensity[3 * i + c];
}

/* A raw value as the model sees it: negatives (noise below black) and
 * non-finite values (only memory images can hold them) count as 0. */
static double clean(float v)
{
    return isfinite(v) && v > 0.0f ? (double)v : 0.0;
}

/* The grey sample of image i at every pixel: mean over channels of
 * value / intensity. A sample with a raw channel >= clip is saturated and
 * stored negated, so that the fit knows it without a second array (and a
 * saturated 0 as -FLT_MIN). Returns the largest finite raw value inside the
 * mask, which sets the clip level of data beyond 1 (btf__ps_full_scale). */
static double grey_of(const btf_image *img, int i, const double *intensity, double clip,
                      const unsigned char *inside, float *out)
{
    size_t count = (size_t)img->width * img->height;
    int channels = img->channels;
    double scale[3], peak = 0.0;
    for (int c = 0; c < channels; c++)
        scale[c] = 1.0 / channel_intensity(intensity, i, c, channels) / channels;
    for (size_t k = 0; k < count; k++) {
        if (!inside[k]) {
            out[k] = 0.0f;
            continue;
        }
        const float *p = img->data + k * (size_t)channels;
        double grey = 0.0;
        int saturated = 0;
        for (int c = 0; c < channels; c++) {
            saturated |= p[c] >= clip; /* NaN compares false */
            if (isfinite(p[c]) && p[c] > peak)
                peak = p[c];
            grey += clean(p[c]) * scale[c];
        }
        float f = (float)grey;
        if (!isfinite(f))
            f = FLT_MAX;
        if (saturated)
            f = -(f > FLT_MIN ? f : FLT_MIN);
        out[k] = f;
    }
    return peak;
}

double btf__ps_full_scale(double peak)
{
    return peak > 1.0 ? peak : 1.0;
}

/* Image i's share of the albedo sums: for each pixel whose fit used sample
 * i, num_c += I_c n.l and den += (n.l)^2 (l: light i's direction). */
static void albedo_add(const btf_image *img, int i, const double *intensity,
                       const btf_ps_solve *job, double *num, double *den)
{
    size_t count = (size_t)img->width * img->height;
    int channels = img->channels;
    double scale[3];
    for (int c = 0; c < channels; c++)
        scale[c] = 1.0 / channel_intensity(intensity, i, c, channels);
    const double *light = job->lights + 3 * i;
    uint64_t bit = (uint64_t)1 << (i & 63);
    for (size_t k = 0; k < count; k++) {
        if (!(job->fit_sets[k * (size_t)job->set_words + (size_t)(i >> 6)] & bit))
            continue;
        const float *normal = job->normal + 3 * k;
        double nl = normal[0] * light[0] + normal[1] * light[1] + normal[2] * light[2];
        if (!(nl > 0.0))
            continue;
        const float *p = img->data + k * (size_t)channels;
        for (int c = 0; c < channels; c++)
            num[k * (size_t)channels + c] += clean(p[c]) * scale[c] * nl;
        den[k] += nl * nl;
    }
}

/* Files take the first two fifths of the progress bar, memory none to
 * speak of. */
btf_status btf__ps_pass_grey(const btf_ps_source *src, const double *intensity, double clip,
                             const unsigned char *inside, float *grey, double *peak,
                             const btf_photostereo_opts *o, btf_error *err)
{
    size_t wh = (size_t)src->width * src->height;
    btf_image tmp = {0}; /* one buffer for every image (btf__ps_source_get) */
    double most = 0.0;
    for (int i = 0; i < src->count; i++) {
        const btf_image *img;
        btf_status rc = btf__ps_source_get(src, i, &tmp, &img, err);
        if (rc)
            return rc;
        double p = grey_of(img, i, intensity, clip, inside, grey + (size_t)i * wh);
        most = p > most ? p : most;
        if (!src->images)
            btf__ps_report(o, 0.4 * (i + 1) / src->count,
                           peak ? "reading images" : "reading images (clip level of HDR data)");
    }
    btf_image_free(&tmp);
    if (peak)
        *peak = most;
    return BTF_OK;
}

btf_status btf__ps_pass_albedo(const btf_ps_source *src, const double *intensity,
                               const btf_ps_solve *job, btf_image *albedo,
                               const btf_photostereo_opts *o, btf_error *err)
{
    size_t wh = (size_t)src->width * src->height;
    int channels = src->channels;
    double *num = btf__calloc(wh * (size_t)(channels + 1), sizeof(double), err);
    if (!num)
        return BTF_E_NOMEM;
    double *den = num + wh * (size_t)channels;
    btf_status rc = BTF_OK;
    btf_image tmp = {0}; /* one buffer for every image (btf__ps_source_get) */
    for (int i = 0; i < src->count && rc == BTF_OK; i++) {
        const btf_image *img;
        if ((rc = btf__ps_source_get(src, i, &tmp, &img, err)))
            break;
        albedo_add(img, i, intensity, job, num, den);
        if (!src->images)
            btf__ps_report(o, 0.5 + 0.4 * (i + 1) / src->count, "reading images (albedo)");
    }
    btf_image_free(&tmp);
    for (size_t k = 0; rc == BTF_OK && k < wh; k++) {
        for (int c = 0; c < channels; c++) {
            double a = job->inside[k] && den[k] > 0.0 ? num[k * channels + c] / den[k] : 0.0;
            float f = (float)a;
            albedo->data[k * channels + c] = isfinite(f) ? f : FLT_MAX;
        }
    }
    free(num);
    return rc;
}
