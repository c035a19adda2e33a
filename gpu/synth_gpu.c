/*
 * synth_gpu.c — subspace synthesis on the GPU (Haindl & Filip 2007, section
 * II.C: CAR fields by their causal recursion, the pyramid collapse, the
 * inverse decorrelation; section III does it in fragment programs, here it
 * is Vulkan compute), the same computation as the CPU reference in
 * src/synth/, bit for bit:
 *   1. synth_field.comp: every CAR field (subspace, band, level) in one
 *      workgroup, its causal recursion as a wavefront (docs/gpu.md);
 *   2. synth_collapse.comp: the pyramid collapse, level by level from the
 *      coarsest;
 *   3. synth_unmix.comp: the inverse colour decorrelation.
 * The geometry (src/synth/geometry.h: windows; src/car/margin.c: margins,
 * kept per model by src/model/model_margins.c) and the float formulas
 * (src/synth/btf_shared.h) are the CPU's. One job (command buffer) per
 * strip of rows of a batch of subspace images; batches and strips are cut
 * so that every buffer fits the device's limits. Tileable synthesis is the
 * same computation with periodic noise (gpu_task.period_w, period_h;
 * docs/synthesis.md, "Tileable synthesis"). The images go to host memory
 * (btf_gpu_synthesise) or stay in one device buffer
 * (btf__gpu_synthesise_device, gpu/synth_gpu.h).
 * The btf_gpu handle that holds the pipelines, its limits and memory budget
 * are gpu/gpu_handle.c's, the image arrays on the device gpu/gpu_images.c's
 * (docs/gpu.md, "Images left on the device"); both are called from here,
 * never the other way.
 */
#include "synth/synth.h"
#include "core/core.h"
#include "model/model.h"

#include "btf_shared.h"
#include "geometry.h"
#include "synth_gpu.h"
#include "vk.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* C mirrors of gpu/synth_task.glsl (4-byte members only: std430 agrees). */
typedef struct gpu_task {
    int32_t fx0, fy0, fw, fh;
    int32_t rows_given;
    int32_t x0, y0, window_w, window_h;
    uint32_t field_off, gauss_off;
    uint32_t stream;
    int32_t n_offsets, n_earlier, slope, coarse;
    int32_t period_w, period_h;
    float sigma, mean;
    int32_t off_r[24];
    int32_t off_c[24];
    float gamma[24];
} gpu_task;

typedef struct gpu_unmix {
    float mean[3];
    float basis[9];
    uint32_t gauss_off[3];
    uint32_t out_off;
    int32_t width, height;
    int32_t transfer;           /* the marginal transfer (src/synth/marginal.c) is on */
    float origin[3], inv_h[3], tlo[3], thi[3], qmin[3], qmax[3];
    float q[3][BTF_MARGIN_TABLE], dq[3][BTF_MARGIN_TABLE];
    float lo[3], hi[3], nlo[3], nhi[3];
} gpu_unmix;

_Static_assert(sizeof(gpu_task) == 368, "gpu_task must match synth_task.glsl");
_Static_assert(sizeof(gpu_unmix) == 76 + 72 + 6 * 4 * BTF_MARGIN_TABLE + 48, "gpu_unmix must match synth_task.glsl");
_Static_assert(BTF_CAR_MAX_NEIGHBOURS == 24, "synth_task.glsl holds 24 offsets");
_Static_assert(BTF_MARGIN_TABLE == 16, "synth_task.glsl holds 16 entries per band");

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
 * earlier rows first in stored order, then the same row from the farthest
 * column to the nearest. The rows (fy0, rows_given, fh, y0, window_h) are set per
 * strip. */
static void fill_task(gpu_task *t, const btf_car_band *b, int margin, uint32_t stream, int x0,
                      int x1, int period_w, int period_h)
{
    memset(t, 0, sizeof *t);
    t->x0 = x0, t->window_w = x1 - x0;
    t->fx0 = x0 - margin, t->fw = t->window_w + 2 * margin;
    t->stream = stream;
    t->sigma = b->sigma, t->mean = b->mean;
    t->slope = wavefront_slope(b);
    t->coarse = -1;
    t->period_w = period_w, t->period_h = period_h;
    int k = 0, same[BTF_CAR_MAX_NEIGHBOURS];
    for (int s = 0; s < b->n; s++)
        if (b->offsets[s].row != 0) {
            t->off_r[k] = b->offsets[s].row;
            t->off_c[k] = b->offsets[s].col;
            t->gamma[k] = b->gamma[s];
            k++;
        }
    t->n_earlier = k;
    int nsame = btf__car_same_row_order(b, same);
    for (int i = 0; i < nsame; i++, k++) {
        t->off_r[k] = 0;
        t->off_c[k] = b->offsets[same[i]].col;
        t->gamma[k] = b->gamma[same[i]];
    }
    t->n_offsets = k;
}

/* Where one field stands while the strips go down the image. */
typedef struct field_state {
    int level;            /* pyramid level */
    int reach_up;         /* rows of history the recursion reads */
    int next;             /* next absolute field row to compute */
    int base;             /* absolute row held in buffer row 0 */
    int rows;             /* field buffer rows reserved */
    int gauss_rows;       /* G window rows reserved */
    int carry;            /* rows reserved in the carry buffer */
} field_state;

