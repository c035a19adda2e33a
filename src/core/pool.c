/*
 * pool.c — the library's one thread pool: runs jobs 0..N-1 of a batch over
 * T threads, the calling thread among them. Every stage whose work splits
 * into independent pieces uses it: the image features of segmentation
 * (paper section II.A), the rows of photometric stereo (section II.B) and
 * the images of the procedural generator.
 *
 * Jobs are handed out one at a time from a shared counter, so a slow job
 * does not hold back a fixed share of the others. Each job runs exactly once
 * (until a failure stops the batch), and a job's output may depend only on
 * its index: then the result is the same for any thread count. The worker
 * index exists only so that callers can give each thread its own scratch.
 *
 * The first failure wins: its status and message are returned, and workers
 * take no new job once it is recorded (jobs already running finish).
 * Progress is reported from the calling thread only, so that a caller's
 * callback need not be thread-safe nor care which thread it runs on; after
 * the last job the final fraction is always reported once.
 *
 * The relay (btf_relay_*) is the other shape of parallel work: a pipeline
 * of two stages, the caller's and one long-lived helper thread's, handing
 * over a job at a time. A batch per hand-over would start and join a
 * thread each time (tens of microseconds, hundreds of times per image).
 */
#include "core/core.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

typedef struct pool_run {
    int jobs;
    btf_pool_job_fn job;
    void *user;
    const btf_pool_progress *progress;
    int reported;           /* jobs done at the last progress report */
    atomic_int next, done, failed;
    pthread_mutex_t lock;   /* guards status and error */
    btf_status status;
    btf_error error;
} pool_run;

typedef struct pool_worker {
    pool_run *run;
    int index;
} pool_worker;

static void report(pool_run *r, int done)
{
    const btf_pool_progress *p = r->progress;
    r->reported = done;
    p->fn(p->user, p->from + (p->to - p->from) * (double)done / (double)r->jobs, p->what);
}

static void *work(void *arg)
{
    pool_worker *w = arg;
    pool_run *r = w->run;
    const btf_pool_progress *p = w->index == 0 && r->progress && r->progress->fn ? r->progress
                                                                                 : NULL;
    int every = p && p->every > 1 ? p->every : 1;
    btf_error e = {0};
    while (!atomic_load(&r->failed)) {
        int t = atomic_fetch_add(&r->next, 1);
        if (t >= r->jobs)
            break;
        btf_status rc = r->job(r->user, t, w->index, &e);
        if (rc != BTF_OK) {
            pthread_mutex_lock(&r->lock);
            if (!atomic_load(&r->failed)) {
                r->status = rc;
                r->error = e;
                atomic_store(&r->failed, 1);
            }
            pthread_mutex_unlock(&r->lock);
            break;
        }
        int d = atomic_fetch_add(&r->done, 1) + 1;
        if (p && d - r->reported >= every && d < r->jobs)
            report(r, d);
    }
    return NULL;
}

int btf__pool_workers(int threads, int jobs)
{
    int n = threads > 0 ? threads : btf__cpu_count();
    if (n > BTF_POOL_MAX_THREADS)
        n = BTF_POOL_MAX_THREADS;
    if (n > jobs)
        n = jobs;
    return n < 1 ? 1 : n;
}

btf_status btf__pool_run(int jobs, int threads, btf_pool_job_fn job, void *user,
                         const btf_pool_progress *progress, btf_error *err)
{
    if (jobs <= 0)
        return BTF_OK;
    if (!job)
        return btf__fail(err, BTF_E_ARG, "thread pool: no job function given");
    pool_run r = {.jobs = jobs, .job = job, .user = user, .progress = progress,
                  .status = BTF_OK};
    atomic_init(&r.next, 0);
    atomic_init(&r.done, 0);
    atomic_init(&r.failed, 0);
    pthread_mutex_init(&r.lock, NULL);
    int workers = btf__pool_workers(threads, jobs);
    pthread_t tid[BTF_POOL_MAX_THREADS];
    pool_worker arg[BTF_POOL_MAX_THREADS];
    int started = 0;
    for (int i = 1; i < workers; i++) {
        arg[i] = (pool_worker){&r, i};
        /* A thread that cannot be started only means fewer workers: the
         * jobs still all get done, by the others. */
        if (pthread_create(&tid[i], NULL, work, &arg[i]) != 0)
            break;
        started = i;
    }
    arg[0] = (pool_worker){&r, 0};
    work(&arg[0]);
    for (int i = 1; i <= started; i++)
        pthread_join(tid[i], NULL);
    pthread_mutex_destroy(&r.lock);
    if (atomic_load(&r.failed)) {
        if (err)
            *err = r.error;
        return r.status;
    }
    if (progress && progress->fn)
        report(&r, jobs);
    return BTF_OK;
}

struct btf_relay {
    btf_pool_job_fn job;
    void *user;
    int threaded;           /* a helper thread takes jobs too */
    pthread_t tid;
    pthread_mutex_t lock;   /* guards what follows */
    pthread_cond_t cond;    /* a new batch (for the helper), a batch done (for the caller) */
    int first, count;       /* the batch: jobs first .. first + count - 1 */
    int next, done, stop;   /* jobs handed out, jobs finished */
    btf_status status;      /* the batch's first failure */
    btf_error error;
    atomic_int posted;      /* batches posted, background, stop: what the idle helper spins on */
    btf_background *bg;     /* work for the helper's idle time, or NULL */
};

