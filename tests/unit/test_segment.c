/* test_segment.c — Lab cumulative histograms, k-means and BTF segmentation. */
#include "testutil.h"
#include "core/core.h"
#include "segment/segment.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static void cumhist_properties(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    TU_OK(btf_image_alloc(&img, 5, 3, 3, &e), &e);
    float f[3 * 16];
    /* Constant mid grey: L's CDF steps once, a and b step at the middle. */
    for (int i = 0; i < 45; i++)
        img.data[i] = 0.18f;
    TU_OK(btf__lab_cumhist(&img, 16, f, &e), &e);
    int steps = 0;
    for (int b = 0; b < 16; b++) {
        assert_true(f[b] == 0.0f || f[b] == 1.0f);
        steps += b > 0 && f[b] != f[b - 1];
    }
    assert_int_equal(steps, 1);
    assert_true(f[16 + 7] == 0.0f && f[16 + 8] == 1.0f); /* a* = 0 is bin 8 of 16 */
    /* Random colours, black, saturated and super-white values: monotone, in
     * [0, 1], ending at 1. */
    btf_rng r;
    btf__rng_seed(&r, 3);
    for (int i = 0; i < 45; i++)
        img.data[i] = (float)btf__rng_uniform(&r) * 3.0f;
    img.data[0] = img.data[1] = img.data[2] = 0.0f;
    img.data[3] = 1e30f;
    TU_OK(btf__lab_cumhist(&img, 16, f, &e), &e);
    for (int c = 0; c < 3; c++) {
        assert_true(f[c * 16 + 15] == 1.0f);
        for (int b = 1; b < 16; b++)
            assert_true(f[c * 16 + b] >= f[c * 16 + b - 1] && f[c * 16 + b] <= 1.0f);
    }
    /* A 1x1 image and bad arguments. */
    btf_image one;
    TU_OK(btf_image_alloc(&one, 1, 1, 3, &e), &e);
    TU_OK(btf__lab_cumhist(&one, 2, f, &e), &e);
    assert_int_equal(btf__lab_cumhist(&one, 1, f, &e), BTF_E_ARG);
    btf_image_free(&one);
    btf_image_free(&img);
}

/* Points in three tight, well separated blobs (dimension 4). */
static float *blobs(int n, btf_rng *r)
{
    float *x = malloc((size_t)n * 4 * sizeof(float));
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 4; j++)
            x[i * 4 + j] = (float)(10.0 * (i % 3) + 0.1 * btf__rng_uniform(r));
    return x;
}

static void kmeans_recovers_blobs_deterministically(void **state)
{
    (void)state;
    btf_rng r;
    btf__rng_seed(&r, 11);
    float *x = blobs(300, &r);
    btf_kmeans_result a, b, c;
    btf_kmeans_opts o = {.seed = 5};
    btf_error e = {0};
    TU_OK(btf__kmeans(x, 300, 4, 3, &o, &a, &e), &e);
    assert_int_equal(a.k, 3);
    for (int i = 0; i < 300; i++) /* canonical order: point 0 is in cluster 0 */
        assert_int_equal(a.labels[i], i % 3);
    TU_OK(btf__kmeans(x, 300, 4, 3, &o, &b, &e), &e);
    assert_memory_equal(a.labels, b.labels, 300 * sizeof(int));
    assert_memory_equal(a.centres, b.centres, 3 * 4 * sizeof(float));
    assert_true(a.distortion == b.distortion);
    /* K = 1: the centre is the mean, the distortion the total scatter. */
    TU_OK(btf__kmeans(x, 300, 4, 1, &o, &c, &e), &e);
    assert_int_equal(c.k, 1);
    double mean = 0;
    for (int i = 0; i < 300; i++)
        mean += x[i * 4];
    assert_true(fabs(c.centres[0] - mean / 300) < 1e-4);
    btf__kmeans_free(&a);
    btf__kmeans_free(&b);
    btf__kmeans_free(&c);
    free(x);
}

