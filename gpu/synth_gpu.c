/*
 * synth_gpu.c — subspace synthesis on the GPU (Vulkan compute), the same
 * computation as the CPU reference src/synth.c, bit for bit:
 *   1. synth_field.comp: every CAR field (subspace, band, level) in one
 *      workgroup, its causal recursion as a wavefront (docs/gpu.md);
 *   2. synth_collapse.comp: the pyramid collapse, level by level from the
 *      coarsest;
 *   3. synth_unmix.comp: the inverse colour decorrelation.
 * The geometry (windows, margins, burn-in) and the float formulas are the
 * CPU's (gpu/btf_shared.h). One job (command buffer) per batch of subspace
 * images; batches are cut so that every buffer fits the device's limits.
 */
#include "internal.h"

#include "btf_shared.h"
#include "vk.h"

#include "synth_collapse_spv.h"
#include "synth_field_spv.h"
#include "synth_unmix_spv.h"

#include <stdlib.h>
#include <string.h>

/* C mirrors of gpu/synth_task.glsl (4-byte members only: std430 agrees). */
typedef struct gpu_task {
    int32_t fx0, fy0, fw, fh;
    int32_t x0, y0, w, h;
    uint32_t field_off, g_off;
    uint32_t stream;
    int32_t n, a, coarse;
    float sigma, mean;
    int32_t off_r[24];
    int32_t off_c[24];
    float gamma[24];
} gpu_task;

typedef struct gpu_unmix {
    float mean[3];
    float basis[9];
    uint32_t g_off[3];
    uint32_t out_off;
    int32_t w, h;
} gpu_unmix;

_Static_assert(sizeof(gpu_task) == 352, "gpu_task must match synth_task.glsl");
_Static_assert(sizeof(gpu_unmix) == 72, "gpu_unmix must match synth_task.glsl");
_Static_assert(BTF_CAR_MAX_NEIGHBOURS == 24, "synth_task.glsl holds 24 offsets");

struct btf_gpu {
    btf_vk *vk;
    btf_vk_pipeline *field, *collapse, *unmix;
};

int btf_gpu_open(const btf_gpu_opts *opts, btf_gpu **out, btf_error *err)
{
    *out = NULL;
    btf_gpu_opts o = {0};
    if (opts)
        o = *opts;
    btf_gpu *g = btf_calloc(1, sizeof *g, err);
    if (!g)
        return BTF_E_NOMEM;
    btf_vk_opts vo = {.use_device = o.use_device, .device = o.device, .allow_cpu = o.allow_cpu,
                      .validation = o.validation};
    int rc = btf_vk_create(&vo, &g->vk, err);
    if (rc == 0)
        rc = btf_vk_pipeline_create(g->vk, synth_field_spv, sizeof synth_field_spv, 2, 12, NULL, 0,
                                    &g->field, err);
    if (rc == 0)
        rc = btf_vk_pipeline_create(g->vk, synth_collapse_spv, sizeof synth_collapse_spv, 3, 4,
                                    NULL, 0, &g->collapse, err);
    if (rc == 0)
        rc = btf_vk_pipeline_create(g->vk, synth_unmix_spv, sizeof synth_unmix_spv, 3, 4, NULL, 0,
                                    &g->unmix, err);
    if (rc) {
        btf_gpu_close(g);
        return rc;
    }
    *out = g;
    return BTF_OK;
}

void btf_gpu_close(btf_gpu *g)
{
    if (!g)
        return;
    btf_vk_pipeline_destroy(g->field);
    btf_vk_pipeline_destroy(g->collapse);
    btf_vk_pipeline_destroy(g->unmix);
    btf_vk_destroy(g->vk);
    free(g);
}

const char *btf_gpu_device_name(const btf_gpu *g)
{
    return btf_vk_info(g->vk)->name;
}

int btf_gpu_is_cpu(const btf_gpu *g)
{
    return btf_vk_info(g->vk)->is_cpu;
}

unsigned btf_gpu_validation_errors(const btf_gpu *g)
{
    return btf_vk_validation_errors(g->vk);
}

const char *btf_gpu_first_validation_message(const btf_gpu *g)
{
    return btf_vk_first_validation_message(g->vk);
}

static int floordiv2(int a)
{
    return a >= 0 ? a / 2 : -((-a + 1) / 2);
}

/* The wavefront slope: pixel (r, c) must come after (r + dr, c + dc) for
 * every offset, i.e. a |dr| > dc for offsets of earlier rows. */