/* A batch: n_images subspace images of one size synthesised together,
 * strip by strip (tileable: periodic noise). Tasks are grouped by level (the collapse dispatches one
 * level at a time). */
typedef struct batch {
    int n_images, width, height, strip, tileable;
    gpu_task *tasks;
    field_state *fs;
    int ntasks;
    int level_start[BTF_MAX_LEVELS + 1]; /* tasks of level l: [start[l], start[l+1]) */
    gpu_unmix *unmix;
    uint64_t field_floats, gauss_floats, out_floats, carry_floats;
} batch;

static void batch_free(batch *bt)
{
    BTF_FREE_ALL(bt->tasks, bt->fs, bt->unmix);
    memset(bt, 0, sizeof *bt);
}

static int field_reach_up(const gpu_task *t)
{
    int up = 0;
    for (int k = 0; k < t->n_offsets; k++)
        if (-t->off_r[k] > up)
            up = -t->off_r[k];
    return up;
}

/* The rows of each field for the strip [y0, y1), advancing its state and
 * writing them into its task record, and the most rows each buffer needs so
 * far (field_state.rows, gauss_rows, carry). build_batch walks every strip
 * through it once to size the buffers; run_strip calls it again before each
 * job, from the first strip on, so the records match the strip it runs.
 * Returns through keep[] the rows carried from the previous strip (0 on
 * the first). */
static void strip_rows(batch *bt, int y0, int y1, int first, int *keep, int *keep_from)
{
    for (int i = 0; i < bt->ntasks; i++) {
        gpu_task *t = &bt->tasks[i];
        field_state *f = &bt->fs[i];
        btf_span rows = btf_level_span((btf_span){y0, y1}, f->level);
        int ga = rows.lo, gb = rows.hi;
        if (first) {
            /* The field starts its margin (x0 - fx0, set by fill_task) rows
             * above its window; the `reach_up` rows above that are zero (the
             * buffer is cleared). */
            f->next = ga - (t->x0 - t->fx0);
            f->base = f->next - f->reach_up;
            keep[i] = 0;
            keep_from[i] = 0;
        } else {
            int base = ga < f->next - f->reach_up ? ga : f->next - f->reach_up;
            keep[i] = f->next - base;
            keep_from[i] = base - f->base;
            f->base = base;
        }
        t->fy0 = f->base;
        t->rows_given = f->next - f->base;
        t->fh = (gb > f->next ? gb : f->next) - f->base;
        t->y0 = ga;
        t->window_h = gb - ga;
        if (gb > f->next)
            f->next = gb;
        if (t->fh > f->rows)
            f->rows = t->fh;
        if (t->window_h > f->gauss_rows)
            f->gauss_rows = t->window_h;
        if (keep[i] > f->carry)
            f->carry = keep[i];
    }
}

/* The members of the marginal table (src/synth/marginal.c) that an unmix
 * record mirrors, by name: the same in both structs. */
#define UNMIX_TABLE_MEMBERS(X)                                                                 \
    X(origin) X(inv_h) X(tlo) X(thi) X(qmin) X(qmax) X(q) X(dq) X(lo) X(hi) X(nlo) X(nhi)

/* An image's marginal transfer into its unmix record: the CPU's very table,
 * member by member (each the same size on both sides). */
