/*
 * test_report.c — the report's measurements (src/report/, docs/report.md):
 * the spread of directions, quality per (view, light) pair, the sweep and
 * its resume, the presets, the analysis on shared work, the preview scene.
 *
 * One small generated material (81 x 81 images of 32^2) and its model, made
 * once for the group.
 */
#include "testutil.h"
#include "analyse/analyse.h"
#include "car/car.h"
#include "report/measures.h"
#include "segment/segment.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

static char dataset[4096];
static btf_dataset *ds;
static btf_model model;

static btf_analyse_opts quick(void)
{
    btf_analyse_opts o = btf_analyse_defaults();
    o.segment.subspaces = 3;
    o.segment.kmeans.seed = 1;
    o.fit.levels = 1;
    return o;
}

static int setup(void **state)
{
    tu_setup_dir(state);
    btf_error e = {0};
    snprintf(dataset, sizeof dataset, "%s/leather", tu_dir);
    btf_generate_opts g = btf_generate_defaults();
    g.size = 32;
    g.seed = 2;
    if (btf_generate("leather", dataset, &g, &e) || btf_dataset_open(dataset, NULL, &ds, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    btf_analyse_opts o = quick();
    if (btf_analyse(ds, &o, &model, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    btf_model_free(&model);
    btf_dataset_close(ds);
    return tu_teardown_dir(state);
}

/* The spread starts at the pole, reaches every ring and never repeats. */
static void test_spread(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dirset set;
    TU_OK(btf_dirset_ubo81(&set, &e), &e);
    int idx[81];
    assert_int_equal(btf__spread_directions(&set, 9, idx), 9);
    assert_int_equal(idx[0], 0); /* the pole, and indices ascending */
    int rings_hit[6] = {0};
    for (int i = 0; i < 9; i++) {
        if (i)
            assert_true(idx[i] > idx[i - 1]);
        rings_hit[(int)lround(set.dirs[idx[i]].theta / 15.0)] = 1;
    }
    for (int r = 2; r < 6; r++) /* 15 deg holds 6 of 81: a stride of 9 may skip it */
        assert_true(rings_hit[r]);
    /* n beyond the set: all of it; n < 1: one. */
    assert_int_equal(btf__spread_directions(&set, 500, idx), 81);
    for (int i = 0; i < 81; i++)
        assert_int_equal(idx[i], i);
    assert_int_equal(btf__spread_directions(&set, 0, idx), 1);
    assert_int_equal(btf__spread_directions(NULL, 3, idx), 0);
    btf_dirset_free(&set);
}

typedef struct seen_pairs {
    int calls;
    int bad;
} seen_pairs;

static btf_status count_pair(void *user, int pair, int view, int light, const btf_image *meas,
                             const btf_image *mod, btf_error *err)
{
    (void)pair, (void)view, (void)light, (void)err;
    seen_pairs *s = user;
    __atomic_add_fetch(&s->calls, 1, __ATOMIC_SEQ_CST);
    if (meas->width != mod->width || meas->height != mod->height || mod->channels != 3)
        __atomic_add_fetch(&s->bad, 1, __ATOMIC_SEQ_CST);
    return BTF_OK;
}

/* Every sampled pair measured once, finite, summarised consistently; the
 * same result on 1 and 2 threads. */
static void test_quality(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_quality_opts o = btf_quality_defaults();
    o.views = 4;
    o.lights = 3;
    o.threads = 1;
    seen_pairs seen = {0, 0};
    o.on_pair = count_pair;
    o.on_pair_user = &seen;
    btf_quality q, q2;
    TU_OK(btf__quality_measure(ds, &model, &o, &q, &e), &e);
    assert_int_equal(q.n_pairs, 12);
    assert_int_equal(seen.calls, 12);
    assert_int_equal(seen.bad, 0);
    double sum = 0, worst = 0;
    for (int i = 0; i < q.n_pairs; i++) {
        const btf_pair_quality *p = &q.pairs[i];
        assert_true(isfinite(p->d.combined) && p->d.combined >= 0);
        assert_int_equal(p->subspace, model.index[p->view * 81 + p->light]);
        sum += p->d.combined;
        worst = p->d.combined > worst ? p->d.combined : worst;
        if (i)
            assert_true(p->view > q.pairs[i - 1].view ||
                        (p->view == q.pairs[i - 1].view && p->light > q.pairs[i - 1].light));
    }
    assert_true(fabs(q.mean_combined - sum / 12) < 1e-9);
    assert_true(q.worst_combined == worst && q.pairs[q.worst].d.combined == worst);
    assert_true(q.median_combined <= worst && q.median_combined >= 0);
    assert_int_equal(q.texture_size, 32);
    o.threads = 2;
    o.on_pair = NULL;
    TU_OK(btf__quality_measure(ds, &model, &o, &q2, &e), &e);
    for (int i = 0; i < q.n_pairs; i++)
        assert_true(q.pairs[i].d.combined == q2.pairs[i].d.combined);
    btf__quality_free(&q);
    btf__quality_free(&q2);
}

/* A model that is not of the dataset, and bad options, are errors. */
static void test_quality_errors(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_quality q;
    btf_model tex;
    btf_image img;
    TU_OK(btf_image_alloc(&img, 32, 32, 3, &e), &e);
    for (int i = 0; i < 32 * 32 * 3; i++)
        img.data[i] = 0.5f;
    btf_fit_opts fo = btf_fit_defaults();
    TU_OK(btf_texture_fit(&img, &fo, &tex, &e), &e);
    assert_int_not_equal(btf__quality_measure(ds, &tex, NULL, &q, &e), BTF_OK);
    btf_quality_opts o = btf_quality_defaults();
    o.relief = NAN;
    assert_int_equal(btf__quality_measure(ds, &model, &o, &q, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "relief"));
    assert_int_equal(btf__quality_measure(NULL, &model, NULL, &q, &e), BTF_E_ARG);
    btf_model_free(&tex);
    btf_image_free(&img);
}

/* Shared features and range give the very model a full analysis gives. */
static void test_analyse_shared(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_analyse_opts o = quick();
    float *features;
    int dim;
    TU_OK(btf__dataset_features(ds, &o.segment.features, &features, &dim, &e), &e);
    btf_model range;
    memset(&range, 0, sizeof range);
    TU_OK(btf__analyse_range(ds, &o, &range, &e), &e);
    o.features = features;
    o.feature_dim = dim;
    o.range_from = &range;
    btf_model m;
    TU_OK(btf_analyse(ds, &o, &m, &e), &e);
    unsigned char *a, *b;
    size_t na, nb;
    TU_OK(btf_model_encode(&model, &a, &na, &e), &e);
    TU_OK(btf_model_encode(&m, &b, &nb, &e), &e);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na);
    free(a);
    free(b);
    btf_model_free(&m);
    /* A model without a range map to copy from is an error. */
    btf_model none;
    memset(&none, 0, sizeof none);
    o.range_from = &none;
    assert_int_equal(btf_analyse(ds, &o, &m, &e), BTF_E_ARG);
    free(features);
    btf_model_free(&range);
}

/* The sweep o run again resumes n of its points from its state folder. */
static void assert_sweep_resumes(const btf_sweep_opts *o, int n)
{
    btf_error e = {0};
    btf_sweep again;
    TU_OK(btf__sweep_run(ds, o, &again, &e), &e);
    assert_int_equal(again.resumed, n);
    btf_sweep_free(&again);
}

/* A 2 x 1 x 2 grid (K auto and 2, levels 1, neighbours auto and 4) of
 * small images and a 2 x 2 spread: four points in seconds. */
static btf_sweep_opts small_grid(void)
{
    btf_sweep_opts o = btf_sweep_defaults();
    o.analyse = quick();
    o.analyse.segment.subspaces = 0;
    o.n_subspaces = 2, o.subspaces[0] = 0, o.subspaces[1] = 2;
    o.n_levels = 1, o.levels[0] = 1;
    o.n_neighbours = 2, o.neighbours[0] = 0, o.neighbours[1] = 4;
    o.quality.views = 2, o.quality.lights = 2;
    o.synth_size = 64, o.render_size = 32;
    return o;
}

/* A 2 x 1 x 2 grid: every point measured, finite; the fronts marked; a
 * second run resumes every point from the state folder, and a point file
 * of other options is measured again. */
static void test_sweep_resume(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_sweep_opts o = small_grid();
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/sweep", tu_dir);
    o.state_dir = dir;
    btf_sweep s;
    TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
    assert_int_equal(s.n_points, 4);
    assert_int_equal(s.resumed, 0);
    int fronts = 0, defaults = 0;
    for (int i = 0; i < 4; i++) {
        const btf_sweep_point *p = &s.points[i];
        assert_true(p->k >= 1 && p->bytes > 100);
        assert_true(isfinite(p->mean_combined) && p->worst_combined >= p->mean_combined);
        assert_true(p->analyse_s > 0 && p->synth_s > 0 && p->render_s > 0);
        assert_true(p->gpu_synth_s < 0);
        fronts += p->pareto_bytes;
        defaults += p->is_default;
    }
    assert_int_equal(s.points[2].k, 2);
    assert_true(fronts >= 1);
    assert_int_equal(defaults, 1); /* K auto, levels 1, auto neighbours: the base's */
    assert_true(s.points[0].is_default);
    assert_int_equal(tu_count_files(dir), 4);
    btf_sweep again;
    TU_OK(btf__sweep_run(ds, &o, &again, &e), &e);
    assert_int_equal(again.resumed, 4);
    for (int i = 0; i < 4; i++) {
        /* cJSON keeps 15 significant digits unless that loses more than an ulp */
        assert_true(fabs(again.points[i].mean_combined - s.points[i].mean_combined) <=
                    1e-12 * s.points[i].mean_combined);
        assert_true(again.points[i].bytes == s.points[i].bytes);
    }
    btf_sweep_free(&again);
    /* Other quality options: nothing resumed. A damaged file: measured again. */
    tu_write_file(tu_fmt("%s/point-K0-L1-N0.json", dir), "{\"format\":", 10);
    assert_sweep_resumes(&o, 3);
    o.quality.views = 3;
    assert_sweep_resumes(&o, 0);
    btf_sweep_free(&s);
    /* Bad grids. */
    o.n_levels = 1, o.levels[0] = 99;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "levels 99"));
}

/* A sweep split over 3 shares (docs/cluster.md): each share measures its
 * points alone (point i in share i mod 3: no overlap, the union the grid),
 * the others are missing, not measured; the merge (resume_only) reads all
 * four back with the one-process sweep's figures; a missing point makes
 * the merge an error naming it; bad shares are refused; the report refuses
 * a share (its page comes from the merge). */
static void test_sweep_shares(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_sweep_opts o = small_grid();
    o.seeds = 1;
    char whole[4096], shared[4096];
    snprintf(whole, sizeof whole, "%s/sweep-whole", tu_dir);
    snprintf(shared, sizeof shared, "%s/sweep-shared", tu_dir);
    o.state_dir = whole;
    btf_sweep one;
    TU_OK(btf__sweep_run(ds, &o, &one, &e), &e);
    o.state_dir = shared;
    o.share_count = 3;
    int measured[4] = {0};
    for (int share = 0; share < 3; share++) {
        o.share_index = share;
        btf_sweep s;
        TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
        int missing = 0;
        for (int i = 0; i < 4; i++) {
            const btf_sweep_point *p = &s.points[i];
            int mine = i % 3 == share;
            if (mine) { /* measured now: not read back, not missing */
                assert_false(p->resumed);
                assert_false(p->missing);
                measured[i]++;
            } else {
                assert_true(p->missing || p->resumed);
                assert_false(p->missing && (p->pareto_bytes || p->pareto_time));
            }
            missing += p->missing;
        }
        assert_int_equal(s.n_missing, missing);
        btf_sweep_free(&s);
    }
    for (int i = 0; i < 4; i++)
        assert_int_equal(measured[i], 1); /* no overlap, none left out */
    o.share_count = o.share_index = 0;
    o.resume_only = 1;
    btf_sweep merged;
    TU_OK(btf__sweep_run(ds, &o, &merged, &e), &e);
    assert_int_equal(merged.resumed, 4);
    assert_int_equal(merged.n_missing, 0);
    for (int i = 0; i < 4; i++) {
        const btf_sweep_point *a = &merged.points[i], *b = &one.points[i];
        assert_int_equal(a->k, b->k);
        assert_true(a->bytes == b->bytes);
        assert_true(fabs(a->mean_combined - b->mean_combined) <= 1e-12 * b->mean_combined);
        assert_int_equal(a->pareto_bytes, b->pareto_bytes);
    }
    btf_sweep_free(&merged);
    btf_sweep_free(&one);
    /* a point gone: the merge names it and measures nothing */
    assert_int_equal(remove(tu_fmt("%s/point-K2-L1-N4.json", shared)), 0);
    assert_int_equal(btf__sweep_run(ds, &o, &merged, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "1 of the sweep's 4 points are missing"));
    assert_non_null(strstr(e.msg, "K 2, levels 1, neighbours 4"));
    assert_int_equal(tu_count_files(shared), 3);
    /* bad shares */
    o.resume_only = 0;
    o.share_count = 2, o.share_index = 2;
    assert_int_equal(btf__sweep_run(ds, &o, &merged, &e), BTF_E_ARG);
    o.share_count = -1, o.share_index = 0;
    assert_int_equal(btf__sweep_run(ds, &o, &merged, &e), BTF_E_ARG);
    btf_report_opts ro = btf_report_defaults();
    ro.sweep = 1;
    ro.sweep_opts.share_count = 2;
    assert_int_equal(btf_report_write(ds, &model, tu_fmt("%s/share-report", tu_dir), &ro, NULL,
                                      &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "merge"));
}

/* The commands of a split sweep: --points writes the share's points and
 * nothing else; --merge builds the page from them; misuse is one line. */
static void test_sweep_share_commands(void **state)
{
    (void)state;
    btf_error e = {0};
    char mpath[4096], out[4096];
    snprintf(mpath, sizeof mpath, "%s/share-model.btfcar", tu_dir);
    snprintf(out, sizeof out, "%s/share-cli", tu_dir);
    TU_OK(btf_model_write(mpath, &model, &e), &e);
    const char *grid = "--sweep --sweep-subspaces auto --sweep-levels 1 --sweep-neighbours "
                       "auto,4 --sweep-seeds 1 --views 2 --lights 2";
    char *cmd = strdup(tu_fmt("%s report %s %s %s", tu_cli(), dataset, mpath, grid));
    int st;
    char *o = tu_capture(tu_fmt("%s --points 1/2 -o %s", cmd, out), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(o, "sweep share   1/2: 1 of the 2 points"));
    free(o);
    assert_int_equal(tu_count_files(out), 1); /* sweep/ only: no page */
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s --merge -o %s", cmd, out), &err), 1);
    assert_non_null(strstr(err, "1 of the sweep's 2 points are missing"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s -q --points 0/2 -o %s", cmd, out), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s -q --merge -o %s", cmd, out), NULL), 0);
    struct stat sb;
    assert_int_equal(stat(tu_fmt("%s/index.html", out), &sb), 0);
    /* shares in separate folders, gathered by the merge */
    assert_int_equal(tu_run(tu_fmt("%s -q --points 0/2 -o %s.a", cmd, out), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s -q --points 1/2 -o %s.b", cmd, out), NULL), 0);
    o = tu_capture(tu_fmt("%s --merge-from %s.a --merge-from %s.b -o %s.c", cmd, out, out, out),
                   &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(o, "2 point files gathered from 2 folders"));
    assert_non_null(strstr(o, "2 resumed"));
    free(o);
    assert_int_equal(stat(tu_fmt("%s.c/index.html", out), &sb), 0);
    err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s --merge-from %s.nope -o %s.d", cmd, out, out), &err), 1);
    assert_non_null(strstr(err, ".nope"));
    free(err);
    const char *bad[] = {"--points 2/2", "--points 1/2 --merge", "--points x"};
    for (int i = 0; i < 3; i++) {
        err = NULL;
        assert_int_not_equal(tu_run(tu_fmt("%s %s -o %s.bad", cmd, bad[i], out), &err), 0);
        assert_non_null(err);
        assert_true(strchr(err, '\n') == err + strlen(err) - 1); /* one line */
        free(err);
    }
    err = NULL;
    assert_int_not_equal(tu_run(tu_fmt("%s report %s %s --points 0/2 -o %s.bad", tu_cli(),
                                       dataset, mpath, out), &err), 0);
    assert_non_null(strstr(err, "--sweep"));
    free(err);
    free(cmd);
}

/* The library report (btf_library_write): rows read from report folders,
 * the figures of each report.json, relative links; missing or foreign
 * folders named together and nothing written. */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return strdup(buf);
}

static void test_library(void **state)
{
    (void)state;
    btf_error e = {0};
    char a[4096], lib[4096];
    snprintf(a, sizeof a, "%s/lib-report", tu_dir);
    snprintf(lib, sizeof lib, "%s/lib-page", tu_dir);
    btf_report_opts ro = btf_report_defaults();
    ro.quality.views = 2, ro.quality.lights = 2;
    btf_report_summary sum;
    TU_OK(btf_report_write(ds, &model, a, &ro, &sum, &e), &e);
    const char *two[2] = {a, a};
    int rows = 0;
    TU_OK(btf_library_write(two, 2, lib, &rows, &e), &e);
    assert_int_equal(rows, 2);
    char *json = slurp(tu_fmt("%s/library.json", lib));
    char want[64];
    snprintf(want, sizeof want, "\"model_bytes\":\t%llu", (unsigned long long)sum.model_bytes);
    assert_non_null(strstr(json, want));
    assert_non_null(strstr(json, "\"report\":\t\"../lib-report\""));
    assert_non_null(strstr(json, "\"format\":\t\"btfcar-library\""));
    free(json);
    json = slurp(tu_fmt("%s/index.html", lib));
    assert_non_null(strstr(json, "href=\"../lib-report/index.html\""));
    assert_non_null(strstr(json, "src=\"../lib-report/sphere.png\""));
    free(json);
    /* two folders missing: both named, nothing written */
    const char *bad[3] = {a, tu_fmt("%s/no-such", tu_dir), tu_fmt("%s/leather", tu_dir)};
    char other[4096];
    snprintf(other, sizeof other, "%s/lib-bad", tu_dir);
    assert_int_not_equal(btf_library_write(bad, 3, other, &rows, &e), BTF_OK);
    assert_non_null(strstr(e.msg, "2 of 3 material reports"));
    assert_non_null(strstr(e.msg, "no-such"));
    struct stat sb;
    assert_int_not_equal(stat(other, &sb), 0);
    /* a JSON that is not a report */
    mkdir(tu_fmt("%s/fake", tu_dir), 0777);
    tu_write_file(tu_fmt("%s/fake/report.json", tu_dir), "{\"format\": \"x\"}", 15);
    const char *fake[1] = {tu_fmt("%s/fake", tu_dir)};
    assert_int_equal(btf_library_write(fake, 1, other, &rows, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "not a btfcar report"));
}

/* A sweep of one setting (K, L, N), with and without the layers, tiny
 * quality and sizes, its state in tu_dir/name (the path into dir). */
static btf_sweep_opts one_setting_sweep(int k, int l, int n, const char *name, char *dir,
                                        size_t dir_size)
{
    btf_sweep_opts o = btf_sweep_defaults();
    o.analyse = quick();
    o.analyse.segment.subspaces = 0;
    o.n_subspaces = 1, o.subspaces[0] = k;
    o.n_levels = 1, o.levels[0] = l;
    o.n_neighbours = 1, o.neighbours[0] = n;
    o.n_plain = 2, o.plain[0] = 0, o.plain[1] = 1;
    o.quality.views = 2, o.quality.lights = 2;
    o.synth_size = 64, o.render_size = 32;
    snprintf(dir, dir_size, "%s/%s", tu_dir, name);
    o.state_dir = dir;
    return o;
}

/* The structure axis: each setting with the layers and as format 1.3's
 * plain model; the plain points have no structure, their own state files
 * (the layered ones keep their names), and only a layered point is the
 * default. */
static void test_sweep_structure(void **state)
{
    (void)state;
    btf_error e = {0};
    char dir[4096];
    btf_sweep_opts o = one_setting_sweep(0, 1, 0, "sweep-structure", dir, sizeof dir);
    btf_sweep s;
    TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
    assert_int_equal(s.n_points, 2);
    assert_int_equal(s.points[0].setting.plain, 0);
    assert_int_equal(s.points[1].setting.plain, 1);
    assert_true(s.points[0].is_default && !s.points[1].is_default);
    for (int i = 0; i < 2; i++)
        assert_true(isfinite(s.points[i].mean_combined) && s.points[i].bytes > 100);
    assert_int_equal(access(tu_fmt("%s/point-K0-L1-N0.json", dir), F_OK), 0);
    assert_int_equal(access(tu_fmt("%s/point-K0-L1-N0-plain.json", dir), F_OK), 0);
    assert_sweep_resumes(&o, 2);
    btf_sweep_free(&s);
    o.n_plain = 2, o.plain[0] = o.plain[1] = 1;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
    o.n_plain = 1, o.plain[0] = 7;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
}

/* The range-size axis: a layered setting at the analysed resolution and
 * with a small tile (no structure layer: fewer bytes), the plain point once
 * (its own tile whatever the axis); state files named by the size; sizes
 * out of range refused. */
static void test_sweep_range_size(void **state)
{
    (void)state;
    btf_error e = {0};
    char dir[4096];
    btf_sweep_opts o = one_setting_sweep(2, 1, 4, "sweep-range", dir, sizeof dir);
    o.n_range_sizes = 2, o.range_sizes[0] = 0, o.range_sizes[1] = 8;
    btf_sweep s;
    TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
    assert_int_equal(s.n_points, 3);
    assert_int_equal(s.points[0].setting.range_size, 0);
    assert_int_equal(s.points[1].setting.range_size, 8);
    assert_int_equal(s.points[2].setting.range_size, 0);
    assert_int_equal(s.points[2].setting.plain, 1);
    assert_true(s.points[1].bytes < s.points[0].bytes);
    for (int i = 0; i < 3; i++)
        assert_true(isfinite(s.points[i].mean_combined) && !s.points[i].is_default);
    assert_int_equal(access(tu_fmt("%s/point-K2-L1-N4.json", dir), F_OK), 0);
    assert_int_equal(access(tu_fmt("%s/point-K2-L1-N4-R8.json", dir), F_OK), 0);
    assert_int_equal(access(tu_fmt("%s/point-K2-L1-N4-plain.json", dir), F_OK), 0);
    assert_sweep_resumes(&o, 3);
    btf_sweep_free(&s);
    o.range_sizes[1] = 3;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "range size 3"));
    o.range_sizes[1] = 5000;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
}