static void kmeans_degenerate_inputs(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_kmeans_result r;
    /* 40 points with only 3 distinct values, k = 10: reduced to 3, exact. */
    float x[40 * 2];
    for (int i = 0; i < 40; i++) {
        x[2 * i] = (float)(i % 3);
        x[2 * i + 1] = -(float)(i % 3);
    }
    btf_kmeans_opts o = {.seed = 1};
    TU_OK(btf__kmeans(x, 40, 2, 10, &o, &r, &e), &e);
    assert_int_equal(r.k, 3);
    assert_true(r.distortion == 0.0);
    btf__kmeans_free(&r);
    /* All points identical. */
    float same[20];
    for (int i = 0; i < 20; i++)
        same[i] = 0.5f;
    TU_OK(btf__kmeans(same, 10, 2, 4, &o, &r, &e), &e);
    assert_int_equal(r.k, 1);
    assert_true(r.centres[0] == 0.5f && r.centres[1] == 0.5f);
    btf__kmeans_free(&r);
    /* One point; k larger than n. */
    TU_OK(btf__kmeans(same, 1, 2, 3, &o, &r, &e), &e);
    assert_int_equal(r.k, 1);
    btf__kmeans_free(&r);
    /* Many seeds on data made to empty clusters (a heavy duplicate mass and
     * far outliers): every cluster has members, no centre is NaN. */
    float y[200];
    for (int i = 0; i < 100; i++) {
        y[2 * i] = i < 90 ? 0.0f : (float)(i * i);
        y[2 * i + 1] = i < 90 ? 0.0f : (float)(i % 7);
    }
    for (uint64_t s = 0; s < 50; s++) {
        btf_kmeans_opts os = {.seed = s, .restarts = 2};
        TU_OK(btf__kmeans(y, 100, 2, 8, &os, &r, &e), &e);
        int count[8] = {0};
        for (int i = 0; i < 100; i++) {
            assert_true(r.labels[i] >= 0 && r.labels[i] < r.k);
            count[r.labels[i]]++;
        }
        for (int c = 0; c < r.k; c++) {
            assert_true(count[c] > 0);
            assert_true(isfinite(r.centres[2 * c]) && isfinite(r.centres[2 * c + 1]));
        }
        btf__kmeans_free(&r);
    }
    /* Bad arguments. */
    assert_int_equal(btf__kmeans(x, 0, 2, 1, &o, &r, &e), BTF_E_ARG);
    assert_int_equal(btf__kmeans(x, 4, 2, 0, &o, &r, &e), BTF_E_ARG);
    x[3] = NAN;
    assert_int_equal(btf__kmeans(x, 4, 2, 2, &o, &r, &e), BTF_E_ARG);
}

/* A generated dataset shared by the segmentation tests. */
static char *dir;
static btf_dataset *ds;

static int setup(void **state)
{
    (void)state;
    dir = tu_tmpdir();
    btf_error e = {0};
    btf_generate_opts g = {.size = 16, .seed = 2};
    char out[4096];
    snprintf(out, sizeof out, "%s/leather", dir);
    if (btf_generate("leather", out, &g, &e) != 0 || btf_dataset_open(out, NULL, &ds, &e) != 0) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
    return 0;
}