static void unmix_take_table(gpu_unmix *u, const btf_marginal_table *mt)
{
    u->transfer = mt->on;
#define TAKE(f)                                                                                \
    _Static_assert(sizeof u->f == sizeof mt->f, "gpu_unmix." #f " mirrors the table's");      \
    memcpy(u->f, mt->f, sizeof mt->f);
    UNMIX_TABLE_MEMBERS(TAKE)
#undef TAKE
}

/* Builds the batch and sizes its buffers for strips of `strip` rows;
 * margins[j][b][l] of image j. */
static int build_batch(const btf_model *m, const int *subs, const int (*margins)[3][BTF_MAX_LEVELS],
                       int n, int w, int h, int strip, int tileable, batch *bt, btf_error *err)
{
    memset(bt, 0, sizeof *bt);
    bt->n_images = n, bt->width = w, bt->height = h, bt->strip = strip;
    bt->tileable = tileable;
    int max_levels = 0, count[BTF_MAX_LEVELS] = {0};
    for (int j = 0; j < n; j++) {
        const btf_subspace_model *sm = &m->subspaces[subs[j]];
        if (sm->levels > max_levels)
            max_levels = sm->levels;
        for (int l = 0; l < sm->levels; l++)
            count[l] += 3;
    }
    for (int l = 0; l < max_levels; l++)
        bt->level_start[l + 1] = bt->level_start[l] + count[l];
    bt->ntasks = bt->level_start[max_levels];
    bt->tasks = btf__calloc((size_t)bt->ntasks, sizeof(gpu_task), err);
    bt->fs = btf__calloc((size_t)bt->ntasks, sizeof(field_state), err);
    bt->unmix = btf__calloc((size_t)n, sizeof(gpu_unmix), err);
    int *keep = btf__calloc((size_t)bt->ntasks * 2, sizeof(int), err);
    if (!bt->tasks || !bt->fs || !bt->unmix || !keep) {
        free(keep);
        return BTF_E_NOMEM;
    }
    int fill[BTF_MAX_LEVELS];
    memcpy(fill, bt->level_start, sizeof fill);
    for (int j = 0; j < n; j++) {
        const btf_subspace_model *sm = &m->subspaces[subs[j]];
        for (int b = 0; b < 3; b++) {
            btf_span xs = {0, w};
            int prev = -1;
            for (int l = 0; l < sm->levels; l++) {
                int ti = fill[l]++;
                /* tileable: level l's period, (w >> l) x (h >> l), as on the CPU
                 * (src/synth/collapse.c) */
                fill_task(&bt->tasks[ti], &sm->bands[b][l], margins[j][b][l],
                          btf_noise_stream((uint32_t)subs[j], (uint32_t)b, (uint32_t)l), xs.lo,
                          xs.hi, tileable ? w >> l : 0, tileable ? h >> l : 0);
                bt->fs[ti].level = l;
                bt->fs[ti].reach_up = field_reach_up(&bt->tasks[ti]);
                if (prev >= 0)
                    bt->tasks[prev].coarse = ti;
                prev = ti;
                xs = btf_coarser_span(xs);
            }
        }
        memcpy(bt->unmix[j].mean, sm->mean, sizeof bt->unmix[j].mean);
        memcpy(bt->unmix[j].basis, sm->basis, sizeof bt->unmix[j].basis);
        bt->unmix[j].width = w;
        btf_marginal_table mt; /* the CPU's very table (src/synth/marginal.c) */
        btf__marginal_table_make(sm, &mt);
        unmix_take_table(&bt->unmix[j], &mt);
    }
    /* Walk the strips once to size every field's buffer rows. */
    for (int y = 0; y < h; y += strip)
        strip_rows(bt, y, y + strip < h ? y + strip : h, y == 0, keep, keep + bt->ntasks);
    free(keep);
    for (int i = 0; i < bt->ntasks; i++) {
        gpu_task *t = &bt->tasks[i];
        t->field_off = (uint32_t)bt->field_floats;
        t->gauss_off = (uint32_t)bt->gauss_floats;
        bt->field_floats += (uint64_t)t->fw * bt->fs[i].rows;
        bt->gauss_floats += (uint64_t)t->window_w * bt->fs[i].gauss_rows;
        bt->carry_floats += (uint64_t)t->fw * bt->fs[i].carry;
    }
    for (int j = 0; j < n; j++)
        bt->out_floats += (uint64_t)w * strip * 3;
    return BTF_OK;
}

/* The largest buffer a batch needs, in bytes. */
static uint64_t batch_need(const batch *bt)
{
    uint64_t need = bt->field_floats;
    if (bt->gauss_floats > need)
        need = bt->gauss_floats;
    if (bt->out_floats > need)
        need = bt->out_floats;
    if (bt->carry_floats > need)
        need = bt->carry_floats;
    return 4 * need;
}

/* Dispatches `count` x gy workgroups from `base`, split at the device's
 * limit along x. */
static int dispatch_range(btf_gpu *g, btf_vk_job *job, const btf_vk_pipeline *pipe,
                          btf_vk_buffer *const *bufs, int nbufs, uint32_t *push, int push_words,
                          uint32_t base, uint32_t count, uint32_t gy, btf_error *err)
{
    const btf_vk_device_info *in = btf__vk_info(g->vk);
    uint32_t limit = in->max_workgroup_count[0];
    if (gy > in->max_workgroup_count[1])
        return btf__fail(err, BTF_E_UNSUPPORTED, "GPU synthesis needs %u workgroups along y, more "
                         "than the device's %u; use the CPU backend", gy,
                         in->max_workgroup_count[1]);
    while (count > 0) {
        uint32_t k = count < limit ? count : limit;
        push[push_words - 1] = base; /* the base is the last push word */
        int rc = btf__vk_job_dispatch(job, pipe, bufs, nbufs, push, 4u * push_words, k, gy, 1, err);
        if (rc)
            return rc;
        base += k;
        count -= k;
    }
    return BTF_OK;
}

/* Workgroups along y that cover `pixels` in chunks of BTF_GPU_CHUNK. */
static uint32_t chunks(uint64_t pixels)
{
    uint64_t c = (pixels + BTF_GPU_CHUNK - 1) / BTF_GPU_CHUNK;
    return c ? (uint32_t)(c > 0xFFFFFFFFu ? 0xFFFFFFFFu : c) : 1;
}

/* The wavefront of a strip in dispatches of a bounded number of steps:
 * lavapipe ends a shader invocation after 65,535 loop iterations in all (its
 * loop limiter is shared by every loop), silently. A step costs an
 * invocation 1 + q (2 + n) iterations, q = ceil(active pixels / 64), n the
 * neighbours; each dispatch stays within half the limit. */
static int dispatch_wavefront(btf_gpu *g, btf_vk_job *job, const batch *bt, uint64_t seed,
                              btf_vk_buffer *const *bufs, btf_error *err)
{
    int64_t steps = 0, per_step = 1;
    for (int i = 0; i < bt->ntasks; i++) {
        const gpu_task *t = &bt->tasks[i];
        int rows = t->fh - t->rows_given;
        if (rows <= 0)
            continue;
        int64_t st = (int64_t)t->slope * (rows - 1) + t->fw;
        int64_t active = (t->fw + t->slope - 1) / t->slope;
        if (active > rows)
            active = rows;
        int64_t cost = 1 + ((active + 63) / 64) * (2 + t->n_offsets);
        if (st > steps)
            steps = st;
        if (cost > per_step)
            per_step = cost;
    }
    int64_t chunk = BTF_GPU_LOOP_BUDGET * 8 / per_step;
    if (chunk < 1)
        chunk = 1;
    int rc = BTF_OK;
    for (int64_t s0 = 0; rc == 0 && s0 < steps; s0 += chunk) {
        int64_t s1 = s0 + chunk < steps ? s0 + chunk : steps;
        uint32_t push[5] = {(uint32_t)seed, (uint32_t)(seed >> 32), (uint32_t)s0, (uint32_t)s1, 0};
        rc = dispatch_range(g, job, g->field, bufs, 2, push, 5, 0, (uint32_t)bt->ntasks, 1, err);
    }
    return rc;
}

typedef struct batch_buffers {
    btf_vk_buffer *tasks, *unmix, *fields, *gauss, *out, *carry;
} batch_buffers;

static void buffers_free(batch_buffers *b)
{
    btf__vk_buffer_destroy(b->tasks);
    btf__vk_buffer_destroy(b->unmix);
    btf__vk_buffer_destroy(b->fields);
    btf__vk_buffer_destroy(b->gauss);
    btf__vk_buffer_destroy(b->out);
    btf__vk_buffer_destroy(b->carry);
}

static int buffers_make(btf_gpu *g, const batch *bt, batch_buffers *b, btf_error *err)
{
    memset(b, 0, sizeof *b);
    int rc = btf__vk_buffer_create(g->vk, sizeof(gpu_task) * (uint64_t)bt->ntasks, &b->tasks, err);
    if (rc == 0)
        rc = btf__vk_buffer_create(g->vk, sizeof(gpu_unmix) * (uint64_t)bt->n_images, &b->unmix,
                                   err);
    if (rc == 0)
        rc = btf__vk_buffer_create(g->vk, 4 * bt->field_floats, &b->fields, err);
    if (rc == 0)
        rc = btf__vk_buffer_create(g->vk, 4 * bt->gauss_floats, &b->gauss, err);
    if (rc == 0)
        rc = btf__vk_buffer_create(g->vk, 4 * bt->out_floats, &b->out, err);
    if (rc == 0)
        rc = btf__vk_buffer_create(g->vk, 4 * (bt->carry_floats ? bt->carry_floats : 1), &b->carry,
                                   err);
    return rc;
}

/* Carries each field's last rows to the top of its buffer (through the
 * carry buffer: source and destination may overlap). */
static int record_carry(btf_vk_job *job, const batch *bt, const batch_buffers *b, const int *keep,
                        const int *keep_from, btf_error *err)
{
    uint64_t toff = 0;
    int rc = BTF_OK;
    for (int i = 0; rc == 0 && i < bt->ntasks; i++) {
        const gpu_task *t = &bt->tasks[i];
        uint64_t bytes = 4ull * t->fw * keep[i], from = 4ull * t->field_off;
        if (bytes == 0 || keep_from[i] == 0)
            continue; /* nothing to keep, or already in place */
        rc = btf__vk_job_copy(job, b->fields, from + 4ull * t->fw * keep_from[i], b->carry, toff,
                              bytes, err);
        if (rc == 0)
            rc = btf__vk_job_copy(job, b->carry, toff, b->fields, from, bytes, err);
        toff += bytes;
    }
    return rc;
}

/* Where a batch's images go: host images, or the device array dev at
 * float offsets dev_off[j] (btf__gpu_synthesise_device). */
typedef struct batch_dest {
    btf_image *images;
    const btf_gpu_images *dev;
    const uint64_t *dev_off;
} batch_dest;

/* One strip of every image of the batch: one job. */
static int run_strip(btf_gpu *g, batch *bt, batch_buffers *b, int y0, int y1, uint64_t seed,
                     const batch_dest *dst, int *keep, btf_error *err)
{
    int first = y0 == 0;
    strip_rows(bt, y0, y1, first, keep, keep + bt->ntasks);
    uint64_t out_off = 0;
    for (int j = 0; j < bt->n_images; j++) {
        bt->unmix[j].out_off = (uint32_t)out_off;
        bt->unmix[j].height = y1 - y0;
        out_off += (uint64_t)bt->width * (y1 - y0) * 3;
    }
    for (int j = 0; j < bt->n_images; j++) /* level-0 tasks of image j, bands 0..2 */
        for (int band = 0; band < 3; band++)
            bt->unmix[j].gauss_off[band] = bt->tasks[3 * j + band].gauss_off;
    btf_vk_job *job = NULL;
    int rc = btf__vk_buffer_upload(g->vk, b->tasks, 0, bt->tasks,
                                   sizeof(gpu_task) * (uint64_t)bt->ntasks, err);
    if (rc == 0)
        rc = btf__vk_buffer_upload(g->vk, b->unmix, 0, bt->unmix,
                                   sizeof(gpu_unmix) * (uint64_t)bt->n_images, err);
    if (rc == 0)
        rc = btf__vk_job_begin(g->vk, &job, err);
    if (rc == 0 && first)
        rc = btf__vk_job_fill(job, b->fields, 0, 4 * bt->field_floats, 0, err);
    if (rc == 0 && !first)
        rc = record_carry(job, bt, b, keep, keep + bt->ntasks, err);
    btf_vk_buffer *fb[2] = {b->tasks, b->fields};
    if (rc == 0)
        rc = dispatch_wavefront(g, job, bt, seed, fb, err);
    btf_vk_buffer *cb[3] = {b->tasks, b->fields, b->gauss};
    int levels = 0;
    while (levels < BTF_MAX_LEVELS && bt->level_start[levels + 1] > bt->level_start[levels])
        levels++;
    for (int l = levels - 1; rc == 0 && l >= 0; l--) {
        uint32_t cpush[1];
        uint64_t most = 0;
        for (int i = bt->level_start[l]; i < bt->level_start[l + 1]; i++)
            if ((uint64_t)bt->tasks[i].window_w * bt->tasks[i].window_h > most)
                most = (uint64_t)bt->tasks[i].window_w * bt->tasks[i].window_h;
        rc = dispatch_range(g, job, g->collapse, cb, 3, cpush, 1, (uint32_t)bt->level_start[l],
                            (uint32_t)(bt->level_start[l + 1] - bt->level_start[l]), chunks(most),
                            err);
    }
    btf_vk_buffer *ub[3] = {b->unmix, b->gauss, b->out};
    uint32_t upush[1];
    if (rc == 0)
        rc = dispatch_range(g, job, g->unmix, ub, 3, upush, 1, 0, (uint32_t)bt->n_images,
                            chunks((uint64_t)bt->width * (y1 - y0)), err);
    uint64_t strip_bytes = 4ull * bt->width * (y1 - y0) * 3;
    for (int j = 0; rc == 0 && dst->dev && j < bt->n_images; j++) /* on the device */
        rc = btf__gpu_images_copy_in(job, b->out, 4ull * bt->unmix[j].out_off, dst->dev,
                                     dst->dev_off[j] + (uint64_t)y0 * bt->width * 3,
                                     strip_bytes / 4, err);
    if (rc == 0) {
        rc = btf__vk_job_submit_wait(job, err);
        job = NULL;
    }
    for (int j = 0; rc == 0 && !dst->dev && j < bt->n_images; j++)
        rc = btf__vk_buffer_download(g->vk, b->out, 4ull * bt->unmix[j].out_off,
                                     dst->images[j].data + (size_t)y0 * bt->width * 3,
                                     strip_bytes, err);
    btf__vk_job_abort(job);
    return rc;
}

static int run_batch(btf_gpu *g, batch *bt, uint64_t seed, const batch_dest *dst,
                     btf_error *err)
{
    batch_buffers b;
    int *keep = btf__calloc((size_t)bt->ntasks * 2, sizeof(int), err);
    int rc = keep ? buffers_make(g, bt, &b, err) : BTF_E_NOMEM;
    for (int y = 0; rc == 0 && y < bt->height; y += bt->strip) {
        int y1 = y + bt->strip < bt->height ? y + bt->strip : bt->height;
        rc = run_strip(g, bt, &b, y, y1, seed, dst, keep, err);
        g->jobs++;
    }
    g->batches++;
    if (keep)
        buffers_free(&b);
    free(keep);
    return rc;
}

/* The subspaces checked as on the CPU, and their margins (once per call:
 * planning builds batches many times). */
static btf_status check_request(const btf_model *m, const int *subs, int n,
                                int (*margins)[3][BTF_MAX_LEVELS], btf_error *err)
{
    for (int j = 0; j < n; j++) {
        if (subs[j] < 0 || subs[j] >= m->n_subspaces)
            return btf__fail(err, BTF_E_ARG, "subspace %d: the model has %d", subs[j],
                             m->n_subspaces);
        const btf_subspace_model *sm = &m->subspaces[subs[j]];
        if (sm->levels < 1 || sm->levels > BTF_MAX_LEVELS)
            return btf__fail(err, BTF_E_ARG, "subspace %d: %d pyramid levels", subs[j], sm->levels);
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < sm->levels; l++) {
                btf_status rc = btf__synth_check_band(&sm->bands[b][l], 0, err);
                if (rc)
                    return rc;
                if ((margins[j][b][l] = btf__model_margin(m, subs[j], b, l)) < 0)
                    return btf__fail(err, BTF_E_NOMEM, "out of memory");
                if ((rc = btf__synth_check_band(&sm->bands[b][l], margins[j][b][l], err)))
                    return rc;
            }
    }
    return BTF_OK;
}