/* The point's quality over seeds: the mean of btf__quality_measure with
 * seeds S and S + 1 on the setting's model, and their standard deviation;
 * another seed count measures again; a count out of range is refused. */
static void test_sweep_seeds(void **state)
{
    (void)state;
    btf_error e = {0};
    char dir[4096];
    btf_sweep_opts o = one_setting_sweep(2, 1, 4, "sweep-seeds", dir, sizeof dir);
    o.n_plain = 1, o.plain[0] = 0;
    o.seeds = 2;
    btf_sweep s;
    TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
    assert_int_equal(s.n_points, 1);
    assert_int_equal(s.seeds, 2);
    btf_analyse_opts a = quick();
    a.segment.subspaces = 2;
    btf_offset fam[BTF_CAR_MAX_NEIGHBOURS];
    btf__car_candidate_offsets(fam);
    memcpy(a.fit.car.fixed, fam, 4 * sizeof fam[0]);
    a.fit.car.n_fixed = 4;
    btf_model m;
    TU_OK(btf_analyse(ds, &a, &m, &e), &e);
    double d[2];
    for (int i = 0; i < 2; i++) {
        btf_quality_opts q = o.quality;
        q.seed = o.quality.seed + (uint64_t)i;
        q.threads = 1;
        btf_quality r;
        TU_OK(btf__quality_measure(ds, &m, &q, &r, &e), &e);
        d[i] = r.mean_combined;
        btf__quality_free(&r);
    }
    btf_model_free(&m);
    assert_true(d[0] != d[1]); /* the seeds do move the figure */
    const btf_sweep_point *p = &s.points[0];
    assert_true(fabs(p->mean_combined - 0.5 * (d[0] + d[1])) <= 1e-12 * p->mean_combined);
    assert_true(fabs(p->seed_spread - fabs(d[0] - d[1]) / sqrt(2.0)) <= 1e-9 * p->seed_spread);
    assert_sweep_resumes(&o, 1);
    btf_sweep_free(&s);
    o.seeds = 1;
    TU_OK(btf__sweep_run(ds, &o, &s, &e), &e);
    assert_int_equal(s.resumed, 0);
    assert_true(s.points[0].seed_spread == 0.0);
    assert_true(fabs(s.points[0].mean_combined - d[0]) <= 1e-12 * d[0]);
    btf_sweep_free(&s);
    o.seeds = BTF_SWEEP_MAX_SEEDS + 1;
    assert_int_equal(btf__sweep_run(ds, &o, &s, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "seeds"));
}