static int wavefront_slope(const btf_car_band *b)
{
    int a = 1;
    for (int s = 0; s < b->n; s++) {
        int dr = -b->offsets[s].row, dc = b->offsets[s].col;
        if (dr > 0) {
            int need = (dc >= 0 ? dc / dr : -((-dc) / dr)) + 1;
            if (need > a)
                a = need;
        }
    }
    return a;
}

/* A task record for one field; offsets ordered as btf_shared.h sums them:
 * earlier rows first, then the same row, each in stored order. */
static void fill_task(gpu_task *t, const btf_car_band *b, uint32_t stream, int x0, int x1, int y0,
                      int y1)
{
    memset(t, 0, sizeof *t);
    t->x0 = x0, t->y0 = y0, t->w = x1 - x0, t->h = y1 - y0;
    t->fx0 = x0 - BTF_SYNTH_MARGIN, t->fw = t->w + 2 * BTF_SYNTH_MARGIN;
    t->fy0 = y0 - BTF_SYNTH_BURNIN, t->fh = t->h + BTF_SYNTH_BURNIN;
    t->stream = stream;
    t->sigma = b->sigma, t->mean = b->mean;
    t->a = wavefront_slope(b);
    t->coarse = -1;
    int k = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int s = 0; s < b->n; s++)
            if ((b->offsets[s].row != 0) == (pass == 0)) {
                t->off_r[k] = b->offsets[s].row;
                t->off_c[k] = b->offsets[s].col;
                t->gamma[k] = b->gamma[s];
                k++;
            }
    t->n = k;
}

/* One batch of subspace images: tasks grouped by level (coarsest first is
 * not needed: collapse dispatches name their level's range). */
typedef struct batch {
    gpu_task *tasks;
    int ntasks;
    int level_start[BTF_MAX_LEVELS + 1]; /* tasks of level l: [start[l], start[l+1]) */
    gpu_unmix *unmix;
    int n;
    uint64_t field_floats, gauss_floats, out_floats;
} batch;

/* Task index of (image j, band b, level l) inside a level group. */
static int build_batch(const btf_model *m, const int *subs, int n, int w, int h, batch *bt,
                       btf_error *err)
{
    memset(bt, 0, sizeof *bt);
    int max_levels = 0;
    for (int j = 0; j < n; j++)
        if (m->subspaces[subs[j]].levels > max_levels)
            max_levels = m->subspaces[subs[j]].levels;
    bt->tasks = btf_calloc((size_t)n * 3 * max_levels, sizeof(gpu_task), err);
    bt->unmix = btf_calloc((size_t)n, sizeof(gpu_unmix), err);
    if (!bt->tasks || !bt->unmix)
        return BTF_E_NOMEM;
    bt->n = n;
    /* Count tasks per level to lay the groups out. */
    int count[BTF_MAX_LEVELS] = {0};
    for (int j = 0; j < n; j++)
        for (int l = 0; l < m->subspaces[subs[j]].levels; l++)
            count[l] += 3;
    for (int l = 0; l < max_levels; l++)
        bt->level_start[l + 1] = bt->level_start[l] + count[l];
    bt->ntasks = bt->level_start[max_levels];
    int fill[BTF_MAX_LEVELS];
    memcpy(fill, bt->level_start, sizeof fill);
    for (int j = 0; j < n; j++) {
        const btf_subspace_model *sm = &m->subspaces[subs[j]];
        for (int b = 0; b < 3; b++) {
            int x0 = 0, x1 = w, y0 = 0, y1 = h, prev = -1;
            for (int l = 0; l < sm->levels; l++) {
                int ti = fill[l]++;
                gpu_task *t = &bt->tasks[ti];
                fill_task(t, &sm->bands[b][l],
                          btf_noise_stream((uint32_t)subs[j], (uint32_t)b, (uint32_t)l), x0, x1,
                          y0, y1);
                t->field_off = (uint32_t)bt->field_floats;
                t->g_off = (uint32_t)bt->gauss_floats;
                bt->field_floats += (uint64_t)t->fw * t->fh;
                bt->gauss_floats += (uint64_t)t->w * t->h;
                if (prev >= 0)
                    bt->tasks[prev].coarse = ti;
                else
                    bt->unmix[j].g_off[b] = t->g_off;
                prev = ti;
                int nx0 = floordiv2(x0) - 1, nx1 = floordiv2(x1 - 1) + 2;
                int ny0 = floordiv2(y0) - 1, ny1 = floordiv2(y1 - 1) + 2;
                x0 = nx0, x1 = nx1, y0 = ny0, y1 = ny1;
            }
        }
        gpu_unmix *u = &bt->unmix[j];
        memcpy(u->mean, sm->mean, sizeof u->mean);
        memcpy(u->basis, sm->basis, sizeof u->basis);
        u->out_off = (uint32_t)bt->out_floats;
        u->w = w, u->h = h;
        bt->out_floats += (uint64_t)w * h * 3;
    }
    return BTF_OK;
}

