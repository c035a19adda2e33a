/*
 * sweep.c — the speed/accuracy trade, measured (docs/report.md,
 * "The sweep"): the dataset analysed under a grid of settings — the number
 * of subspace images K (paper section II.A), the pyramid levels and the CAR
 * neighbourhood (section II.C) — and each model timed, sized and measured,
 * so that users choose a setting knowing its price. The per-image features
 * and the range map do not depend on these settings: they are computed once
 * and shared (btf_analyse_opts.features, .range_from). Settings run in
 * parallel, one per thread, each single-threaded inside, so that their
 * times compare; every finished point is written to the state folder at
 * once and read back by a later run, so an interrupted sweep resumes.
 */
#include "analyse/analyse.h"
#include "car/car.h"
#include "core/core.h"
#include "report/report.h"
#include "segment/segment.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The sweep's sphere frame: lit from 45 degrees above, upper left. */
#define SWEEP_LIGHT_THETA 45.0
#define SWEEP_LIGHT_PHI 135.0

btf_sweep_opts btf_sweep_defaults(void)
{
    btf_sweep_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    static const int k[] = {0, 2, 4, 8}, l[] = {0, 1, 2, 3}, n[] = {0, 4, 8, 12};
    o.n_subspaces = o.n_levels = o.n_neighbours = 4;
    memcpy(o.subspaces, k, sizeof k);
    memcpy(o.levels, l, sizeof l);
    memcpy(o.neighbours, n, sizeof n);
    o.analyse = btf_analyse_defaults();
    o.quality = btf_quality_defaults();
    o.seeds = 3;
    o.synth_size = 512;
    o.render_size = 256;
    return o;
}

static btf_status resolve(const btf_sweep_opts *in, btf_sweep_opts *o, btf_error *err)
{
    btf_sweep_opts d = btf_sweep_defaults();
    if (btf__opts_take(o, sizeof *o, in, &d, "btf_sweep_run", err))
        return BTF_E_ARG;
    if (o->n_subspaces == 0) {
        o->n_subspaces = d.n_subspaces;
        memcpy(o->subspaces, d.subspaces, sizeof d.subspaces);
    }
    if (o->n_levels == 0) {
        o->n_levels = d.n_levels;
        memcpy(o->levels, d.levels, sizeof d.levels);
    }
    if (o->n_neighbours == 0) {
        o->n_neighbours = d.n_neighbours;
        memcpy(o->neighbours, d.neighbours, sizeof d.neighbours);
    }
    if (o->n_plain == 0)
        o->n_plain = 1, o->plain[0] = 0;
    if (o->n_range_sizes == 0)
        o->n_range_sizes = 1, o->range_sizes[0] = 0;
    if (o->n_range_sizes < 0 || o->n_range_sizes > BTF_SWEEP_MAX_VALUES)
        return btf__fail(err, BTF_E_ARG, "sweep: at most %d range sizes", BTF_SWEEP_MAX_VALUES);
    for (int i = 0; i < o->n_range_sizes; i++)
        if (o->range_sizes[i] != 0 && (o->range_sizes[i] < 4 || o->range_sizes[i] > 4096))
            return btf__fail(err, BTF_E_ARG,
                             "sweep: range size %d: expected 0 (the analysed resolution) or "
                             "4..4096", o->range_sizes[i]);
    if (o->n_plain < 0 || o->n_plain > 2 || (o->n_plain == 2 && o->plain[0] == o->plain[1]))
        return btf__fail(err, BTF_E_ARG, "sweep: %d structure values (expected on, off or both)",
                         o->n_plain);
    for (int i = 0; i < o->n_plain; i++)
        if (o->plain[i] != 0 && o->plain[i] != 1)
            return btf__fail(err, BTF_E_ARG, "sweep: structure value %d (expected 0: on, 1: off)",
                             o->plain[i]);
    if (o->share_count < 0 || o->share_count > 100000 ||
        (o->share_count > 0 && (o->share_index < 0 || o->share_index >= o->share_count)) ||
        (o->share_count == 0 && o->share_index != 0))
        return btf__fail(err, BTF_E_ARG, "sweep: share %d of %d (expected 0 <= I < N)",
                         o->share_index, o->share_count);
    if (o->resume_only && !o->state_dir)
        return btf__fail(err, BTF_E_ARG, "sweep: a merge (resume_only) needs the state folder");
    if (o->seeds == 0)
        o->seeds = d.seeds;
    if (o->seeds < 1 || o->seeds > BTF_SWEEP_MAX_SEEDS)
        return btf__fail(err, BTF_E_ARG, "sweep: %d seeds (expected 1..%d)", o->seeds,
                         BTF_SWEEP_MAX_SEEDS);
    if (o->synth_size == 0)
        o->synth_size = d.synth_size;
    if (o->render_size == 0)
        o->render_size = d.render_size;
    if (o->n_subspaces < 0 || o->n_subspaces > BTF_SWEEP_MAX_VALUES || o->n_levels < 0 ||
        o->n_levels > BTF_SWEEP_MAX_VALUES || o->n_neighbours < 0 ||
        o->n_neighbours > BTF_SWEEP_MAX_VALUES)
        return btf__fail(err, BTF_E_ARG, "sweep: at most %d values per setting",
                         BTF_SWEEP_MAX_VALUES);
    for (int i = 0; i < o->n_subspaces; i++)
        if (o->subspaces[i] < 0 || o->subspaces[i] > 255)
            return btf__fail(err, BTF_E_ARG, "sweep: subspaces %d: expected 0 (auto) or 1..255",
                             o->subspaces[i]);
    for (int i = 0; i < o->n_levels; i++)
        if (o->levels[i] < 0 || o->levels[i] > BTF_MAX_LEVELS)
            return btf__fail(err, BTF_E_ARG, "sweep: levels %d: expected 0 (auto) or 1..%d",
                             o->levels[i], BTF_MAX_LEVELS);
    for (int i = 0; i < o->n_neighbours; i++)
        if (o->neighbours[i] < 0 || o->neighbours[i] > BTF_CAR_MAX_NEIGHBOURS)
            return btf__fail(err, BTF_E_ARG,
                             "sweep: neighbours %d: expected 0 (auto) or 1..%d",
                             o->neighbours[i], BTF_CAR_MAX_NEIGHBOURS);
    if (o->synth_size < 8 || o->synth_size > 8192 || o->render_size < 16 ||
        o->render_size > 4096)
        return btf__fail(err, BTF_E_ARG, "sweep: synthesis size %d (8..8192) or render size %d "
                         "(16..4096) out of range", o->synth_size, o->render_size);
    return BTF_OK;
}