static void segmentation_is_consistent(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_segmentation s, t;
    btf_segment_opts o = {.kmeans.seed = 9};
    TU_OK(btf_segment(ds, &o, &s, &e), &e);
    assert_true(s.k >= 2 && s.k <= 20);
    assert_true(strlen(s.reason) > 0);
    print_message("auto: %s\n", s.reason);
    /* The rule: D(K) <= 0.1 D(1) and, for K > 1, D(K-1) > 0.1 D(1). */
    assert_true(s.distortion_by_k[s.k] <= 0.1 * s.distortion_by_k[1]);
    if (s.k > 1)
        assert_true(s.distortion_by_k[s.k - 1] > 0.1 * s.distortion_by_k[1]);
    int n = 81 * 81, sum = 0;
    for (int c = 0; c < s.k; c++) {
        /* The representative is a member of its own subspace. */
        assert_int_equal(s.index[s.rep_view[c] * 81 + s.rep_light[c]], c);
        int count = 0;
        for (int i = 0; i < n; i++)
            count += s.index[i] == c;
        assert_int_equal(count, s.members[c]);
        assert_true(count > 0);
        sum += count;
    }
    assert_int_equal(sum, n);
    /* Determinism: the same seed gives the same table. */
    TU_OK(btf_segment(ds, &o, &t, &e), &e);
    assert_int_equal(s.k, t.k);
    assert_memory_equal(s.index, t.index, (size_t)n);
    btf_segmentation_free(&t);
    /* A fixed K is honoured. */
    btf_segment_opts f = {.subspaces = 4, .kmeans.seed = 9};
    TU_OK(btf_segment(ds, &f, &t, &e), &e);
    assert_int_equal(t.k, 4);
    btf_segmentation_free(&t);
    btf_segment_opts big = {.subspaces = 300};
    assert_int_equal(btf_segment(ds, &big, &t, &e), BTF_E_ARG);
    btf_segmentation_free(&s);
}

static void nearby_directions_share_clusters(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_segmentation s;
    btf_segment_opts o = {.subspaces = 8, .kmeans.seed = 1};
    TU_OK(btf_segment(ds, &o, &s, &e), &e);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    /* For every view, pairs of lights less than 20 degrees apart versus pairs
     * more than 60 degrees apart. */
    long near = 0, near_same = 0, far = 0, far_same = 0;
    for (int v = 0; v < 81; v++)
        for (int a = 0; a < 81; a++)
            for (int b = a + 1; b < 81; b++) {
                double ang = btf_dir_angle(in->lights->dirs[a], in->lights->dirs[b]);
                int same = s.index[v * 81 + a] == s.index[v * 81 + b];
                if (ang < 20.0)
                    near++, near_same += same;
                else if (ang > 60.0)
                    far++, far_same += same;
            }
    double pn = (double)near_same / near, pf = (double)far_same / far;
    print_message("same cluster: near lights %.3f, far lights %.3f\n", pn, pf);
    assert_true(pn > pf + 0.25);
    btf_segmentation_free(&s);
}

static void constant_dataset_gives_one_subspace(void **state)
{
    (void)state;
    /* Identical features: auto picks K = 1 and says why. */
    float f[6 * 9];
    for (int i = 0; i < 54; i++)
        f[i] = (float)(i % 9) / 8.0f;
    btf_segmentation s;
    btf_error e = {0};
    TU_OK(btf__segment_features(f, 2, 3, 9, NULL, &s, &e), &e);
    assert_int_equal(s.k, 1);
    assert_non_null(strstr(s.reason, "same feature"));
    btf_segmentation_free(&s);
}

/* Three groups on a line: the threshold holds at K = 2 (the two close
 * groups together), the split gain then separates them; off, it does not. */
