/*
 * segment.h — the segmentation stage's parts (src/segment/, paper section
 * II.A) that the rest of the library and the tests call: the images'
 * features, k-means, and the segmentation of features computed before (the
 * sweep shares them between analyses). The public entry is btf_segment
 * (btfcar/analyse.h). Private to the library.
 */
#ifndef BTF_SEGMENT_H
#define BTF_SEGMENT_H

#include "btfcar.h"

/* Fixed ranges of the histograms: L* [0, 100], a* and b* [-64, 64] (values
 * outside are counted in the end bins). */
#define BTF_LAB_A_RANGE 64.0f

/* The feature of one linear-RGB image: the cumulative histograms of L*, a*,
 * b* (each normalised to end at 1), concatenated: 3 * bins floats. */
btf_status btf__lab_cumhist(const btf_image *img, int bins, float *feature, btf_error *err);

/* Features of every image of a dataset, streamed (one image decoded at a time
 * per thread): features[(view * n_lights + light) * dim + i], dim = 3 * bins. */
btf_status btf__dataset_features(const btf_dataset *ds, const btf_feature_opts *opts,
                                 float **features, int *dim, btf_error *err);
/* Each image's mean linear RGB alone (what btf_feature_opts.means gives in
 * the features' pass): means[(view * n_lights + light) * 3 + c], the
 * caller frees it. */
btf_status btf__dataset_means(const btf_dataset *ds, int threads, float **means, btf_error *err);

typedef struct btf_kmeans_result {
    int k;                    /* clusters produced: min(k asked, distinct points) */
    int *labels;              /* n: cluster of each point, 0..k-1 */
    float *centres;           /* k * dim; never NaN */
    double distortion;        /* sum of squared distances to the centres */
} btf_kmeans_result;

/* k-means with k-means++ seeding and restarts. k larger than the number of
 * distinct points is reduced to it; clusters that go empty are re-seeded at
 * the point farthest from its centre. Same inputs and seed, same result. */
btf_status btf__kmeans(const float *points, int n, int dim, int k, const btf_kmeans_opts *opts,
                       btf_kmeans_result *out, btf_error *err);
void btf__kmeans_free(btf_kmeans_result *r);

/* btf_segment from features already computed (n = n_views * n_lights);
 * out->means is NULL. */
btf_status btf__segment_features(const float *features, int n_views, int n_lights, int dim,
                                 const btf_segment_opts *opts, btf_segmentation *out,
                                 btf_error *err);

#endif