typedef struct sweep_ctx {
    const btf_dataset *ds;
    const btf_dataset_info *in;
    const btf_sweep_opts *o;
    const float *features;
    const float *means;     /* each image's mean colour (the pair gains) */
    int dim;
    const btf_model *range;
    btf_sweep *s;
    pthread_mutex_t gpu_lock;
    char fingerprint[1024];
} sweep_ctx;

/* The settings and options a point's figures depend on: a state file
 * written under others is measured again. */
static void make_fingerprint(sweep_ctx *c)
{
    const btf_dataset_info *in = c->in;
    const btf_sweep_opts *o = c->o;
    snprintf(c->fingerprint, sizeof c->fingerprint,
             "btfcar %s; dataset %s %dx%d views x lights %dx%d, %llu bytes; seed %llu; "
             "quality %s %dx%d relief %g, %d seeds; synth %d; render %d; range %s; cells %s",
             BTF_VERSION_STRING, in->root, in->width, in->height, in->n_views, in->n_lights,
             (unsigned long long)in->bytes_on_disk, (unsigned long long)o->quality.seed,
             o->quality.all ? "all" : "spread", o->quality.views, o->quality.lights,
             o->quality.relief, o->seeds, o->synth_size, o->render_size,
             o->analyse.no_range ? "none" : "yes", o->analyse.no_cells ? "none" : "yes");
}

static void point_name(const btf_sweep_setting *s, char *buf, size_t n)
{
    /* the structure layers' own points keep the names of format 1.4's */
    char range[24] = "";
    if (s->range_size)
        snprintf(range, sizeof range, "-R%d", s->range_size);
    snprintf(buf, n, "point-K%d-L%d-N%d%s%s.json", s->subspaces, s->levels, s->neighbours,
             range, s->plain ? "-plain" : "");
}