/* The largest batch of images from `subs` (at most n), with the tallest
 * strips, whose buffers fit `limit` bytes; BTF_E_UNSUPPORTED if even one image
 * in strips of one row does not fit (the width alone is too large). */
static int plan_batch(const btf_model *m, const int *subs, const int (*margins)[3][BTF_MAX_LEVELS],
                      int n, int w, int h, int tileable, uint64_t limit, batch *bt, btf_error *err)
{
    for (int k = n; k >= 1; k = k / 2) {
        for (int strip = h;; strip = (strip + 1) / 2) {
            int rc = build_batch(m, subs, margins, k, w, h, strip, tileable, bt, err);
            if (rc)
                return rc;
            if (batch_need(bt) <= limit && bt->field_floats <= 0x7FFFFFFFull)
                return BTF_OK;
            uint64_t need = batch_need(bt);
            batch_free(bt);
            if (strip == 1) {
                if (k == 1)
                    return btf__fail(err, BTF_E_UNSUPPORTED,
                                     "synthesis of width %d needs a %.1f MiB GPU buffer even in "
                                     "strips of one row, more than the device's limit of %.1f MiB; "
                                     "use the CPU backend", w, need / 1048576.0, limit / 1048576.0);
                break;
            }
        }
    }
    return btf__fail(err, BTF_E_UNSUPPORTED, "no GPU batch fits"); /* not reached */
}

