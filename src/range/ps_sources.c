/*
 * ps_sources.c — the inputs of photometric stereo (Haindl & Filip 2007,
 * section II.B): the images of one view under many lights, either in memory
 * or as files decoded on demand, and the mask of the pixels to work on.
 * Files are decoded one at a time, once per pass, so that a dataset or a
 * long capture never has all its images in memory.
 */
#include "range/range.h"
#include "core/core.h"
#include "dataset/dataset.h"

#include <math.h>

btf_status btf__ps_source_probe(btf_ps_source *src, btf_error *err)
{
    btf_image_header hdr;
    btf_status rc = btf_image_probe(src->paths[0], &hdr, err);
    if (rc)
        return rc;
    src->width = hdr.width;
    src->height = hdr.height;
    src->channels = 3;
    return BTF_OK;
}

btf_status btf__ps_source_get(const btf_ps_source *src, int i, btf_image *tmp,
                              const btf_image **img, btf_error *err)
{
    if (src->images) {
        *img = &src->images[i];
        return BTF_OK;
    }
    btf_read_opts ro = src->read;
    ro.channels = 3; /* the fit's grey value and the albedo need the colour */
    btf_status rc;
    if (src->ds) { /* a .btf file's image goes into tmp's buffer when it has one */
        rc = btf__dataset_read_into(src->ds, src->view, src->light_of ? src->light_of[i] : i,
                                    tmp, err);
    } else {
        btf_image_free(tmp);
        rc = btf_image_read(src->paths[i], &ro, tmp, err);
    }
    if (rc)
        return rc;
    if (tmp->width != src->width || tmp->height != src->height) {
        rc = btf__fail(err, BTF_E_DATA, "%s: size %dx%d differs from the first image's %dx%d",
                       src->paths[i], tmp->width, tmp->height, src->width, src->height);
        btf_image_free(tmp);
        return rc;
    }
    *img = tmp;
    return BTF_OK;
}

btf_status btf__ps_mask_inside(const char *name, const btf_image *mask, int width, int height,
                               unsigned char *inside, int *pixels, btf_error *err)
{
    size_t wh = (size_t)width * height;
    if (mask && (!mask->data || mask->width != width || mask->height != height ||
                 (mask->channels != 1 && mask->channels != 3)))
        return btf__fail(err, BTF_E_ARG, "%s: the mask (%dx%d, %d channels) does not fit the "
                         "images (%dx%d; 1 or 3 channels)", name, mask->width, mask->height,
                         mask->channels, width, height);
    int n = 0;
    for (size_t k = 0; k < wh; k++) {
        int in = 1;
        if (mask) {
            in = 0;
            for (int c = 0; c < mask->channels; c++) {
                float v = mask->data[k * (size_t)mask->channels + c];
                in |= v != 0.0f && isfinite(v);
            }
        }
        inside[k] = (unsigned char)in;
        n += in;
    }
    *pixels = n;
    return BTF_OK;
}

/* The angle in degrees between two directions. */
static double angle_between(btf_dir a, btf_dir b)
{
    double u[3], v[3];
    btf_dir_to_vec(a, u);
    btf_dir_to_vec(b, v);
    double d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    d = d > 1.0 ? 1.0 : d < -1.0 ? -1.0 : d;
    return acos(d) * 57.29577951308232;
}

btf_status btf__ps_pick_view(const btf_dir *dirs, int n, const btf_dir *want, const char *name,
                             int *view, btf_error *err)
{
    int best = 0;
    for (int v = 1; v < n; v++)
        if (want ? angle_between(dirs[v], *want) < angle_between(dirs[best], *want)
                 : dirs[v].theta < dirs[best].theta)
            best = v;
    if (want && !(angle_between(dirs[best], *want) <= BTF_PS_VIEW_TOL))
        return btf__fail(err, BTF_E_ARG, "%s: no view near theta %g phi %g (the nearest of its %d "
                         "views is theta %g phi %g, %.1f degrees away; at most %g)", name,
                         want->theta, want->phi, n, dirs[best].theta, dirs[best].phi,
                         angle_between(dirs[best], *want), BTF_PS_VIEW_TOL);
    *view = best;
    return BTF_OK;
}