static void test_presets(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *const *names = btf_analyse_preset_names();
    int n = 0;
    for (; names[n]; n++) {
        btf_analyse_opts o = btf_analyse_defaults();
        TU_OK(btf_analyse_preset(names[n], &o, &e), &e);
        assert_true(o.fit.car.n_fixed >= 0 && o.fit.car.n_fixed <= BTF_CAR_MAX_NEIGHBOURS);
        assert_true(o.fit.levels >= 0 && o.fit.levels <= BTF_MAX_LEVELS);
    }
    assert_int_equal(n, 3);
    /* The documented settings (docs/report.md, "Presets"). */
    static const struct { const char *name; int k, l, n; } want[] = {
        {"fast", 2, 1, 4}, {"balanced", 4, 1, 4}, {"accurate", 8, 0, 0}};
    btf_analyse_opts o = btf_analyse_defaults();
    for (int i = 0; i < 3; i++) {
        o = btf_analyse_defaults();
        TU_OK(btf_analyse_preset(want[i].name, &o, &e), &e);
        assert_int_equal(o.segment.subspaces, want[i].k);
        assert_int_equal(o.fit.levels, want[i].l);
        assert_int_equal(o.fit.car.n_fixed, want[i].n);
        if (want[i].n) { /* the family's first n */
            btf_offset fam[BTF_CAR_MAX_NEIGHBOURS];
            btf__car_candidate_offsets(fam);
            assert_memory_equal(o.fit.car.fixed, fam, (size_t)want[i].n * sizeof fam[0]);
        }
    }
    assert_int_equal(btf_analyse_preset("fastest", &o, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "fastest"));
    assert_int_equal(btf_analyse_preset(NULL, &o, &e), BTF_E_ARG);
    /* The family the fixed orders are cut from: causal, distinct. */
    btf_offset fam[BTF_CAR_MAX_NEIGHBOURS];
    assert_int_equal(btf__car_candidate_offsets(fam), BTF_CAR_MAX_NEIGHBOURS);
    for (int i = 0; i < BTF_CAR_MAX_NEIGHBOURS; i++) {
        assert_true(fam[i].row < 0 || (fam[i].row == 0 && fam[i].col < 0));
        for (int j = 0; j < i; j++)
            assert_false(fam[i].row == fam[j].row && fam[i].col == fam[j].col);
    }
}