static btf_status state_path(const sweep_ctx *c, const btf_sweep_setting *s, char *path,
                             size_t n, btf_error *err)
{
    char name[64];
    point_name(s, name, sizeof name);
    return btf__path_join(path, n, c->o->state_dir, name, err);
}

static double num(const cJSON *o, const char *key, int *ok)
{
    const cJSON *j = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsNumber(j) || !isfinite(j->valuedouble)) {
        *ok = 0;
        return 0.0;
    }
    return j->valuedouble;
}

int btf__sweep_point_parse(const char *text, size_t n, const char *fingerprint,
                           btf_sweep_point *p)
{
    cJSON *j = cJSON_ParseWithLength(text, n);
    if (!j)
        return 0;
    const cJSON *fp = cJSON_GetObjectItemCaseSensitive(j, "fingerprint");
    int ok = cJSON_IsString(fp) && fp->valuestring && !strcmp(fp->valuestring, fingerprint);
    btf_sweep_point q = *p;
    ok = ok && num(j, "subspaces", &ok) == p->setting.subspaces &&
         num(j, "levels", &ok) == p->setting.levels &&
         num(j, "neighbours", &ok) == p->setting.neighbours;
    /* "plain" is new: a point written without it has the layers */
    const cJSON *pl = cJSON_GetObjectItemCaseSensitive(j, "plain");
    ok = ok && (pl ? cJSON_IsNumber(pl) && pl->valuedouble == p->setting.plain
                   : p->setting.plain == 0);
    /* "range_size" likewise: a point written without it has the full map */
    const cJSON *rs = cJSON_GetObjectItemCaseSensitive(j, "range_size");
    ok = ok && (rs ? cJSON_IsNumber(rs) && rs->valuedouble == p->setting.range_size
                   : p->setting.range_size == 0);
    double k = num(j, "k", &ok), bytes = num(j, "bytes", &ok);
    q.analyse_s = num(j, "analyse_s", &ok);
    q.synth_s = num(j, "synth_s", &ok);
    q.gpu_synth_s = num(j, "gpu_synth_s", &ok);
    q.render_s = num(j, "render_s", &ok);
    q.mean_combined = num(j, "mean_combined", &ok);
    q.worst_combined = num(j, "worst_combined", &ok);
    q.seed_spread = num(j, "seed_spread", &ok);
    cJSON_Delete(j);
    /* Numbers a measurement can give, and nothing a cast would mangle. */
    if (!ok || !(k >= 1 && k <= 255) || !(bytes >= 1 && bytes <= 1e15) || q.analyse_s < 0 ||
        q.synth_s < 0 || q.render_s < 0 || q.mean_combined < 0 ||
        q.worst_combined < q.mean_combined || q.seed_spread < 0)
        return 0;
    q.k = (int)k;
    q.bytes = (uint64_t)bytes;
    q.resumed = 1;
    *p = q;
    return 1;
}

/* A point read back from its state file: 1 when it is there, whole, and of
 * this dataset and these options; 0 otherwise (then it is measured). */
static int read_point(const sweep_ctx *c, btf_sweep_point *p)
{
    char path[4096];
    btf_error e = {0};
    unsigned char *data = NULL;
    size_t n = 0;
    if (!c->o->state_dir || state_path(c, &p->setting, path, sizeof path, &e) ||
        btf__read_file(path, 1 << 20, &data, &n, &e))
        return 0;
    int ok = btf__sweep_point_parse((const char *)data, n, c->fingerprint, p);
    free(data);
    return ok;
}

