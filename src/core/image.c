/*
 * image.c — the float image (allocation with a size bound) and the sRGB
 * transfer function (IEC 61966-2-1).
 */
#include "core/core.h"

#include <math.h>
#include <stdlib.h>

btf_status btf_image_alloc(btf_image *img, int width, int height, int channels,
                           btf_error *err)
{
    img->data = NULL;
    img->width = img->height = img->channels = 0;
    if (channels != 1 && channels != 3)
        return btf__fail(err, BTF_E_ARG, "image channels %d: expected 1 or 3", channels);
    return btf__image_alloc_any(img, width, height, channels, err);
}

btf_status btf__image_alloc_any(btf_image *img, int width, int height, int channels,
                                btf_error *err)
{
    img->data = NULL;
    img->width = img->height = img->channels = 0;
    if (width < 1 || height < 1 || width > BTF_MAX_SIDE || height > BTF_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "image size %dx%d out of range 1..%d", width,
                         height, BTF_MAX_SIDE);
    if (channels < 1 || channels > 4)
        return btf__fail(err, BTF_E_ARG, "image channels %d: expected 1 to 4", channels);
    float *d = btf__calloc((size_t)width * (size_t)height * (size_t)channels, sizeof(float), err);
    if (!d)
        return BTF_E_NOMEM;
    img->data = d;
    img->width = width;
    img->height = height;
    img->channels = channels;
    return BTF_OK;
}

int btf__check_pixels(const char *name, int width, int height, uint64_t max_pixels,
                      btf_error *err)
{
    uint64_t cap = max_pixels ? max_pixels : BTF_DEFAULT_MAX_PIXELS;
    uint64_t n = (uint64_t)(width > 0 ? width : 0) * (uint64_t)(height > 0 ? height : 0);
    if (n <= cap)
        return BTF_OK;
    return btf__fail(err, BTF_E_UNSUPPORTED,
                     "%s: %dx%d image (%llu pixels) exceeds the cap of %llu decoded pixels "
                     "(--max-pixels raises it)",
                     name, width, height, (unsigned long long)n, (unsigned long long)cap);
}

void btf_image_free(btf_image *img)
{
    if (!img)
        return;
    free(img->data);
    img->data = NULL;
    img->width = img->height = img->channels = 0;
}

float btf__srgb_to_linear(float v)
{
    if (!(v > 0.0f))
        return 0.0f;
    if (v <= 0.04045f)
        return v / 12.92f;
    if (v >= 1.0f)
        return 1.0f;
    return powf((v + 0.055f) / 1.055f, 2.4f);
}

float btf__linear_to_srgb(float v)
{
    if (!(v > 0.0f))
        return 0.0f;
    if (v <= 0.0031308f)
        return v * 12.92f;
    if (v >= 1.0f)
        return 1.0f;
    return 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

void btf__image_mean_rgb(const btf_image *img, float *rgb)
{
    double s[3] = {0.0, 0.0, 0.0};
    size_t n = (size_t)img->width * img->height;
    int c3 = img->channels >= 3;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            s[c] += img->data[i * img->channels + (c3 ? c : 0)];
    for (int c = 0; c < 3; c++)
        rgb[c] = n ? (float)(s[c] / (double)n) : 0.0f;
}