/* The output size of image j: opts' or, where 0, the analysed size. */
static void image_size(const btf_model *m, int sub, const btf_synth_opts *o, int *w, int *h)
{
    *w = o->width ? o->width : m->subspaces[sub].width;
    *h = o->height ? o->height : m->subspaces[sub].height;
}
/* The checks of a request (before g is used) and the images' sizes and
 * margins (margins[j], n entries, allocated here). */
static btf_status check_all(const btf_model *m, const int *subspaces, int n,
                            const btf_synth_opts *o, int *w, int *h,
                            int (**margins)[3][BTF_MAX_LEVELS], btf_error *err)
{
    *margins = NULL;
    if (!m || n < 0 || (n > 0 && !subspaces))
        return btf__fail(err, BTF_E_ARG, "GPU synthesis: no model, or %d images", n);
    if (n > 0 && !(*margins = btf__calloc((size_t)n, sizeof **margins, err)))
        return BTF_E_NOMEM;
    btf_status rc = check_request(m, subspaces, n, *margins, err);
    for (int j = 0; rc == 0 && j < n; j++) {
        image_size(m, subspaces[j], o, &w[j], &h[j]);
        rc = btf__synth_check_size(w[j], h[j], err);
        if (rc == 0 && o->tileable) /* the CPU's rule and message */
            rc = btf__synth_check_tileable(w[j], h[j], m->subspaces[subspaces[j]].levels, err);
        int match; /* the CPU's rule and message */
        if (rc == 0)
            rc = btf__colour_match_wanted(m, subspaces[j], o->match_colours, &match, err);
    }
    return rc;
}