/* How long an idle relay helper polls for the next batch before it sleeps.
 * A relay lives for one image, whose batches come every few hundred
 * microseconds; waking a sleeping thread took longer than a batch's work
 * on a 2-core VM (the colour step ran mostly on the caller: the marginal
 * transfer cost +33 % of the synthesis where it costs a fifth of the
 * fields' CPU time), so the helper stays awake that long. */
#define RELAY_SPIN_S 2e-3

static void cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
}

/* With the lock held: polls r->posted (unlocked) until it moves from
 * `seen` or RELAY_SPIN_S pass; returns with the lock held again. */
static void relay_spin(btf_relay *r, int seen)
{
    pthread_mutex_unlock(&r->lock);
    double t0 = btf__now();
    for (int i = 0; atomic_load(&r->posted) == seen; i++) {
        cpu_relax();
        if ((i & 63) == 63 && btf__now() - t0 > RELAY_SPIN_S)
            break;
    }
    pthread_mutex_lock(&r->lock);
}

/* Runs jobs of the batch until none is left; called and returns with the
 * lock held. A job runs unlocked; a failure stops the hand-out. */
static void relay_run(btf_relay *r, int worker)
{
    while (r->next < r->count) {
        int j = r->first + r->next++;
        pthread_mutex_unlock(&r->lock);
        btf_error e = {0};
        btf_status rc = r->job(r->user, j, worker, &e);
        pthread_mutex_lock(&r->lock);
        if (rc != BTF_OK && r->status == BTF_OK) {
            r->status = rc;
            r->error = e;
            r->count = r->next; /* the jobs handed out still finish */
        }
        if (++r->done == r->count)
            pthread_cond_broadcast(&r->cond);
    }
}

static int background_left(const btf_relay *r)
{
    return r->bg && r->bg->done < r->bg->count && r->bg->status == BTF_OK;
}

/* One background job; called and returns with the lock held. Only the
 * helper touches bg while the relay runs, so the job itself runs unlocked. */
static void background_step(btf_relay *r)
{
    btf_background *bg = r->bg;
    int j = bg->done;
    pthread_mutex_unlock(&r->lock);
    btf_error e = {0};
    btf_status rc = bg->fn(bg->user, j, 1, &e);
    pthread_mutex_lock(&r->lock);
    if (rc != BTF_OK)
        bg->status = rc, bg->error = e;
    else
        bg->done++;
}

static void *relay_main(void *arg)
{
    btf_relay *r = arg;
    pthread_mutex_lock(&r->lock);
    for (;;) {
        if (r->next < r->count) { /* the pipeline's batch first */
            relay_run(r, 1);
            continue;
        }
        if (r->stop)
            break;
        if (background_left(r)) {
            background_step(r);
            continue;
        }
        relay_spin(r, atomic_load(&r->posted));
        while (r->next >= r->count && !r->stop && !background_left(r))
            pthread_cond_wait(&r->cond, &r->lock);
    }
    pthread_mutex_unlock(&r->lock);
    return NULL;
}

void btf__relay_background(btf_relay *r, btf_background *bg)
{
    pthread_mutex_lock(&r->lock);
    r->bg = bg;
    atomic_fetch_add(&r->posted, 1);
    if (r->threaded)
        pthread_cond_broadcast(&r->cond);
    pthread_mutex_unlock(&r->lock);
}

btf_relay *btf__relay_start(btf_pool_job_fn job, void *user, btf_error *err)
{
    btf_relay *r = btf__calloc(1, sizeof *r, err);
    if (!r)
        return NULL;
    r->job = job;
    r->user = user;
    atomic_init(&r->posted, 0);
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->cond, NULL);
    /* one CPU: a second thread would only take turns with the caller */
    r->threaded = btf__cpu_count() > 1 && pthread_create(&r->tid, NULL, relay_main, r) == 0;
    return r;
}

void btf__relay_post(btf_relay *r, int first, int count)
{
    pthread_mutex_lock(&r->lock);
    r->first = first;
    r->count = count > 0 ? count : 0;
    r->next = r->done = 0;
    r->status = BTF_OK;
    atomic_fetch_add(&r->posted, 1);
    if (r->threaded)
        pthread_cond_broadcast(&r->cond);
    pthread_mutex_unlock(&r->lock);
}

btf_status btf__relay_wait(btf_relay *r, btf_error *err)
{
    pthread_mutex_lock(&r->lock);
    relay_run(r, 0); /* what the helper has not taken yet, the caller does */
    while (r->done < r->count)
        pthread_cond_wait(&r->cond, &r->lock);
    btf_status rc = r->status;
    if (rc && err)
        *err = r->error;
    pthread_mutex_unlock(&r->lock);
    return rc;
}

void btf__relay_stop(btf_relay *r)
{
    if (!r)
        return;
    if (r->threaded) {
        pthread_mutex_lock(&r->lock);
        r->stop = 1;
        atomic_fetch_add(&r->posted, 1);
        pthread_cond_broadcast(&r->cond);
        pthread_mutex_unlock(&r->lock);
        pthread_join(r->tid, NULL);
    }
    pthread_cond_destroy(&r->cond);
    pthread_mutex_destroy(&r->lock);
    free(r);
}