static void batch_free(batch *bt)
{
    free(bt->tasks);
    free(bt->unmix);
    memset(bt, 0, sizeof *bt);
}

/* The largest buffer a batch needs, in bytes (fields, G windows, output). */
static uint64_t batch_need(const batch *bt)
{
    uint64_t need = bt->field_floats;
    if (bt->gauss_floats > need)
        need = bt->gauss_floats;
    if (bt->out_floats > need)
        need = bt->out_floats;
    return 4 * need;
}

/* Dispatches `count` workgroups from `base`, split at the device's limit. */
static int dispatch_range(btf_gpu *g, btf_vk_job *job, const btf_vk_pipeline *pipe,
                          btf_vk_buffer *const *bufs, int nbufs, uint32_t *push, int push_words,
                          uint32_t base, uint32_t count, btf_error *err)
{
    uint32_t limit = btf_vk_info(g->vk)->max_workgroup_count[0];
    while (count > 0) {
        uint32_t k = count < limit ? count : limit;
        push[push_words - 1] = base; /* the base is the last push word */
        int rc = btf_vk_job_dispatch(job, pipe, bufs, nbufs, push, 4u * push_words, k, 1, 1, err);
        if (rc)
            return rc;
        base += k;
        count -= k;
    }
    return BTF_OK;
}

static int run_batch(btf_gpu *g, const batch *bt, uint64_t seed, btf_image *outs, btf_error *err)
{
    btf_vk_buffer *tasks = NULL, *unmix = NULL, *fields = NULL, *gauss = NULL, *out = NULL;
    btf_vk_job *job = NULL;
    int rc = btf_vk_buffer_create(g->vk, sizeof(gpu_task) * (uint64_t)bt->ntasks, &tasks, err);
    if (rc == 0)
        rc = btf_vk_buffer_create(g->vk, sizeof(gpu_unmix) * (uint64_t)bt->n, &unmix, err);
    if (rc == 0)
        rc = btf_vk_buffer_create(g->vk, 4 * bt->field_floats, &fields, err);
    if (rc == 0)
        rc = btf_vk_buffer_create(g->vk, 4 * bt->gauss_floats, &gauss, err);
    if (rc == 0)
        rc = btf_vk_buffer_create(g->vk, 4 * bt->out_floats, &out, err);
    if (rc == 0)
        rc = btf_vk_buffer_upload(g->vk, tasks, 0, bt->tasks, sizeof(gpu_task) * (uint64_t)bt->ntasks,
                                  err);
    if (rc == 0)
        rc = btf_vk_buffer_upload(g->vk, unmix, 0, bt->unmix, sizeof(gpu_unmix) * (uint64_t)bt->n,
                                  err);
    if (rc == 0)
        rc = btf_vk_job_begin(g->vk, &job, err);
    uint32_t fpush[3] = {(uint32_t)seed, (uint32_t)(seed >> 32), 0};
    btf_vk_buffer *fb[2] = {tasks, fields};
    if (rc == 0)
        rc = dispatch_range(g, job, g->field, fb, 2, fpush, 3, 0, (uint32_t)bt->ntasks, err);
    btf_vk_buffer *cb[3] = {tasks, fields, gauss};
    int levels = 0;
    while (levels < BTF_MAX_LEVELS && bt->level_start[levels + 1] > bt->level_start[levels])
        levels++;
    for (int l = levels - 1; rc == 0 && l >= 0; l--) {
        uint32_t cpush[1];
        rc = dispatch_range(g, job, g->collapse, cb, 3, cpush, 1, (uint32_t)bt->level_start[l],
                            (uint32_t)(bt->level_start[l + 1] - bt->level_start[l]), err);
    }
    btf_vk_buffer *ub[3] = {unmix, gauss, out};
    uint32_t upush[1];
    if (rc == 0)
        rc = dispatch_range(g, job, g->unmix, ub, 3, upush, 1, 0, (uint32_t)bt->n, err);
    if (rc == 0) {
        rc = btf_vk_job_submit_wait(job, err);
        job = NULL;
    }
    for (int j = 0; rc == 0 && j < bt->n; j++)
        rc = btf_vk_buffer_download(g->vk, out, 4ull * bt->unmix[j].out_off, outs[j].data,
                                    (uint64_t)outs[j].width * outs[j].height * 12, err);
    btf_vk_job_abort(job);
    btf_vk_buffer_destroy(tasks);
    btf_vk_buffer_destroy(unmix);
    btf_vk_buffer_destroy(fields);
    btf_vk_buffer_destroy(gauss);
    btf_vk_buffer_destroy(out);
    return rc;
}