/* Images [0, n) of one request, batch by batch (a batch holds images of
 * one size) into dst; images[j] (host) are checked for Inf and NaN. */
static btf_status run_all(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                          const btf_synth_opts *o, const int *w, const int *h,
                          const int (*margins)[3][BTF_MAX_LEVELS], const batch_dest *dst,
                          btf_error *err)
{
    uint64_t limit = btf__vk_info(g->vk)->max_storage_buffer_range;
    if (g->max_buffer_bytes && g->max_buffer_bytes < limit)
        limit = g->max_buffer_bytes;
    btf_status rc = BTF_OK;
    for (int start = 0; rc == 0 && start < n;) {
        int width = w[start], height = h[start], same = 1;
        while (start + same < n && w[start + same] == width && h[start + same] == height)
            same++;
        batch bt;
        rc = plan_batch(m, subspaces + start, margins + start, same, width, height,
                        o->tileable != 0, limit, &bt, err);
        if (rc)
            break;
        batch_dest d = {dst->images ? dst->images + start : NULL, dst->dev,
                        dst->dev_off ? dst->dev_off + start : NULL};
        rc = run_batch(g, &bt, o->seed, &d, err);
        for (int j = 0; rc == 0 && dst->images && j < bt.n_images; j++)
            for (int y = 0; rc == 0 && y < height; y++)
                rc = btf__check_finite_row(dst->images[start + j].data + (size_t)y * width * 3,
                                           (size_t)width * 3, subspaces[start + j], y, err);
        start += bt.n_images;
        batch_free(&bt);
    }
    return rc;
}
/* An image synthesised on the GPU and read back, finished by the CPU's code
 * (the bits the device's finishing gives): times the structure layer's
 * pattern (cached per size in *pattern), then colour matched when wanted. */
static btf_status finish_on_host(const btf_model *m, int subspace, const btf_synth_opts *o,
                                 btf_image *img, btf_image *pattern, btf_error *err)
{
    int match = 0;
    btf_status rc = btf__structure_apply(m, subspace, o->seed, img, pattern, err);
    if (rc == BTF_OK)
        rc = btf__colour_match_wanted(m, subspace, o->match_colours, &match, err);
    if (rc == BTF_OK && match)
        rc = btf__colour_match(m, subspace, img, err);
    return rc;
}