static btf_status write_point(const sweep_ctx *c, const btf_sweep_point *p, btf_error *err)
{
    if (!c->o->state_dir)
        return BTF_OK;
    char path[4096];
    btf_status rc = state_path(c, &p->setting, path, sizeof path, err);
    if (rc)
        return rc;
    cJSON *j = cJSON_CreateObject();
    if (!j)
        return btf__fail(err, BTF_E_NOMEM, "out of memory");
    cJSON_AddStringToObject(j, "format", "btfcar-sweep-point");
    cJSON_AddStringToObject(j, "fingerprint", c->fingerprint);
    cJSON_AddNumberToObject(j, "subspaces", p->setting.subspaces);
    cJSON_AddNumberToObject(j, "levels", p->setting.levels);
    cJSON_AddNumberToObject(j, "neighbours", p->setting.neighbours);
    cJSON_AddNumberToObject(j, "plain", p->setting.plain);
    cJSON_AddNumberToObject(j, "range_size", p->setting.range_size);
    cJSON_AddNumberToObject(j, "k", p->k);
    cJSON_AddNumberToObject(j, "analyse_s", p->analyse_s);
    cJSON_AddNumberToObject(j, "synth_s", p->synth_s);
    cJSON_AddNumberToObject(j, "gpu_synth_s", p->gpu_synth_s);
    cJSON_AddNumberToObject(j, "render_s", p->render_s);
    cJSON_AddNumberToObject(j, "bytes", (double)p->bytes);
    cJSON_AddNumberToObject(j, "mean_combined", p->mean_combined);
    cJSON_AddNumberToObject(j, "worst_combined", p->worst_combined);
    cJSON_AddNumberToObject(j, "seed_spread", p->seed_spread);
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text)
        return btf__fail(err, BTF_E_NOMEM, "out of memory");
    rc = btf_write_file_atomic(path, text, strlen(text), err);
    cJSON_free(text);
    return rc;
}

/* The analysis options of one setting, single-threaded, on the shared work. */
static btf_analyse_opts setting_opts(const sweep_ctx *c, const btf_sweep_setting *s)
{
    btf_analyse_opts a = c->o->analyse;
    a.segment.subspaces = s->subspaces;
    a.segment.features.threads = 1;
    a.photostereo.threads = 1;
    a.fit.levels = s->levels;
    a.fit.car.n_fixed = 0;
    if (s->neighbours > 0) {
        btf_offset fam[BTF_CAR_MAX_NEIGHBOURS];
        btf__car_candidate_offsets(fam);
        memcpy(a.fit.car.fixed, fam, (size_t)s->neighbours * sizeof fam[0]);
        a.fit.car.n_fixed = s->neighbours;
    }
    a.fit.car.warn = NULL;
    a.progress = NULL;
    a.report = NULL;
    a.features = c->features;
    a.feature_dim = c->dim;
    a.means = c->means;
    a.range_from = c->range;
    if (s->plain) { /* format 1.3's model: its own small tile, no layers */
        a.no_structure = 1;
        a.no_gains = 1;
        a.range_size = 64;
        a.range_from = NULL;
    } else if (s->range_size) { /* its own tile: photometric stereo again, timed */
        a.range_size = s->range_size;
        a.range_from = NULL;
    }
    return a;
}

static int drop_image(void *user, int i, btf_image *img, btf_error *err)
{
    (void)user, (void)i, (void)img, (void)err;
    return 0; /* freed by the synthesis */
}

/* Subspaces 0 .. n - 1, for a batch of every subspace image; NULL when out
 * of memory. */
static int *every_subspace(int n, btf_error *err)
{
    int *ks = btf__alloc((size_t)n, sizeof(int), err);
    for (int k = 0; ks && k < n; k++)
        ks[k] = k;
    return ks;
}

/* The timed syntheses' options: synth_size^2, the quality's seed. */
static btf_synth_opts timed_synth_opts(const btf_sweep_opts *o)
{
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = o->synth_size;
    so.seed = o->quality.seed;
    return so;
}

/* Every subspace image at synth_size^2 on the CPU (the reference), in one
 * batch as `btfcar synthesise` makes them (colour matching beside the
 * fields, btf_synthesise_each). */
static btf_status time_synthesis(const btf_model *m, const btf_sweep_opts *o, double *seconds,
                                 btf_error *err)
{
    int n = m->n_subspaces;
    int *ks = every_subspace(n, err);
    if (!ks)
        return BTF_E_NOMEM;
    btf_synth_opts so = timed_synth_opts(o);
    double t0 = btf__now();
    btf_status rc = btf_synthesise_each(m, ks, n, &so, drop_image, NULL, err);
    *seconds = btf__now() - t0;
    free(ks);
    return rc;
}

/* The same on the GPU, all subspaces in one call; one setting at a time
 * holds the device (the mutex), so the times are the device's alone. */