static int check_request(const btf_model *m, const int *subs, int n, int w, int h, btf_error *err)
{
    if (w < 1 || h < 1 || w > BTF_SYNTH_MAX_SIDE || h > BTF_SYNTH_MAX_SIDE)
        return btf_fail(err, BTF_E_ARG, "synthesis size %dx%d: expected 1..%d on each side", w, h,
                        BTF_SYNTH_MAX_SIDE);
    for (int j = 0; j < n; j++) {
        if (subs[j] < 0 || subs[j] >= m->n_subspaces)
            return btf_fail(err, BTF_E_ARG, "subspace %d: the model has %d", subs[j],
                            m->n_subspaces);
        const btf_subspace_model *sm = &m->subspaces[subs[j]];
        if (sm->levels < 1 || sm->levels > BTF_MAX_LEVELS)
            return btf_fail(err, BTF_E_ARG, "subspace %d: %d pyramid levels", subs[j], sm->levels);
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < sm->levels; l++) {
                const btf_car_band *cb = &sm->bands[b][l];
                if (cb->n < 0 || cb->n > BTF_CAR_MAX_NEIGHBOURS)
                    return btf_fail(err, BTF_E_ARG, "CAR model with %d neighbours", cb->n);
                for (int s = 0; s < cb->n; s++) {
                    btf_offset o = cb->offsets[s];
                    if (!(o.row < 0 || (o.row == 0 && o.col < 0)))
                        return btf_fail(err, BTF_E_ARG, "CAR offset %d:%d is not causal", o.row,
                                        o.col);
                }
            }
    }
    return BTF_OK;
}

int btf_gpu_synthesise(btf_gpu *g, const btf_model *m, const int *subspaces, int n, int width,
                       int height, uint64_t seed, btf_image *outs, btf_error *err)
{
    for (int j = 0; j < n; j++)
        memset(&outs[j], 0, sizeof outs[j]);
    int rc = check_request(m, subspaces, n, width, height, err);
    if (rc)
        return rc;
    for (int j = 0; rc == 0 && j < n; j++)
        rc = btf_image_alloc(&outs[j], width, height, 3, err);
    uint64_t limit = btf_vk_info(g->vk)->max_storage_buffer_range;
    /* Grow each batch while its buffers fit; one image that does not fit
     * alone is refused (strip tiling of one field is not implemented). */
    int start = 0;
    while (rc == 0 && start < n) {
        int k = 1;
        batch bt;
        rc = build_batch(m, subspaces + start, 1, width, height, &bt, err);
        if (rc == 0 && (batch_need(&bt) > limit || bt.field_floats > 0x7FFFFFFFull)) {
            rc = btf_fail(err, BTF_E_UNSUPPORTED,
                          "synthesis of %dx%d needs a %.0f MiB GPU buffer, more than the "
                          "device's limit of %.0f MiB; use the CPU backend", width, height,
                          batch_need(&bt) / 1048576.0, limit / 1048576.0);
        }
        while (rc == 0 && start + k < n) {
            batch bigger;
            rc = build_batch(m, subspaces + start, k + 1, width, height, &bigger, err);
            if (rc)
                break;
            if (batch_need(&bigger) > limit || bigger.field_floats > 0x7FFFFFFFull) {
                batch_free(&bigger);
                break;
            }
            batch_free(&bt);
            bt = bigger;
            k++;
        }
        if (rc == 0)
            rc = run_batch(g, &bt, seed, outs + start, err);
        batch_free(&bt);
        start += k;
    }
    if (rc)
        for (int j = 0; j < n; j++)
            btf_image_free(&outs[j]);
    return rc;
}
