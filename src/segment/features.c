/*
 * features.c — the feature that BTF space segmentation clusters on (paper
 * section II.A): for one image, the cumulative histograms of CIE L*, a* and
 * b*, concatenated. Cumulative histograms compare images by their colour
 * distributions without pixel correspondence, and the L1 distance of two
 * 1-D cumulative histograms is their earth mover's distance, so nearby
 * illumination changes move features smoothly.
 *
 * A dataset's features are computed streaming by the thread pool
 * (core/pool.c): each job decodes one image into its thread's buffer
 * (reused from image to image: a fresh buffer per image was fresh pages
 * each time, 40 % of an analysis of a 400^2 .btf file in page faults,
 * docs/datasets.md); only the features stay in memory. The Lab conversion
 * goes through a small buffer on the stack, a chunk of pixels at a time.
 */
#include "io/io.h"
#include "core/core.h"

#include <stdlib.h>
#include <string.h>

static int bin_of(float v, float lo, float hi, int bins)
{
    float t = (v - lo) / (hi - lo) * (float)bins;
    if (!(t >= 0.0f)) /* below the range, or NaN */
        return 0;
    if (t >= (float)bins)
        return bins - 1;
    return (int)t;
}

btf_status btf_lab_cumhist(const btf_image *img, int bins, float *feature, btf_error *err)
{
    if (bins < 2 || bins > 4096)
        return btf_fail(err, BTF_E_ARG, "histogram bins %d: expected 2..4096", bins);
    if (!img || !img->data || img->channels != 3)
        return btf_fail(err, BTF_E_ARG, "Lab histogram needs an RGB image");
    size_t n = (size_t)img->width * img->height;
    uint32_t *count = btf_calloc((size_t)bins * 3, sizeof(uint32_t), err);
    if (!count)
        return BTF_E_NOMEM;
    const size_t CHUNK = 1024;
    float lab[3 * 1024];
    char msg[256];
    const float a = BTF_LAB_A_RANGE;
    for (size_t i0 = 0; i0 < n; i0 += CHUNK) {
        size_t m = n - i0 < CHUNK ? n - i0 : CHUNK;
        if (btfcv_rgb_to_lab(img->data + 3 * i0, m, lab, msg, sizeof msg) != 0) {
            free(count);
            return btf_fail(err, BTF_E_NUMERIC, "Lab conversion failed: %s", msg);
        }
        for (size_t i = 0; i < m; i++) {
            count[bin_of(lab[3 * i], 0.0f, 100.0f, bins)]++;
            count[bins + bin_of(lab[3 * i + 1], -a, a, bins)]++;
            count[2 * bins + bin_of(lab[3 * i + 2], -a, a, bins)]++;
        }
    }
    for (int c = 0; c < 3; c++) {
        uint64_t run = 0;
        for (int b = 0; b < bins; b++) {
            run += count[c * bins + b];
            feature[c * bins + b] = (float)((double)run / (double)n);
        }
    }
    free(count);
    return BTF_OK;
}

/* One job per image: decode it into the worker's buffer, compute its
 * feature into its own row. */
typedef struct feature_batch {
    const btf_dataset *ds;
    int n_lights, bins, dim;
    float *features;      /* (views x lights) x dim */
    float *means;         /* NULL or (views x lights) x 3 */
    btf_image *buffers;   /* one per worker, kept from image to image */
} feature_batch;

static btf_status feature_job(void *user, int image, int worker, btf_error *err)
{
    const feature_batch *b = user;
    btf_image *img = &b->buffers[worker];
    btf_status rc = btf_dataset_read_into(b->ds, image / b->n_lights, image % b->n_lights, img,
                                          err);
    if (rc == BTF_OK)
        rc = btf_lab_cumhist(img, b->bins, b->features + (size_t)image * b->dim, err);
    if (rc == BTF_OK && b->means)
        btf_image_mean_rgb(img, b->means + 3 * (size_t)image);
    return rc;
}

btf_feature_opts btf_feature_defaults(void)
{
    return (btf_feature_opts){.bins = 32, .threads = 0};
}

btf_status btf_dataset_features(const btf_dataset *ds, const btf_feature_opts *opts,
                                float **features, int *dim, btf_error *err)
{
    btf_feature_opts o = opts ? *opts : btf_feature_defaults();
    int bins = o.bins ? o.bins : btf_feature_defaults().bins;
    if (bins < 2 || bins > 4096)
        return btf_fail(err, BTF_E_ARG, "histogram bins %d: expected 2..4096", bins);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    feature_batch b = {.ds = ds, .n_lights = in->n_lights, .bins = bins, .dim = 3 * bins,
                       .means = o.means};
    int total = in->n_views * in->n_lights;
    b.features = btf_alloc((size_t)total * b.dim, sizeof(float), err);
    if (!b.features)
        return BTF_E_NOMEM;
    int workers = btf_pool_workers(o.threads, total);
    b.buffers = btf_calloc((size_t)(workers > 0 ? workers : 1), sizeof *b.buffers, err);
    if (!b.buffers) {
        free(b.features);
        return BTF_E_NOMEM;
    }
    btf_pool_progress progress = {o.progress, o.progress_user, "image features", 0.0, 1.0, 64};
    btf_status rc = btf_pool_run(total, o.threads, feature_job, &b, &progress, err);
    for (int w = 0; w < workers; w++)
        btf_image_free(&b.buffers[w]);
    free(b.buffers);
    if (rc) {
        free(b.features);
        return rc;
    }
    *features = b.features;
    *dim = b.dim;
    return BTF_OK;
}

/* One job per image: its mean colour alone. */
typedef struct mean_batch {
    const btf_dataset *ds;
    int n_lights;
    float *means;
    btf_image *buffers;
} mean_batch;

static btf_status mean_job(void *user, int image, int worker, btf_error *err)
{
    const mean_batch *b = user;
    btf_image *img = &b->buffers[worker];
    btf_status rc = btf_dataset_read_into(b->ds, image / b->n_lights, image % b->n_lights, img,
                                          err);
    if (rc == BTF_OK)
        btf_image_mean_rgb(img, b->means + 3 * (size_t)image);
    return rc;
}

btf_status btf_dataset_means(const btf_dataset *ds, int threads, float **means, btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    int total = in->n_views * in->n_lights;
    mean_batch b = {ds, in->n_lights, NULL, NULL};
    int workers = btf_pool_workers(threads, total);
    b.means = btf_alloc((size_t)total * 3, sizeof(float), err);
    b.buffers = btf_calloc((size_t)(workers > 0 ? workers : 1), sizeof *b.buffers, err);
    btf_status rc = b.means && b.buffers ? btf_pool_run(total, threads, mean_job, &b, NULL, err)
                                         : BTF_E_NOMEM;
    for (int w = 0; b.buffers && w < workers; w++)
        btf_image_free(&b.buffers[w]);
    free(b.buffers);
    if (rc) {
        free(b.means);
        return rc;
    }
    *means = b.means;
    return BTF_OK;
}