static btf_status time_gpu_synthesis(const btf_model *m, const btf_sweep_opts *o,
                                     pthread_mutex_t *gpu_lock, double *seconds, btf_error *err)
{
    *seconds = -1.0;
    if (!o->gpu)
        return BTF_OK;
    int n = m->n_subspaces;
    int *ks = every_subspace(n, err);
    btf_image *imgs = btf__calloc((size_t)n, sizeof(btf_image), err);
    if (!ks || !imgs) {
        free(ks);
        free(imgs);
        return BTF_E_NOMEM;
    }
    btf_synth_opts so = timed_synth_opts(o);
    pthread_mutex_lock(gpu_lock);
    double t0 = btf__now();
    btf_status rc = btf_gpu_synthesise(o->gpu, m, ks, n, &so, imgs, err);
    *seconds = btf__now() - t0;
    pthread_mutex_unlock(gpu_lock);
    for (int k = 0; k < n; k++)
        btf_image_free(&imgs[k]);
    free(imgs);
    free(ks);
    return rc;
}

/* The sphere frame, the whole render (trace, needed subspaces, synthesis,
 * shading), one thread. */
static btf_status time_render(const btf_model *m, const btf_sweep_opts *o, double *seconds,
                              btf_error *err)
{
    btf_scene sc;
    btf_dir light = {SWEEP_LIGHT_THETA, SWEEP_LIGHT_PHI};
    btf_status rc = btf_scene_sphere(light, 128.0, &sc, err);
    if (rc)
        return rc;
    btf_render_opts ro = btf_render_defaults();
    ro.width = ro.height = o->render_size;
    ro.seed = o->quality.seed;
    ro.threads = 1;
    btf_image img = {0};
    double t0 = btf__now();
    rc = btf_render_scene(m, &sc, &ro, &img, NULL, err);
    *seconds = btf__now() - t0;
    btf_image_free(&img);
    btf_scene_free(&sc);
    return rc;
}

/* The point's quality over the sweep's seeds: one synthesis seed's figure
 * moves by about as much as many of the grid's steps (docs/report.md, "The
 * sweep"), so the fronts are drawn through the mean; the spread between the
 * seeds is kept beside it. */
static btf_status measure_quality(const sweep_ctx *c, const btf_model *m, btf_sweep_point *p,
                                  btf_error *err)
{
    double sum = 0.0, sum2 = 0.0, worst = 0.0;
    int n = c->o->seeds;
    for (int i = 0; i < n; i++) {
        btf_quality_opts q = c->o->quality;
        q.seed = c->o->quality.seed + (uint64_t)i;
        q.threads = 1;
        q.progress = NULL;
        q.on_pair = NULL;
        btf_quality r;
        btf_status rc = btf__quality_measure(c->ds, m, &q, &r, err);
        if (rc == BTF_OK) {
            sum += r.mean_combined;
            sum2 += r.mean_combined * r.mean_combined;
            worst += r.worst_combined;
        }
        btf__quality_free(&r);
        if (rc)
            return rc;
    }
    p->mean_combined = sum / n;
    p->worst_combined = worst / n;
    double var = n > 1 ? (sum2 - sum * sum / n) / (n - 1) : 0.0;
    p->seed_spread = var > 0.0 ? sqrt(var) : 0.0;
    /* the mean of the worsts is at least the mean of the means, rounding aside */
    if (p->worst_combined < p->mean_combined)
        p->worst_combined = p->mean_combined;
    return BTF_OK;
}

static btf_status measure_point(sweep_ctx *c, btf_sweep_point *p, btf_error *err)
{
    btf_analyse_opts a = setting_opts(c, &p->setting);
    btf_model m;
    double t0 = btf__now();
    btf_status rc = btf_analyse(c->ds, &a, &m, err);
    if (rc)
        return rc;
    p->analyse_s = btf__now() - t0;
    p->k = m.n_subspaces;
    unsigned char *bytes = NULL;
    size_t size = 0;
    rc = btf_model_encode(&m, &bytes, &size, err);
    free(bytes);
    p->bytes = size;
    if (rc == BTF_OK)
        rc = time_synthesis(&m, c->o, &p->synth_s, err);
    if (rc == BTF_OK)
        rc = time_gpu_synthesis(&m, c->o, &c->gpu_lock, &p->gpu_synth_s, err);
    if (rc == BTF_OK)
        rc = time_render(&m, c->o, &p->render_s, err);
    if (rc == BTF_OK)
        rc = measure_quality(c, &m, p, err);
    btf_model_free(&m);
    return rc;
}

