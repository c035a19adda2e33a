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
 *
 * Lab needs a white: values are clamped to [0, 1] first. 8- and 16-bit
 * files have theirs at 1; float data (EXR, .btf files) have none, so a
 * linear dataset x 1000 turned white and collapsed into one subspace. They
 * are divided by their own white level, measured on a sample of images, so
 * that the features do not depend on their units (docs/segmentation.md,
 * "Scale").
 */
#include "dataset/dataset.h"
#include "io/io.h"
#include "core/core.h"
#include "segment/segment.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The white level of float data: the WHITE_QUANTILE quantile of the
 * pixels' largest channel (a few hot pixels or glints cannot set it), over
 * at most WHITE_IMAGES images spread over the dataset (few beside the
 * thousands the features decode) and about WHITE_PIXELS pixels of them. */
#define WHITE_IMAGES 64
#define WHITE_PIXELS (1 << 18)
#define WHITE_QUANTILE 0.9999

static int bin_of(float v, float lo, float hi, int bins)
{
    float t = (v - lo) / (hi - lo) * (float)bins;
    if (!(t >= 0.0f)) /* below the range, or NaN */
        return 0;
    if (t >= (float)bins)
        return bins - 1;
    return (int)t;
}

/* btf__lab_cumhist of img / white. The division is one float division per
 * value, so data x k with white x k give the same bits (when both products
 * are exact, as for half floats x 1000); white 1 leaves the values as they
 * are. */
