/*
 * test_behind.c — writing behind (src/core/behind.c), which btfcar
 * synthesise's whole images and the EXR writer's slabs share: jobs run in
 * the order they are put; put blocks while `depth` jobs are held, the
 * running one counted; the first failure is kept, returned by every later
 * put and by the finish with its message, and no job runs after it; every
 * job goes to done once, run or not; finish and abort with nothing queued;
 * a start that fails (a bad spec, no thread), and the fallback that runs
 * the jobs in put when no thread can be had.
 *
 * pthread_create is wrapped (-Wl,--wrap=pthread_create, Makefile) so that
 * a test can make the start's thread fail.
 */
#include "testutil.h"
#include "core/behind.h"
#include "core/core.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <time.h>

#define MAX_JOBS 64

int __real_pthread_create(pthread_t *t, const pthread_attr_t *a, void *(*fn)(void *), void *arg);

static atomic_int refuse_threads; /* 1: the next pthread_create fails */

int __wrap_pthread_create(pthread_t *t, const pthread_attr_t *a, void *(*fn)(void *), void *arg)
{
    if (atomic_exchange(&refuse_threads, 0))
        return EAGAIN;
    return __real_pthread_create(t, a, fn, arg);
}

/* What the jobs did: the order they ran in, the jobs done, and a gate the
 * test opens one job at a time (released: jobs allowed to finish). */
typedef struct record {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    int order[MAX_JOBS], ran, done[MAX_JOBS], n_done;
    int gated, released, started;
    int fail_from;          /* jobs from this one fail; -1: none */
    pthread_t runner;       /* the thread of the last run */
} record;

typedef struct job {
    int id;
} job;

static void record_init(record *r, int gated, int fail_from)
{
    memset(r, 0, sizeof *r);
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->cond, NULL);
    r->gated = gated;
    r->fail_from = fail_from;
}

static void record_free(record *r)
{
    pthread_cond_destroy(&r->cond);
    pthread_mutex_destroy(&r->lock);
}

static btf_status run(void *user, void *p, btf_error *err)
{
    record *r = user;
    int id = ((job *)p)->id;
    pthread_mutex_lock(&r->lock);
    r->started++;
    pthread_cond_broadcast(&r->cond);
    while (r->gated && r->released <= id)
        pthread_cond_wait(&r->cond, &r->lock);
    r->order[r->ran++] = id;
    r->runner = pthread_self();
    pthread_mutex_unlock(&r->lock);
    if (r->fail_from >= 0 && id >= r->fail_from)
        return btf__fail(err, BTF_E_IO, "job %d failed", id);
    return BTF_OK;
}

static void done(void *user, void *p)
{
    record *r = user;
    pthread_mutex_lock(&r->lock);
    r->done[((job *)p)->id]++;
    r->n_done++;
    pthread_cond_broadcast(&r->cond);
    pthread_mutex_unlock(&r->lock);
}

static btf_behind *start(record *r, int depth, btf_error *e)
{
    btf_behind_spec spec = {.run = run, .done = done, .user = r, .job_size = sizeof(job),
                            .depth = depth};
    btf_behind *b = btf__behind_start(&spec, e);
    if (!b)
        print_error("start: %s\n", e->msg);
    assert_non_null(b);
    return b;
}

static void release_jobs(record *r, int upto)
{
    pthread_mutex_lock(&r->lock);
    r->released = upto;
    pthread_cond_broadcast(&r->cond);
    pthread_mutex_unlock(&r->lock);
}

static int get(record *r, const int *field)
{
    pthread_mutex_lock(&r->lock);
    int v = *field;
    pthread_mutex_unlock(&r->lock);
    return v;
}

/* Every job, in the order put, each to done once; at depths 1, 2 and 5. */
static void jobs_in_order(void **state)
{
    (void)state;
    static const int depths[] = {1, 2, 5};
    for (int d = 0; d < 3; d++) {
        record r;
        record_init(&r, 0, -1);
        btf_error e = {0};
        btf_behind *b = start(&r, depths[d], &e);
        for (int i = 0; i < 50; i++)
            TU_OK(btf__behind_put(b, &(job){i}, &e), &e);
        TU_OK(btf__behind_finish(b, &e), &e);
        assert_int_equal(r.ran, 50);
        assert_int_equal(r.n_done, 50);
        for (int i = 0; i < 50; i++) {
            assert_int_equal(r.order[i], i);
            assert_int_equal(r.done[i], 1);
        }
        assert_false(pthread_equal(r.runner, pthread_self())); /* on the thread */
        record_free(&r);
    }
}

