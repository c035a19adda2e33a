/*
 * features.c — the feature that BTF space segmentation clusters on (paper
 * section II.A): for one image, the cumulative histograms of CIE L*, a* and
 * b*, concatenated. Cumulative histograms compare images by their colour
 * distributions without pixel correspondence, and the L1 distance of two
 * 1-D cumulative histograms is their earth mover's distance, so nearby
 * illumination changes move features smoothly.
 *
 * A dataset's features are computed streaming: each worker thread decodes one
 * image at a time; only the features stay in memory.
 */
#include "io/io.h"
#include "core/core.h"

#include <pthread.h>
#include <stdatomic.h>
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
    float *lab = btf_alloc(n * 3, sizeof(float), err);
    uint32_t *count = btf_calloc((size_t)bins * 3, sizeof(uint32_t), err);
    if (!lab || !count) {
        free(lab);
        free(count);
        return BTF_E_NOMEM;
    }
    char msg[256];
    if (btfcv_rgb_to_lab(img->data, n, lab, msg, sizeof msg) != 0) {
        free(lab);
        free(count);
        return btf_fail(err, BTF_E_NUMERIC, "Lab conversion failed: %s", msg);
    }
    const float a = BTF_LAB_A_RANGE;
    for (size_t i = 0; i < n; i++) {
        count[bin_of(lab[3 * i], 0.0f, 100.0f, bins)]++;
        count[bins + bin_of(lab[3 * i + 1], -a, a, bins)]++;
        count[2 * bins + bin_of(lab[3 * i + 2], -a, a, bins)]++;
    }
    for (int c = 0; c < 3; c++) {
        uint64_t run = 0;
        for (int b = 0; b < bins; b++) {
            run += count[c * bins + b];
            feature[c * bins + b] = (float)((double)run / (double)n);
        }
    }
    free(lab);
    free(count);
    return BTF_OK;
}

typedef struct feat_job {
    const btf_dataset *ds;
    float *features;
    int bins, dim, total;
    atomic_int next, done, failed;
    pthread_mutex_t lock;
    btf_error err;
    btf_progress_fn progress;
    void *user;
} feat_job;

static void *feat_worker(void *p)
{
    feat_job *j = p;
    int nl = btf_dataset_get_info(j->ds)->n_lights;
    btf_error e = {0};
    for (;;) {
        int t = atomic_fetch_add(&j->next, 1);
        if (t >= j->total || atomic_load(&j->failed))
            break;
        btf_image img = {0};
        int rc = btf_dataset_read(j->ds, t / nl, t % nl, &img, &e);
        if (rc == 0)
            rc = btf_lab_cumhist(&img, j->bins, j->features + (size_t)t * j->dim, &e);
        btf_image_free(&img);
        pthread_mutex_lock(&j->lock);
        if (rc && !atomic_load(&j->failed)) {
            j->err = e;
            atomic_store(&j->failed, 1);
        }
        int d = atomic_fetch_add(&j->done, 1) + 1;
        if (j->progress && (d % 64 == 0 || d == j->total))
            j->progress(j->user, (double)d / j->total, "image features");
        pthread_mutex_unlock(&j->lock);
    }
    return NULL;
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
    feat_job j = {.ds = ds, .bins = bins, .dim = 3 * bins, .total = in->n_views * in->n_lights,
                  .progress = o.progress, .user = o.progress_user};
    j.features = btf_alloc((size_t)j.total * j.dim, sizeof(float), err);
    if (!j.features)
        return BTF_E_NOMEM;
    pthread_mutex_init(&j.lock, NULL);
    int threads = o.threads > 0 ? o.threads : btf_cpu_count();
    pthread_t tid[64];
    int started = 0;
    for (int i = 1; i < threads && i < 64; i++)
        if (pthread_create(&tid[started], NULL, feat_worker, &j) == 0)
            started++;
    feat_worker(&j);
    for (int i = 0; i < started; i++)
        pthread_join(tid[i], NULL);
    pthread_mutex_destroy(&j.lock);
    if (atomic_load(&j.failed)) {
        free(j.features);
        if (err)
            *err = j.err;
        return j.err.code ? j.err.code : BTF_E_IO;
    }
    *features = j.features;
    *dim = j.dim;
    return BTF_OK;
}