/* One image too large for the budget: synthesised in strips straight to the
 * host (no whole image on the device), finished there by the CPU's code
 * (the same bits as on the device), handed to fn as image i. */
static btf_status one_in_strips(btf_gpu *g, const btf_model *m, const int *sub,
                                const btf_synth_opts *o, const int *w, const int *h,
                                const int (*margins)[3][BTF_MAX_LEVELS], int i, btf_image_fn fn,
                                void *user, btf_error *err)
{
    btf_image img = {0}, pattern = {0};
    btf_status rc = btf_image_alloc(&img, *w, *h, 3, err);
    batch_dest d = {&img, NULL, NULL};
    if (rc == BTF_OK)
        rc = run_all(g, m, sub, 1, o, w, h, margins, &d, err);
    if (rc == BTF_OK)
        rc = finish_on_host(m, *sub, o, &img, &pattern, err);
    if (rc == BTF_OK)
        rc = fn(user, i, &img, err);
    btf_image_free(&pattern);
    btf_image_free(&img);
    return rc;
}

static btf_status synth_to_device(btf_gpu *g, const btf_model *m, const int *subs, int n,
                                  const btf_synth_opts *o, const int *w, const int *h,
                                  const int (*margins)[3][BTF_MAX_LEVELS], btf_gpu_images *out,
                                  uint64_t *offsets, btf_error *err);

/* Images [first, first + k) synthesised and finished on the device, then
 * read back one by one (checked for Inf and NaN) and handed to fn. */
static btf_status group_on_device(btf_gpu *g, const btf_model *m, const int *subs, int first,
                                  int k, const btf_synth_opts *o, const int *w, const int *h,
                                  const int (*margins)[3][BTF_MAX_LEVELS], btf_image_fn fn,
                                  void *user, btf_error *err)
{
    btf_gpu_images dev;
    uint64_t *off = btf__calloc((size_t)k, sizeof *off, err);
    btf_status rc = off ? synth_to_device(g, m, subs + first, k, o, w + first, h + first,
                                          margins + first, &dev, off, err)
                        : BTF_E_NOMEM;
    if (!off || rc) {
        free(off);
        return rc;
    }
    for (int j = 0; rc == BTF_OK && j < k; j++) {
        int wj = w[first + j], hj = h[first + j];
        btf_image img;
        if ((rc = btf_image_alloc(&img, wj, hj, 3, err)))
            break;
        rc = btf__gpu_images_download(g->vk, &dev, off[j], img.data, (uint64_t)wj * hj * 3, err);
        for (int y = 0; rc == BTF_OK && y < hj; y++)
            rc = btf__check_finite_row(img.data + (size_t)y * wj * 3, (size_t)wj * 3,
                                       subs[first + j], y, err);
        if (rc == BTF_OK)
            rc = fn(user, first + j, &img, err);
        btf_image_free(&img);
    }
    btf__gpu_images_free(&dev);
    free(off);
    return rc;
}

btf_status btf_gpu_synthesise_each(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                   const btf_synth_opts *opts, btf_image_fn fn, void *user,
                                   btf_error *err)
{
    btf_synth_opts o;
    if (btf__synth_resolve(opts, &o, err))
        return BTF_E_ARG;
    int (*margins)[3][BTF_MAX_LEVELS] = NULL;
    int *w = n > 0 ? btf__calloc((size_t)n * 2, sizeof(int), err) : NULL;
    int *h = w ? w + n : NULL; /* widths, heights */
    btf_status rc = n > 0 && !w ? BTF_E_NOMEM : BTF_OK;
    if (rc == BTF_OK)
        rc = check_all(m, subspaces, n, &o, w, h, &margins, err);
    if (rc == BTF_OK && (!g || !fn))
        rc = btf__fail(err, BTF_E_ARG, "GPU synthesis: no GPU (btf_gpu_open) or no receiver");
    const int (*mg)[3][BTF_MAX_LEVELS] = (const int (*)[3][BTF_MAX_LEVELS])margins;
    uint64_t budget = rc == BTF_OK ? btf_gpu_memory_budget(g) / 4 : 0; /* floats */
    if (g)
        g->jobs = g->batches = 0;
    for (int start = 0, k; rc == BTF_OK && start < n; start += k) {
        uint64_t total = 0; /* the next images that fit the budget together */
        for (k = 0; start + k < n; k++) {
            uint64_t f = 3ull * w[start + k] * h[start + k];
            if (total + f > budget)
                break;
            total += f;
        }
        if (k == 0) {
            k = 1;
            rc = one_in_strips(g, m, subspaces + start, &o, w + start, h + start, mg + start,
                               start, fn, user, err);
        } else {
            rc = group_on_device(g, m, subspaces, start, k, &o, w, h, mg, fn, user, err);
        }
    }
    free(margins);
    free(w);
    return rc;
}

/* btf_gpu_synthesise's receiver: image i kept in outs[i]. */
static int keep_image(void *user, int i, btf_image *img, btf_error *err)
{
    (void)err;
    btf_image *outs = user;
    outs[i] = *img;
    memset(img, 0, sizeof *img);
    return 0;
}