typedef struct putter {
    btf_behind *b;
    record *r;
    int id;
    atomic_int returned;
    int done_at_return;     /* jobs done when the put returned */
    btf_status status;
} putter;

static void *put_one(void *arg)
{
    putter *p = arg;
    btf_error e = {0};
    p->status = btf__behind_put(p->b, &(job){p->id}, &e);
    p->done_at_return = get(p->r, &p->r->n_done);
    atomic_store(&p->returned, 1);
    return NULL;
}

static void sleep_ms(int ms)
{
    struct timespec ts = {0, ms * 1000000L};
    nanosleep(&ts, NULL);
}

/* Put returns at once while fewer than depth jobs are held (the running
 * one counted) and blocks on the next until the oldest is done: with depth
 * 1, until the previous job is done. */
static void put_blocks_at_depth(void **state)
{
    (void)state;
    for (int depth = 1; depth <= 3; depth += 2) {
        record r;
        record_init(&r, 1, -1);
        btf_error e = {0};
        btf_behind *b = start(&r, depth, &e);
        for (int i = 0; i < depth; i++) /* job 0 runs and waits at the gate */
            TU_OK(btf__behind_put(b, &(job){i}, &e), &e);
        putter p = {.b = b, .r = &r, .id = depth};
        pthread_t t;
        assert_int_equal(__real_pthread_create(&t, NULL, put_one, &p), 0);
        sleep_ms(100);
        assert_false(atomic_load(&p.returned)); /* held: depth jobs */
        assert_int_equal(get(&r, &r.n_done), 0);
        release_jobs(&r, 1); /* job 0 finishes: a slot frees */
        pthread_join(t, NULL);
        assert_int_equal(p.status, BTF_OK);
        assert_int_equal(p.done_at_return, 1);
        release_jobs(&r, MAX_JOBS);
        TU_OK(btf__behind_finish(b, &e), &e);
        assert_int_equal(r.ran, depth + 1);
        for (int i = 0; i <= depth; i++)
            assert_int_equal(r.order[i], i);
        record_free(&r);
    }
}

/* Job 3 fails (and so would every later one): puts after it return its
 * status and message, the finish too; no job runs after it, and every
 * job, run, skipped or refused, goes to done once. */
static void first_failure_kept(void **state)
{
    (void)state;
    for (int depth = 1; depth <= 4; depth += 3) {
        record r;
        record_init(&r, 0, 3);
        btf_error e = {0};
        btf_behind *b = start(&r, depth, &e);
        int failed = 0;
        for (int i = 0; i < 20; i++) {
            memset(&e, 0, sizeof e);
            btf_status rc = btf__behind_put(b, &(job){i}, &e);
            assert_true(rc == BTF_OK || rc == BTF_E_IO);
            if (failed) /* once failed, always failed */
                assert_int_equal(rc, BTF_E_IO);
            if (rc) {
                assert_string_equal(e.msg, "job 3 failed");
                assert_int_equal(e.code, BTF_E_IO);
                failed = 1;
            }
            if (i == 10) /* a put after the failure is certain to see it */
                while (get(&r, &r.ran) < 4)
                    sleep_ms(1);
        }
        assert_true(failed);
        memset(&e, 0, sizeof e);
        assert_int_equal(btf__behind_finish(b, &e), BTF_E_IO);
        assert_string_equal(e.msg, "job 3 failed");
        assert_int_equal(r.ran, 4); /* 0, 1, 2 and the failing 3 */
        for (int i = 0; i < 4; i++)
            assert_int_equal(r.order[i], i);
        assert_int_equal(r.n_done, 20);
        for (int i = 0; i < 20; i++)
            assert_int_equal(r.done[i], 1);
        record_free(&r);
    }
}

