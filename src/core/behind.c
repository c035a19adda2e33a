/*
 * behind.c — writing behind (behind.h): one thread, a ring of `depth` job
 * slots, one lock and one condition.
 *
 * A job keeps its slot, and counts as held, until it has run and gone to
 * done: so the slot is the job's memory while it runs, and "put waits
 * until the previous job is done" (depth 1) is the same rule as "put waits
 * for a free slot". One condition serves both sides (a job queued or a stop
 * for the thread, a slot freed or a failure for the caller): each side
 * wakes once per job, so broadcasting costs nothing worth a second one.
 *
 * After a failure the thread still takes every queued job off the ring and
 * hands it to done without running it: the jobs after a failed one would
 * leave a hole in what is written (a file without its rows), and the
 * caller gets the failure from its next put or the finish anyway.
 */
#include "core/behind.h"
#include "core/core.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

enum { RUN_QUEUED = 1, DROP_QUEUED = 2 }; /* how the thread stops: finish, abort */

struct btf_behind {
    btf_behind_spec spec;
    unsigned char *slots;  /* depth jobs of job_size bytes, a ring */
    int head, count;       /* the oldest job held (running or next); how many */
    int stop;              /* 0, RUN_QUEUED or DROP_QUEUED */
    btf_status status;     /* the first failure, and its message */
    btf_error error;
    int has_thread;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t cond;
};

static void *slot(btf_behind *b, int i)
{
    return b->slots + (size_t)(i % b->spec.depth) * b->spec.job_size;
}

static void job_done(btf_behind *b, void *job)
{
    if (b->spec.done)
        b->spec.done(b->spec.user, job);
}

/* Runs the job unless told to skip it, then hands it to done; its status
 * (BTF_OK when skipped), the message in e. */
static btf_status run_job(btf_behind *b, void *job, int skip, btf_error *e)
{
    btf_status rc = skip ? BTF_OK : b->spec.run(b->spec.user, job, e);
    job_done(b, job);
    return rc;
}

/* The first failure is the one reported; later ones are its consequences. */
static void keep_failure(btf_behind *b, btf_status rc, const btf_error *e)
{
    if (rc && !b->status)
        b->status = rc, b->error = *e;
}

/* The kept failure into err (may be NULL); its status, or BTF_OK. */
static btf_status kept_failure(const btf_behind *b, btf_error *err)
{
    if (b->status && err)
        *err = b->error;
    return b->status;
}

/* The thread: the held jobs in order, until a stop finds none left. */
static void *behind_main(void *arg)
{
    btf_behind *b = arg;
    pthread_mutex_lock(&b->lock);
    for (;;) {
        while (!b->count && !b->stop)
            pthread_cond_wait(&b->cond, &b->lock);
        if (!b->count)
            break;
        void *job = slot(b, b->head);
        int skip = b->status != BTF_OK || b->stop == DROP_QUEUED;
        pthread_mutex_unlock(&b->lock);
        btf_error e = {0};
        btf_status rc = run_job(b, job, skip, &e);
        pthread_mutex_lock(&b->lock);
        keep_failure(b, rc, &e);
        b->head = (b->head + 1) % b->spec.depth;
        b->count--;
        pthread_cond_broadcast(&b->cond);
    }
    pthread_mutex_unlock(&b->lock);
    return NULL;
}

/* The lock, the condition and the thread. Without a thread, when the spec
 * allows it, b runs each job in put instead. */
static btf_status start_thread(btf_behind *b, btf_error *err)
{
    if (pthread_mutex_init(&b->lock, NULL) != 0)
        return btf__fail(err, BTF_E_NOMEM, "cannot create a lock");
    if (pthread_cond_init(&b->cond, NULL) != 0) {
        pthread_mutex_destroy(&b->lock);
        return btf__fail(err, BTF_E_NOMEM, "cannot create a condition");
    }
    int e = pthread_create(&b->thread, NULL, behind_main, b);
    b->has_thread = e == 0;
    if (e && !b->spec.run_here_without_thread) {
        pthread_cond_destroy(&b->cond);
        pthread_mutex_destroy(&b->lock);
        return btf__fail(err, BTF_E_NOMEM, "cannot start the writer thread: %s", strerror(e));
    }
    return BTF_OK;
}

btf_behind *btf__behind_start(const btf_behind_spec *spec, btf_error *err)
{
    if (!spec || !spec->run || spec->job_size < 1 || spec->depth < 1) {
        btf__fail(err, BTF_E_ARG, "write-behind: no job function, or a job size or depth below 1");
        return NULL;
    }
    btf_behind *b = btf__calloc(1, sizeof *b, err);
    if (!b)
        return NULL;
    b->spec = *spec;
    b->slots = btf__calloc((size_t)spec->depth, spec->job_size, err);
    if (!b->slots || start_thread(b, err) != BTF_OK) {
        free(b->slots);
        free(b);
        return NULL;
    }
    return b;
}

/* put without a thread: the job runs here, by the same rules. */
static btf_status run_here(btf_behind *b, void *job, btf_error *err)
{
    void *s = slot(b, 0);
    memcpy(s, job, b->spec.job_size);
    btf_error e = {0};
    keep_failure(b, run_job(b, s, b->status != BTF_OK, &e), &e);
    return kept_failure(b, err);
}

btf_status btf__behind_put(btf_behind *b, void *job, btf_error *err)
{
    if (!b->has_thread)
        return run_here(b, job, err);
    pthread_mutex_lock(&b->lock);
    while (b->count == b->spec.depth && !b->status)
        pthread_cond_wait(&b->cond, &b->lock);
    btf_status rc = kept_failure(b, err);
    if (!rc) {
        memcpy(slot(b, b->head + b->count), job, b->spec.job_size);
        b->count++;
        pthread_cond_broadcast(&b->cond);
    }
    pthread_mutex_unlock(&b->lock);
    if (rc)
        job_done(b, job); /* refused: it will never run */
    return rc;
}

/* Tells the thread how to stop and waits for it. */
static void stop_thread(btf_behind *b, int how)
{
    if (!b->has_thread)
        return;
    pthread_mutex_lock(&b->lock);
    b->stop = how;
    pthread_cond_broadcast(&b->cond);
    pthread_mutex_unlock(&b->lock);
    pthread_join(b->thread, NULL);
    b->has_thread = 0;
}

static void release(btf_behind *b)
{
    pthread_cond_destroy(&b->cond);
    pthread_mutex_destroy(&b->lock);
    free(b->slots);
    free(b);
}

btf_status btf__behind_finish(btf_behind *b, btf_error *err)
{
    if (!b)
        return BTF_OK;
    stop_thread(b, RUN_QUEUED); /* every job has run or been skipped: the status is final */
    btf_status rc = kept_failure(b, err);
    release(b);
    return rc;
}

void btf__behind_abort(btf_behind *b)
{
    if (!b)
        return;
    stop_thread(b, DROP_QUEUED);
    release(b);
}