static btf_status lab_cumhist_white(const btf_image *img, int bins, float white, float *feature,
                                    btf_error *err)
{
    if (bins < 2 || bins > 4096)
        return btf__fail(err, BTF_E_ARG, "histogram bins %d: expected 2..4096", bins);
    if (!img || !img->data || img->channels != 3)
        return btf__fail(err, BTF_E_ARG, "Lab histogram needs an RGB image");
    size_t n = (size_t)img->width * img->height;
    uint32_t *count = btf__calloc((size_t)bins * 3, sizeof(uint32_t), err);
    if (!count)
        return BTF_E_NOMEM;
    const size_t CHUNK = 1024;
    float lab[3 * 1024], scaled[3 * 1024];
    char msg[256];
    const float a = BTF_LAB_A_RANGE;
    for (size_t i0 = 0; i0 < n; i0 += CHUNK) {
        size_t m = n - i0 < CHUNK ? n - i0 : CHUNK;
        const float *rgb = img->data + 3 * i0;
        if (white != 1.0f) {
            for (size_t j = 0; j < 3 * m; j++)
                scaled[j] = rgb[j] / white;
            rgb = scaled;
        }
        if (btfcv_rgb_to_lab(rgb, m, lab, msg, sizeof msg) != 0) {
            free(count);
            return btf__fail(err, BTF_E_NUMERIC, "Lab conversion failed: %s", msg);
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

btf_status btf__lab_cumhist(const btf_image *img, int bins, float *feature, btf_error *err)
{
    return lab_cumhist_white(img, bins, 1.0f, feature, err);
}

/* One job per sampled image: the largest channel of every stride-th pixel
 * into its own slots of the batch. */
typedef struct white_batch {
    const btf_dataset *ds;
    int n_lights, images, total;
    size_t stride, per_image;  /* pixels: every stride-th, per_image of them */
    float *values;             /* images x per_image */
    btf_image *buffers;        /* one per worker */
} white_batch;

static btf_status white_job(void *user, int j, int worker, btf_error *err)
{
    const white_batch *b = user;
    /* image j of `images` spread evenly over the (view, light) order; in a
     * sparse set the next pair it holds */
    int image = (int)((long long)j * b->total / b->images);
    for (int step = 0; step < b->total && !btf_dataset_has(b->ds, image / b->n_lights,
                                                          image % b->n_lights); step++)
        image = (image + 1) % b->total;
    btf_image *img = &b->buffers[worker];
    btf_status rc = btf__dataset_read_into(b->ds, image / b->n_lights, image % b->n_lights, img,
                                           err);
    if (rc)
        return rc;
    float *out = b->values + (size_t)j * b->per_image;
    for (size_t i = 0; i < b->per_image; i++) {
        const float *p = img->data + 3 * (i * b->stride);
        float v = p[0] > p[1] ? p[0] : p[1];
        v = v > p[2] ? v : p[2];
        out[i] = isfinite(v) && v > 0.0f ? v : 0.0f; /* NaN, below black: no light */
    }
    return BTF_OK;
}

static int float_order(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The level float data are divided by before Lab; 1 for 8- and 16-bit
 * files (their white), and for data without light. */
static btf_status feature_white(const btf_dataset *ds, int threads, float *white, btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    *white = 1.0f;
    if (in->format != BTF_FILE_EXR && in->layout != BTF_LAYOUT_UBO2014)
        return BTF_OK;
    white_batch b = {.ds = ds, .n_lights = in->n_lights, .total = in->n_views * in->n_lights};
    b.images = in->n_pairs < WHITE_IMAGES ? in->n_pairs : WHITE_IMAGES;
    size_t wh = (size_t)in->width * in->height;
    size_t want = WHITE_PIXELS / (size_t)b.images; /* pixels per image, about */
    b.stride = want >= wh ? 1 : (wh + want - 1) / want;
    b.per_image = (wh + b.stride - 1) / b.stride;
    int workers = btf__pool_workers(threads, b.images);
    size_t n = (size_t)b.images * b.per_image;
    b.values = btf__alloc(n, sizeof(float), err);
    b.buffers = btf__calloc((size_t)(workers > 0 ? workers : 1), sizeof *b.buffers, err);
    btf_status rc = b.values && b.buffers
                        ? btf__pool_run(b.images, threads, white_job, &b, NULL, err)
                        : BTF_E_NOMEM;
    for (int w = 0; b.buffers && w < workers; w++)
        btf_image_free(&b.buffers[w]);
    free(b.buffers);
    if (rc == BTF_OK) {
        qsort(b.values, n, sizeof(float), float_order); /* once, 2^18 values at most */
        float level = b.values[(size_t)(WHITE_QUANTILE * (double)(n - 1))];
        if (level > 0.0f)
            *white = level; /* a data value: it scales with the data, exactly */
    }
    free(b.values);
    return rc;
}

/* One job per image: decode it into the worker's buffer, compute its
 * feature into its own row. */
typedef struct feature_batch {
    const btf_dataset *ds;
    float white;          /* the values are divided by it (feature_white) */
    int n_lights, bins, dim;
    float *features;      /* (views x lights) x dim */
    float *means;         /* NULL or (views x lights) x 3 */
    btf_image *buffers;   /* one per worker, kept from image to image */
} feature_batch;

static btf_status feature_job(void *user, int image, int worker, btf_error *err)
{
    const feature_batch *b = user;
    if (!btf_dataset_has(b->ds, image / b->n_lights, image % b->n_lights))
        return BTF_OK; /* a sparse set: its row stays 0 and is not clustered */
    btf_image *img = &b->buffers[worker];
    btf_status rc = btf__dataset_read_into(b->ds, image / b->n_lights, image % b->n_lights, img,
                                           err);
    if (rc == BTF_OK)
        rc = lab_cumhist_white(img, b->bins, b->white, b->features + (size_t)image * b->dim,
                               err);
    if (rc == BTF_OK && b->means)
        btf__image_mean_rgb(img, b->means + 3 * (size_t)image);
    return rc;
}

btf_feature_opts btf_feature_defaults(void)
{
    return (btf_feature_opts){.struct_size = sizeof(btf_feature_opts), .bins = 32, .threads = 0};
}

btf_status btf__dataset_features(const btf_dataset *ds, const btf_feature_opts *opts,
                                 float **features, int *dim, btf_error *err)
{
    btf_feature_opts d = btf_feature_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_dataset_features", err))
        return BTF_E_ARG;
    int bins = o.bins ? o.bins : btf_feature_defaults().bins;
    if (bins < 2 || bins > 4096)
        return btf__fail(err, BTF_E_ARG, "histogram bins %d: expected 2..4096", bins);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    feature_batch b = {.ds = ds, .n_lights = in->n_lights, .bins = bins, .dim = 3 * bins,
                       .means = o.means};
    btf_status rc = feature_white(ds, o.threads, &b.white, err);
    if (rc)
        return rc;
    int total = in->n_views * in->n_lights;
    b.features = btf__calloc((size_t)total * b.dim, sizeof(float), err);
    if (!b.features)
        return BTF_E_NOMEM;
    int workers = btf__pool_workers(o.threads, total);
    b.buffers = btf__calloc((size_t)(workers > 0 ? workers : 1), sizeof *b.buffers, err);
    if (!b.buffers) {
        free(b.features);
        return BTF_E_NOMEM;
    }
    btf_pool_progress progress = {o.progress, o.progress_user, "image features", 0.0, 1.0, 64};
    rc = btf__pool_run(total, o.threads, feature_job, &b, &progress, err);
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
    if (!btf_dataset_has(b->ds, image / b->n_lights, image % b->n_lights))
        return BTF_OK; /* a sparse set: the pair's mean stays 0 */
    btf_image *img = &b->buffers[worker];
    btf_status rc = btf__dataset_read_into(b->ds, image / b->n_lights, image % b->n_lights, img,
                                           err);
    if (rc == BTF_OK)
        btf__image_mean_rgb(img, b->means + 3 * (size_t)image);
    return rc;
}

btf_status btf__dataset_means(const btf_dataset *ds, int threads, float **means, btf_error *err)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    int total = in->n_views * in->n_lights;
    mean_batch b = {ds, in->n_lights, NULL, NULL};
    int workers = btf__pool_workers(threads, total);
    b.means = btf__calloc((size_t)total * 3, sizeof(float), err);
    b.buffers = btf__calloc((size_t)(workers > 0 ? workers : 1), sizeof *b.buffers, err);
    btf_status rc = b.means && b.buffers ? btf__pool_run(total, threads, mean_job, &b, NULL, err)
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