static void split_gain_separates_close_groups(void **state)
{
    (void)state;
    float f[40];
    for (int i = 0; i < 40; i++)
        f[i] = i < 20 ? 0.0f : i < 30 ? 10.0f : 14.0f;
    btf_segmentation s;
    btf_error e = {0};
    btf_segment_opts o = btf_segment_defaults();
    TU_OK(btf__segment_features(f, 5, 8, 1, &o, &s, &e), &e);
    print_message("%s\n", s.reason);
    assert_int_equal(s.k, 3);
    assert_non_null(strstr(s.reason, "split"));
    assert_int_equal(s.index[0], s.index[19]);
    assert_int_not_equal(s.index[20], s.index[30]);
    btf_segmentation_free(&s);
    o.split_gain = -1.0;
    TU_OK(btf__segment_features(f, 5, 8, 1, &o, &s, &e), &e);
    assert_int_equal(s.k, 2);
    assert_int_equal(s.index[20], s.index[30]);
    btf_segmentation_free(&s);
    /* a continuum splits with a slowly falling gain: at most twice the
     * threshold's K */
    float ramp[200];
    for (int i = 0; i < 200; i++)
        ramp[i] = (float)i;
    o.split_gain = 0.0; /* the default */
    TU_OK(btf__segment_features(ramp, 10, 20, 1, &o, &s, &e), &e);
    print_message("ramp: %s\n", s.reason);
    int k_tau = 0;
    while (k_tau < s.k && !(s.distortion_by_k[k_tau + 1] > 0.0 &&
                            s.distortion_by_k[k_tau + 1] <= 0.10 * s.distortion_by_k[1]))
        k_tau++;
    assert_true(s.k > k_tau + 1 && s.k <= 2 * (k_tau + 1));
    btf_segmentation_free(&s);
    o.split_gain = 1.0;
    assert_int_equal(btf__segment_features(f, 5, 8, 1, &o, &s, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "split gain"));
}

static void index_png_and_cli(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_segmentation s;
    btf_segment_opts o = {.subspaces = 3};
    TU_OK(btf_segment(ds, &o, &s, &e), &e);
    const char *png = tu_fmt("%s/index.png", dir);
    TU_OK(btf_segmentation_write_png(&s, 4, png, &e), &e);
    btf_image_header h;
    TU_OK(btf_image_probe(png, &h, &e), &e);
    assert_int_equal(h.width, 81 * 4);
    assert_int_equal(h.height, 81 * 4);
    btf_segmentation_free(&s);

    char out[4096];
    snprintf(out, sizeof out, "%s/seg", dir);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s analyse %s/leather -o %s --stage segment --subspaces 3 > /dev/null",
                           tu_cli(), dir, out), &err);
    if (rc)
        print_error("%s\n", err);
    assert_int_equal(rc, 0);
    free(err);
    const char *files[] = {"index.png", "index.tsv", "subspaces.tsv", "subspace_00.exr",
                           "subspace_02.png"};
    struct stat st;
    for (int i = 0; i < 5; i++)
        assert_int_equal(stat(tu_fmt("%s/%s", out, files[i]), &st), 0);
    assert_int_not_equal(stat(tu_fmt("%s/subspace_03.exr", out), &st), 0);
    /* The subspace image is the real measured image of its representative. */
    btf_image a, b;
    TU_OK(btf_image_read(tu_fmt("%s/subspace_00.exr", out), NULL, &a, &e), &e);
    assert_int_equal(a.width, 16);
    btf_image_free(&a);
    (void)b;
    rc = tu_run(tu_fmt("%s analyse %s/leather -o %s --stage bogus", tu_cli(), dir, out), &err);
    assert_int_equal(rc, 2);
    free(err);
    rc = tu_run(tu_fmt("%s analyse %s/nowhere -o %s --stage segment", tu_cli(), dir, out), &err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, "nowhere"));
    free(err);
}

int main(void)
{
    const struct CMUnitTest unit[] = {
        cmocka_unit_test(cumhist_properties),
        cmocka_unit_test(kmeans_recovers_blobs_deterministically),
        cmocka_unit_test(kmeans_degenerate_inputs),
        cmocka_unit_test(constant_dataset_gives_one_subspace),
        cmocka_unit_test(split_gain_separates_close_groups),
    };
    const struct CMUnitTest on_dataset[] = {
        cmocka_unit_test(segmentation_is_consistent),
        cmocka_unit_test(nearby_directions_share_clusters),
        cmocka_unit_test(index_png_and_cli),
    };
    int failed = cmocka_run_group_tests_name("kmeans", unit, NULL, NULL);
    failed += cmocka_run_group_tests_name("segment", on_dataset, setup, teardown);
    return failed;
}