static void *release_later(void *arg)
{
    sleep_ms(200); /* the abort comes first: job 1 never starts */
    release_jobs(arg, 1);
    return NULL;
}

/* A finish or an abort with nothing queued; NULL for either; an abort
 * lets the running job finish and runs none of the queued ones. */
static void finish_and_abort(void **state)
{
    (void)state;
    record r;
    record_init(&r, 0, -1);
    btf_error e = {0};
    TU_OK(btf__behind_finish(start(&r, 1, &e), &e), &e);
    btf__behind_abort(start(&r, 3, &e));
    assert_int_equal(btf__behind_finish(NULL, &e), BTF_OK);
    btf__behind_abort(NULL);
    assert_int_equal(r.ran, 0);
    assert_int_equal(r.n_done, 0);
    record_free(&r);

    record_init(&r, 1, -1);
    btf_behind *b = start(&r, 3, &e);
    for (int i = 0; i < 3; i++)
        TU_OK(btf__behind_put(b, &(job){i}, &e), &e);
    pthread_mutex_lock(&r.lock);
    while (r.started < 1) /* job 0 runs (at the gate) */
        pthread_cond_wait(&r.cond, &r.lock);
    pthread_mutex_unlock(&r.lock);
    pthread_t t;
    assert_int_equal(__real_pthread_create(&t, NULL, release_later, &r), 0);
    btf__behind_abort(b); /* waits for job 0, which the helper lets go */
    pthread_join(t, NULL);
    assert_int_equal(r.ran, 1);
    assert_int_equal(r.order[0], 0);
    assert_int_equal(r.n_done, 3);
    for (int i = 0; i < 3; i++)
        assert_int_equal(r.done[i], 1);
    record_free(&r);
}

/* A bad spec; no thread to be had (the start fails, with the message the
 * EXR writer passes on), or with the fallback, jobs run in put by the same
 * rules: in order, the first failure kept, nothing after it. */
static void failing_start(void **state)
{
    (void)state;
    record r;
    record_init(&r, 0, 2);
    btf_error e = {0};
    btf_behind_spec spec = {.run = run, .done = done, .user = &r, .job_size = sizeof(job),
                            .depth = 0};
    assert_null(btf__behind_start(&spec, &e));
    assert_int_equal(e.code, BTF_E_ARG);
    spec.depth = 1, spec.run = NULL;
    assert_null(btf__behind_start(&spec, &e));
    assert_null(btf__behind_start(NULL, NULL));
    spec.run = run;
    atomic_store(&refuse_threads, 1);
    memset(&e, 0, sizeof e);
    assert_null(btf__behind_start(&spec, &e));
    assert_int_equal(e.code, BTF_E_NOMEM);
    assert_non_null(strstr(e.msg, "cannot start the writer thread"));
    spec.run_here_without_thread = 1;
    atomic_store(&refuse_threads, 1);
    btf_behind *b = btf__behind_start(&spec, &e);
    assert_non_null(b);
    assert_int_equal(atomic_load(&refuse_threads), 0); /* it did try */
    for (int i = 0; i < 5; i++) {
        btf_status rc = btf__behind_put(b, &(job){i}, &e);
        assert_int_equal(rc, i < 2 ? BTF_OK : BTF_E_IO);
        assert_int_equal(r.ran, i < 2 ? i + 1 : 3); /* ran in the put itself */
        assert_int_equal(r.n_done, i + 1);
        if (rc)
            assert_string_equal(e.msg, "job 2 failed");
    }
    assert_true(pthread_equal(r.runner, pthread_self()));
    memset(&e, 0, sizeof e);
    assert_int_equal(btf__behind_finish(b, &e), BTF_E_IO);
    assert_string_equal(e.msg, "job 2 failed");
    for (int i = 0; i < 3; i++)
        assert_int_equal(r.order[i], i);
    record_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(jobs_in_order),
        cmocka_unit_test(put_blocks_at_depth),
        cmocka_unit_test(first_failure_kept),
        cmocka_unit_test(finish_and_abort),
        cmocka_unit_test(failing_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