static btf_status sweep_job(void *user, int job, int worker, btf_error *err)
{
    (void)worker;
    sweep_ctx *c = user;
    btf_sweep_point *p = &c->s->points[job];
    if (p->resumed || p->missing) /* read back before the run, or another share's */
        return BTF_OK;
    btf_status rc = measure_point(c, p, err);
    if (rc == BTF_OK)
        rc = write_point(c, p, err);
    if (rc) {
        /* Name the setting, keep the cause. */
        char why[sizeof err->msg];
        snprintf(why, sizeof why, "%s", err->msg);
        btf__fail(err, rc, "sweep point K %d, levels %d, neighbours %d: %s",
                  p->setting.subspaces, p->setting.levels, p->setting.neighbours, why);
    }
    return rc;
}

/* Pareto-optimal points of (x, mean_combined), both smaller-is-better: no
 * other point is at least as good in both and better in one. */
static void mark_front(btf_sweep *s, int by_bytes)
{
    for (int i = 0; i < s->n_points; i++) {
        const btf_sweep_point *a = &s->points[i];
        double ax = by_bytes ? (double)a->bytes : a->synth_s;
        int dominated = a->missing; /* a missing point is on no front */
        for (int j = 0; j < s->n_points && !dominated; j++) {
            const btf_sweep_point *b = &s->points[j];
            if (b->missing)
                continue;
            double bx = by_bytes ? (double)b->bytes : b->synth_s;
            dominated = j != i && bx <= ax && b->mean_combined <= a->mean_combined &&
                        (bx < ax || b->mean_combined < a->mean_combined);
        }
        if (by_bytes)
            s->points[i].pareto_bytes = !dominated;
        else
            s->points[i].pareto_time = !dominated;
    }
}

static btf_status make_grid(const btf_sweep_opts *o, btf_sweep *s, btf_error *err)
{
    /* a plain model has its own 64-texel tile: one range size */
    int per_setting = 0;
    for (int d = 0; d < o->n_plain; d++)
        per_setting += o->plain[d] ? 1 : o->n_range_sizes;
    int n = o->n_subspaces * o->n_levels * o->n_neighbours * per_setting;
    if (n < 1)
        return btf__fail(err, BTF_E_ARG, "sweep: an empty grid");
    s->points = btf__calloc((size_t)n, sizeof *s->points, err);
    if (!s->points)
        return BTF_E_NOMEM;
    int def_n = o->analyse.fit.car.n_fixed;
    for (int d = 0; d < o->n_plain; d++)
        for (int r = 0; r < (o->plain[d] ? 1 : o->n_range_sizes); r++)
            for (int a = 0; a < o->n_subspaces; a++)
                for (int b = 0; b < o->n_levels; b++)
                    for (int c = 0; c < o->n_neighbours; c++) {
                        btf_sweep_point *p = &s->points[s->n_points++];
                        btf_sweep_setting *t = &p->setting;
                        t->subspaces = o->subspaces[a];
                        t->levels = o->levels[b];
                        t->neighbours = o->neighbours[c];
                        t->plain = o->plain[d];
                        t->range_size = o->plain[d] ? 0 : o->range_sizes[r];
                        p->is_default = t->subspaces == o->analyse.segment.subspaces &&
                                        t->levels == o->analyse.fit.levels &&
                                        t->neighbours == def_n && !t->plain &&
                                        t->range_size == o->analyse.range_size;
                    }
    return BTF_OK;
}

/* The merge's refusal: how many points are missing and the first few
 * settings, so that the user reruns the shares that hold them. */
static btf_status missing_error(const btf_sweep *s, const char *dir, btf_error *err)
{
    char list[256] = "";
    size_t at = 0;
    int shown = 0;
    for (int i = 0; i < s->n_points && shown < 4; i++) {
        const btf_sweep_setting *t = &s->points[i].setting;
        if (!s->points[i].missing)
            continue;
        int w = snprintf(list + at, sizeof list - at, "%s#%d (K %d, levels %d, neighbours %d%s)",
                         shown ? ", " : "", i, t->subspaces, t->levels, t->neighbours,
                         t->plain ? ", no layers" : "");
        if (w < 0 || (size_t)w >= sizeof list - at)
            break;
        at += (size_t)w;
        shown++;
    }
    return btf__fail(err, BTF_E_DATA, "%s: %d of the sweep's %d points are missing: %s%s; run "
                     "their shares (--points I/N: point i is in share i mod N)", dir,
                     s->n_missing, s->n_points, list, s->n_missing > shown ? ", ..." : "");
}