btf_status btf_gpu_synthesise(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                              const btf_synth_opts *opts, btf_image *outs, btf_error *err)
{
    for (int j = 0; j < n; j++)
        memset(&outs[j], 0, sizeof outs[j]);
    btf_status rc = btf_gpu_synthesise_each(g, m, subspaces, n, opts, keep_image, outs, err);
    if (rc)
        for (int j = 0; j < n; j++)
            btf_image_free(&outs[j]);
    return rc;
}

/* The structure layer's multiply and colour matching of one image in the
 * device array: on the device (gpu/match_gpu.c, the CPU's bits); on the
 * host by the CPU's code only where the pattern does not fit one storage
 * buffer (a side past 2,048 texels with no period: docs/gpu.md). */
static btf_status match_image(btf_gpu *g, const btf_model *m, int subspace,
                              const btf_synth_opts *o, const btf_gpu_images *im,
                              uint64_t offset, int width, int height, btf_image *pattern,
                              btf_error *err)
{
    int match;
    btf_status rc = btf__colour_match_wanted(m, subspace, o->match_colours, &match, err);
    int layer = m->albedo && btf__structure_quilted(m);
    if (rc || (!match && !layer))
        return rc;
    if (layer && (rc = btf__structure_pattern(m, width, height, o->seed, pattern, err)))
        return rc;
    /* with periodic cells, the subspace's own pattern: the CPU's bits */
    btf_image own = {0};
    const btf_image *use = NULL;
    if (layer && (rc = btf__structure_for(m, subspace, pattern, &own, &use, err)))
        return rc;
    uint64_t pat_bytes = layer ? 4ull * use->width * use->height * use->channels : 0;
    if (pat_bytes <= btf__gpu_max_buffer_bytes(g)) {
        rc = btf__gpu_match_images(g->vk, g->matcher, m, subspace, match, im, offset, width,
                                   height, layer ? use : NULL, err);
        btf_image_free(&own);
        return rc;
    }
    btf_image_free(&own);
    btf_image img;
    if ((rc = btf_image_alloc(&img, width, height, 3, err)))
        return rc;
    uint64_t floats = (uint64_t)width * height * 3;
    rc = btf__gpu_images_download(g->vk, im, offset, img.data, floats, err);
    if (rc == BTF_OK)
        rc = finish_on_host(m, subspace, o, &img, pattern, err);
    if (rc == BTF_OK)
        rc = btf__gpu_images_upload(g->vk, im, offset, img.data, floats, err);
    btf_image_free(&img);
    return rc;
}

/* Images subs[0 .. n) of the checked request into the device array *out
 * (created here), synthesised, then finished (the structure layer,
 * colour matching) there. */
static btf_status synth_to_device(btf_gpu *g, const btf_model *m, const int *subs, int n,
                                  const btf_synth_opts *o, const int *w, const int *h,
                                  const int (*margins)[3][BTF_MAX_LEVELS], btf_gpu_images *out,
                                  uint64_t *offsets, btf_error *err)
{
    uint64_t floats = 0;
    for (int j = 0; j < n; j++) {
        offsets[j] = floats;
        floats += (uint64_t)w[j] * h[j] * 3;
    }
    char what[96];
    snprintf(what, sizeof what, "GPU synthesis to the device: %d images", n);
    btf_status rc = btf__gpu_images_create(g->vk, floats, btf__gpu_images_cap(g),
                                           btf__gpu_images_buffers(g), what, out, err);
    batch_dest d = {NULL, out, offsets};
    if (rc == BTF_OK)
        rc = run_all(g, m, subs, n, o, w, h, margins, &d, err);
    btf_image pattern = {0}; /* the structure layer's, quilted once per size */
    for (int j = 0; rc == BTF_OK && j < n; j++)
        rc = match_image(g, m, subs[j], o, out, offsets[j], w[j], h[j], &pattern, err);
    btf_image_free(&pattern);
    if (rc)
        btf__gpu_images_free(out);
    return rc;
}

btf_status btf__gpu_synthesise_device(btf_gpu *g, const btf_model *m, const int *subspaces, int n,
                                      const btf_synth_opts *opts, btf_gpu_images *out,
                                      uint64_t *offsets, btf_error *err)
{
    btf_synth_opts o;
    if (btf__synth_resolve(opts, &o, err))
        return BTF_E_ARG;
    if (out)
        memset(out, 0, sizeof *out);
    if (!g || n < 1 || !offsets || !out)
        return btf__fail(err, BTF_E_ARG, "GPU synthesis to the device: no GPU, no output or "
                         "%d images (at least 1)", n);
    int (*margins)[3][BTF_MAX_LEVELS] = NULL;
    int *w = btf__calloc((size_t)n * 2, sizeof(int), err);
    btf_status rc = w ? check_all(m, subspaces, n, &o, w, w + n, &margins, err) : BTF_E_NOMEM;
    g->jobs = g->batches = 0;
    if (rc == BTF_OK)
        rc = synth_to_device(g, m, subspaces, n, &o, w, w + n,
                             (const int (*)[3][BTF_MAX_LEVELS])margins, out, offsets, err);
    free(margins);
    free(w);
    return rc;
}
