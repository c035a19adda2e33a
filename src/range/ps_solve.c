/*
 * ps_solve.c — the robust fit of every pixel of an image (photometric
 * stereo, Haindl & Filip 2007, section II.B): gathers each row's samples,
 * fits each pixel inside the mask (ps_fit.c) or gives it the fallback
 * normal (0, 0, 1), and records which samples each fit kept for the
 * albedo pass. Rows go to the thread pool in blocks; each pixel is
 * independent, so the result does not depend on the thread count.
 */
#include "range/range.h"
#include "core/core.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Rows per pool job: enough work per job to make handing it out cheap,
 * few enough that the jobs balance over the threads. */
#define ROWS_PER_JOB 8

typedef struct solve_batch {
    btf_ps_solve *job;
    btf_ps_scratch *scratch;   /* one per worker */
    atomic_int fitted, fallback;
} solve_batch;

static void solve_row(btf_ps_solve *j, btf_ps_scratch *s, int y, int *fitted, int *fallback)
{
    int w = j->width, n = j->count;
    size_t wh = (size_t)w * j->height, base = (size_t)y * w;
    /* Gather the row pixel-major: each image's row is contiguous. */
    for (int i = 0; i < n; i++) {
        const float *src = j->grey + (size_t)i * wh + base;
        for (int x = 0; x < w; x++)
            s->row_samples[(size_t)x * n + i] = src[x];
    }
    for (int x = 0; x < w; x++) {
        size_t k = base + (size_t)x;
        if (!j->inside[k])
            continue;
        const double *samples = s->row_samples + (size_t)x * n;
        double g[3] = {0, 0, 0}; /* the scaled normal, albedo x normal */
        int ok = btf__ps_fit_pixel(&j->params, j->lights, j->halfway, n, samples, s, g);
        float *normal = j->normal + 3 * k;
        if (ok) {
            double albedo = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            normal[0] = (float)(g[0] / albedo);
            normal[1] = (float)(g[1] / albedo);
            normal[2] = (float)(g[2] / albedo);
            int used = 0;
            for (int i = 0; i < n; i++)
                used += s->in_fit[i];
            j->lights_used[k] = (float)used;
            j->valid[k] = 1.0f;
            ++*fitted;
        } else {
            btf__ps_fallback_set(j->lights, n, samples, s->in_fit);
            normal[0] = normal[1] = 0.0f;
            normal[2] = 1.0f;
            ++*fallback;
        }
        uint64_t *set = j->fit_sets + k * (size_t)j->set_words;
        for (int i = 0; i < n; i++)
            if (s->in_fit[i])
                set[i >> 6] |= (uint64_t)1 << (i & 63);
    }
}

static btf_status solve_rows(void *user, int block, int worker, btf_error *err)
{
    (void)err;
    solve_batch *b = user;
    btf_ps_solve *j = b->job;
    int y0 = block * ROWS_PER_JOB;
    int y1 = y0 + ROWS_PER_JOB < j->height ? y0 + ROWS_PER_JOB : j->height;
    int fitted = 0, fallback = 0;
    for (int y = y0; y < y1; y++)
        solve_row(j, &b->scratch[worker], y, &fitted, &fallback);
    atomic_fetch_add(&b->fitted, fitted);
    atomic_fetch_add(&b->fallback, fallback);
    return BTF_OK;
}

btf_status btf__ps_solve_all(btf_ps_solve *job, int threads, btf_progress_fn progress,
                             void *progress_user, double from, double to, btf_error *err)
{
    int blocks = (job->height + ROWS_PER_JOB - 1) / ROWS_PER_JOB;
    int workers = btf__pool_workers(threads, blocks);
    solve_batch b = {.job = job};
    atomic_init(&b.fitted, 0);
    atomic_init(&b.fallback, 0);
    b.scratch = btf__calloc((size_t)workers, sizeof *b.scratch, err);
    if (!b.scratch)
        return BTF_E_NOMEM;
    btf_status rc = BTF_OK;
    int made = 0;
    for (; made < workers && rc == BTF_OK; made++)
        rc = btf__ps_scratch_alloc(&b.scratch[made], job->count, job->width, err);
    btf_pool_progress pp = {progress, progress_user, "fitting normals", from, to, 1};
    if (rc == BTF_OK)
        rc = btf__pool_run(blocks, threads, solve_rows, &b, &pp, err);
    for (int t = 0; t < made; t++)
        btf__ps_scratch_free(&b.scratch[t]);
    free(b.scratch);
    job->fitted = atomic_load(&b.fitted);
    job->fallback = atomic_load(&b.fallback);
    return rc;
}