static btf_status make_state_dir(const char *dir, btf_error *err)
{
    struct stat st;
    if (stat(dir, &st) == 0)
        return S_ISDIR(st.st_mode) ? BTF_OK
                                   : btf__fail(err, BTF_E_IO, "%s: not a folder", dir);
    if (mkdir(dir, 0777) != 0)
        return btf__fail(err, BTF_E_IO, "%s: cannot create the sweep's state folder", dir);
    return BTF_OK;
}

btf_status btf__sweep_run(const btf_dataset *ds, const btf_sweep_opts *opts, btf_sweep *out,
                          btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "sweep: no output given");
    memset(out, 0, sizeof *out);
    if (!ds)
        return btf__fail(err, BTF_E_ARG, "sweep: no dataset given");
    btf_sweep_opts o;
    btf_status rc = resolve(opts, &o, err);
    if (rc || (rc = make_grid(&o, out, err)))
        return rc;
    if (o.state_dir && (rc = make_state_dir(o.state_dir, err))) {
        btf_sweep_free(out);
        return rc;
    }
    double t0 = btf__now();
    sweep_ctx c = {.ds = ds, .in = btf_dataset_get_info(ds), .o = &o, .s = out};
    pthread_mutex_init(&c.gpu_lock, NULL);
    make_fingerprint(&c);
    /* Resumed points first: when all are there, nothing shared is computed.
     * A point of another share that is not there is missing, not measured. */
    int missing = 0;
    for (int i = 0; i < out->n_points; i++) {
        btf_sweep_point *p = &out->points[i];
        if (read_point(&c, p))
            continue;
        p->missing = o.resume_only || (o.share_count > 0 && i % o.share_count != o.share_index);
        out->n_missing += p->missing;
        missing += !p->missing;
    }
    if (o.resume_only && out->n_missing) {
        rc = missing_error(out, o.state_dir, err);
        pthread_mutex_destroy(&c.gpu_lock);
        btf_sweep_free(out);
        return rc;
    }
    float *features = NULL, *means = NULL;
    btf_model range;
    memset(&range, 0, sizeof range);
    if (missing) {
        if (o.progress)
            o.progress(o.progress_user, 0.0, "sweep: features of every image");
        btf_feature_opts fo = o.analyse.segment.features;
        fo.threads = o.threads;
        fo.progress = NULL;
        const btf_dataset_info *in = btf_dataset_get_info(ds);
        means = btf__alloc((size_t)in->n_views * in->n_lights * 3, sizeof(float), err);
        fo.means = means; /* read in the same pass, shared by every setting */
        rc = means ? btf__dataset_features(ds, &fo, &features, &c.dim, err) : BTF_E_NOMEM;
        c.means = means;
        if (rc == BTF_OK && !o.analyse.no_range) {
            btf_analyse_opts a = o.analyse;
            a.photostereo.threads = o.threads;
            rc = btf__analyse_range(ds, &a, &range, err);
            c.range = &range;
        }
        c.features = features;
        out->shared_s = btf__now() - t0;
    }
    if (rc == BTF_OK) {
        btf_pool_progress pp = {o.progress, o.progress_user, "sweep: settings", 0.0, 1.0, 1};
        rc = btf__pool_run(out->n_points, o.threads, sweep_job, &c, &pp, err);
    }
    pthread_mutex_destroy(&c.gpu_lock);
    free(features);
    free(means);
    btf_model_free(&range);
    if (rc) {
        btf_sweep_free(out);
        return rc;
    }
    for (int i = 0; i < out->n_points; i++)
        out->resumed += out->points[i].resumed;
    mark_front(out, 1);
    mark_front(out, 0);
    out->seeds = o.seeds;
    out->seconds = btf__now() - t0;
    return BTF_OK;
}

void btf_sweep_free(btf_sweep *s)
{
    if (!s)
        return;
    free(s->points);
    memset(s, 0, sizeof *s);
}