/* The preview scene renders: the sphere is in the middle, the corners are
 * background, the pole light and a horizon light both finite. */
static void test_sphere_scene(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_dir lights[] = {{0, 0}, {90, 270}, {45, 135}};
    for (int i = 0; i < 3; i++) {
        btf_scene s;
        TU_OK(btf_scene_sphere(lights[i], 64.0, &s, &e), &e);
        btf_render_opts ro = btf_render_defaults();
        ro.width = ro.height = 48;
        btf_image img = {0};
        TU_OK(btf_render_scene(&model, &s, &ro, &img, NULL, &e), &e);
        for (int k = 0; k < 48 * 48 * 3; k++)
            assert_true(isfinite(img.data[k]) && img.data[k] >= 0);
        assert_true(fabsf(img.data[0] - 0.04f) < 1e-6); /* a corner: the background */
        btf_image_free(&img);
        btf_scene_free(&s);
    }
    btf_scene s;
    assert_int_equal(btf_scene_sphere((btf_dir){95, 0}, 64.0, &s, &e), BTF_E_ARG);
    assert_int_equal(btf_scene_sphere((btf_dir){45, 0}, 0.0, &s, &e), BTF_E_ARG);
    assert_int_equal(btf_scene_sphere((btf_dir){45, NAN}, 1.0, &s, &e), BTF_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spread),        cmocka_unit_test(test_quality),
        cmocka_unit_test(test_quality_errors), cmocka_unit_test(test_analyse_shared),
        cmocka_unit_test(test_sweep_resume),  cmocka_unit_test(test_sweep_shares),
        cmocka_unit_test(test_sweep_share_commands),
        cmocka_unit_test(test_library),  cmocka_unit_test(test_sweep_structure),
        cmocka_unit_test(test_sweep_range_size), cmocka_unit_test(test_sweep_seeds),
        cmocka_unit_test(test_presets),
        cmocka_unit_test(test_sphere_scene),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
