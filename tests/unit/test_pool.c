/*
 * test_pool.c — the library's thread pool (src/core/pool.c), which the
 * segmentation features, photometric stereo and the generator share: every
 * job runs exactly once whatever the thread count, worker indices stay
 * below btf__pool_workers, the first failure is returned with its message
 * and stops the batch, and progress comes from the calling thread only,
 * in order, ending at its `to` fraction. The relay (btf_relay_*): every job
 * of every batch runs exactly once, while the caller works on, on worker 0
 * or 1; the caller does the jobs a busy helper has not taken; the first
 * failure stops the batch and comes back with its message.
 */
#include "testutil.h"
#include "core/core.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define JOBS 1000

typedef struct batch {
    atomic_int runs[JOBS];
    unsigned results[JOBS];
    int workers;
    atomic_int bad_worker;
    int fail_at;              /* the job that fails; -1: none */
    atomic_int started;
} batch;

static btf_status job(void *user, int j, int worker, btf_error *err)
{
    batch *b = user;
    atomic_fetch_add(&b->started, 1);
    if (worker < 0 || worker >= b->workers)
        atomic_store(&b->bad_worker, 1);
    atomic_fetch_add(&b->runs[j], 1);
    /* Output that depends on the job index alone. */
    unsigned h = 2166136261u ^ (unsigned)j;
    for (int i = 0; i < 100; i++)
        h = (h ^ (unsigned)i) * 16777619u;
    b->results[j] = h;
    if (j == b->fail_at)
        return btf__fail(err, BTF_E_DATA, "job %d failed on purpose", j);
    return BTF_OK;
}

static void batch_init(batch *b, int threads, int fail_at)
{
    memset(b, 0, sizeof *b);
    b->workers = btf__pool_workers(threads, JOBS);
    b->fail_at = fail_at;
}

static void every_job_once(void **state)
{
    (void)state;
    static batch ref, b;
    batch_init(&ref, 1, -1);
    btf_error err = {0};
    TU_OK(btf__pool_run(JOBS, 1, job, &ref, NULL, &err), &err);
    const int threads[] = {0, 2, 3, 7, 64, 1000};
    for (size_t t = 0; t < sizeof threads / sizeof threads[0]; t++) {
        batch_init(&b, threads[t], -1);
        TU_OK(btf__pool_run(JOBS, threads[t], job, &b, NULL, &err), &err);
        for (int j = 0; j < JOBS; j++)
            assert_int_equal(atomic_load(&b.runs[j]), 1);
        assert_memory_equal(b.results, ref.results, sizeof b.results);
        assert_int_equal(atomic_load(&b.bad_worker), 0);
    }
    /* No job: nothing runs, no error. */
    assert_int_equal(btf__pool_run(0, 4, job, &b, NULL, &err), BTF_OK);
}

static void workers_clamped(void **state)
{
    (void)state;
    assert_int_equal(btf__pool_workers(5, 3), 3);
    assert_int_equal(btf__pool_workers(1000, 1000), BTF_POOL_MAX_THREADS);
    assert_int_equal(btf__pool_workers(4, 0), 1);
    assert_int_equal(btf__pool_workers(0, 1000),
                     btf__cpu_count() < BTF_POOL_MAX_THREADS ? btf__cpu_count()
                                                            : BTF_POOL_MAX_THREADS);
}

static void first_failure_wins(void **state)
{
    (void)state;
    static batch b;
    for (int threads = 1; threads <= 4; threads++) {
        batch_init(&b, threads, 10);
        btf_error err = {0};
        assert_int_equal(btf__pool_run(JOBS, threads, job, &b, NULL, &err), BTF_E_DATA);
        assert_int_equal(err.code, BTF_E_DATA);
        assert_string_equal(err.msg, "job 10 failed on purpose");
        /* The batch stops: with one thread exactly at the failure, with
         * more after the jobs already running. */
        int started = atomic_load(&b.started);
        if (threads == 1)
            assert_int_equal(started, 11);
        assert_true(started < JOBS);
        /* err may be NULL. */
        batch_init(&b, threads, 10);
        assert_int_equal(btf__pool_run(JOBS, threads, job, &b, NULL, NULL), BTF_E_DATA);
    }
}

typedef struct progress_log {
    pthread_t caller;
    int calls, wrong_thread;
    double last;
    int backwards;
} progress_log;

static void on_progress(void *user, double f, const char *what)
{
    progress_log *p = user;
    assert_string_equal(what, "testing");
    if (!pthread_equal(pthread_self(), p->caller))
        p->wrong_thread = 1;
    if (f < p->last)
        p->backwards = 1;
    p->last = f;
    p->calls++;
}

static void progress_from_caller(void **state)
{
    (void)state;
    static batch b;
    for (int threads = 1; threads <= 4; threads++) {
        progress_log log = {.caller = pthread_self(), .last = 0.25};
        btf_pool_progress pp = {on_progress, &log, "testing", 0.25, 0.75, 100};
        batch_init(&b, threads, -1);
        btf_error err = {0};
        TU_OK(btf__pool_run(JOBS, threads, job, &b, &pp, &err), &err);
        assert_int_equal(log.wrong_thread, 0);
        assert_int_equal(log.backwards, 0);
        assert_true(log.last == 0.75);
        assert_true(log.calls >= 1 && log.calls <= JOBS / 100 + 1);
        if (threads == 1)
            assert_int_equal(log.calls, JOBS / 100);
    }
}

typedef struct relay_log {
    atomic_int runs[JOBS];
    atomic_int by_caller, fail_at;
    pthread_t caller;
    atomic_int slow; /* jobs on the helper sleep, so that the caller takes some */
} relay_log;

static btf_status relay_job(void *user, int j, int worker, btf_error *err)
{
    relay_log *l = user;
    assert_true(j >= 0 && j < JOBS);
    assert_true(worker == 0 || worker == 1);
    int on_caller = pthread_equal(pthread_self(), l->caller) != 0;
    assert_int_equal(worker == 0, on_caller);
    atomic_fetch_add(&l->by_caller, on_caller);
    if (!on_caller && atomic_load(&l->slow)) {
        struct timespec ts = {0, 200000};
        nanosleep(&ts, NULL);
    }
    atomic_fetch_add(&l->runs[j], 1);
    if (j == atomic_load(&l->fail_at))
        return btf__fail(err, BTF_E_IO, "job %d failed", j);
    return BTF_OK;
}

static void relay_runs_every_job_once(void **state)
{
    (void)state;
    static relay_log l;
    memset(&l, 0, sizeof l);
    atomic_store(&l.fail_at, -1);
    l.caller = pthread_self();
    btf_error e = {0};
    btf_relay *r = btf__relay_start(relay_job, &l, &e);
    assert_non_null(r);
    /* batches of 0..40 jobs, the caller busy meanwhile or not */
    int first = 0;
    for (int n = 0; first + n <= JOBS && n <= 40; first += n, n++) {
        btf__relay_post(r, first, n);
        volatile double x = 0;
        for (int i = 0; i < (n % 3) * 20000; i++)
            x += i;
        assert_int_equal(btf__relay_wait(r, &e), BTF_OK);
        for (int j = first; j < first + n; j++)
            assert_int_equal(atomic_load(&l.runs[j]), 1);
    }
    for (int j = first; j < JOBS; j++)
        assert_int_equal(atomic_load(&l.runs[j]), 0);
    /* a slow helper: the caller takes what it has not */
    atomic_store(&l.slow, 1);
    atomic_store(&l.by_caller, 0);
    memset(l.runs, 0, sizeof l.runs);
    btf__relay_post(r, 0, 200);
    assert_int_equal(btf__relay_wait(r, &e), BTF_OK);
    for (int j = 0; j < 200; j++)
        assert_int_equal(atomic_load(&l.runs[j]), 1);
    if (btf__cpu_count() > 1)
        print_message("caller ran %d of 200 jobs beside a slow helper\n",
                      atomic_load(&l.by_caller));
    assert_true(atomic_load(&l.by_caller) > 0);
    btf__relay_stop(r);
}

static void relay_first_failure(void **state)
{
    (void)state;
    static relay_log l;
    memset(&l, 0, sizeof l);
    l.caller = pthread_self();
    atomic_store(&l.fail_at, 57);
    btf_error e = {0};
    btf_relay *r = btf__relay_start(relay_job, &l, &e);
    assert_non_null(r);
    btf__relay_post(r, 0, 400);
    assert_int_equal(btf__relay_wait(r, &e), BTF_E_IO);
    assert_string_equal(e.msg, "job 57 failed");
    int ran = 0;
    for (int j = 0; j < 400; j++) {
        assert_true(atomic_load(&l.runs[j]) <= 1);
        ran += atomic_load(&l.runs[j]);
    }
    assert_true(ran < 400); /* the hand-out stopped */
    /* the relay serves the next batch as before */
    atomic_store(&l.fail_at, -1);
    memset(l.runs, 0, sizeof l.runs);
    btf_error e2 = {0};
    btf__relay_post(r, 500, 10);
    assert_int_equal(btf__relay_wait(r, &e2), BTF_OK);
    for (int j = 500; j < 510; j++)
        assert_int_equal(atomic_load(&l.runs[j]), 1);
    btf__relay_stop(r);
    btf__relay_stop(NULL);
}

typedef struct bg_log {
    atomic_int order[64]; /* the background jobs in the order they ran */
    atomic_int ran, fail_at;
    atomic_int wrong;     /* a job on another worker or thread than the helper's */
    pthread_t caller;
} bg_log;

/* Runs on the helper: what it sees is recorded, asserted by the caller. */
static btf_status bg_job(void *user, int j, int worker, btf_error *err)
{
    bg_log *l = user;
    if (worker != 1 || pthread_equal(pthread_self(), l->caller))
        atomic_store(&l->wrong, 1);
    int at = atomic_fetch_add(&l->ran, 1);
    if (at >= 64)
        return btf__fail(err, BTF_E_ARG, "background job %d ran more than once", j);
    atomic_store(&l->order[at], j);
    if (j == atomic_load(&l->fail_at))
        return btf__fail(err, BTF_E_IO, "background job %d failed", j);
    return BTF_OK;
}

/* The helper runs background jobs in order between the pipeline's
 * batches, which still run exactly once; a failure stops the background
 * and is kept. With one CPU the helper runs none (the caller's to do). */
static void relay_background_in_order(void **state)
{
    (void)state;
    for (int fail = -1; fail <= 20; fail += 21) {
        static relay_log l;
        static bg_log b;
        memset(&l, 0, sizeof l);
        memset(&b, 0, sizeof b);
        atomic_store(&l.fail_at, -1);
        atomic_store(&b.fail_at, fail);
        l.caller = b.caller = pthread_self();
        btf_error e = {0};
        btf_relay *r = btf__relay_start(relay_job, &l, &e);
        assert_non_null(r);
        btf_background bg = {.fn = bg_job, .user = &b, .count = 40};
        btf__relay_background(r, &bg);
        /* batches meanwhile, idle time between them: 30 batches, then more
         * (each of its jobs again) until the background is through, or 5 s
         * on a loaded machine */
        int want = fail < 0 ? 40 : 21, posts = 0;
        for (; posts < 30 || (btf__cpu_count() > 1 && atomic_load(&b.ran) < want &&
                              posts < 30 + 5000); posts++) {
            int k = posts % 30;
            btf__relay_post(r, 10 * k, 10);
            assert_int_equal(btf__relay_wait(r, &e), BTF_OK);
            struct timespec ts = {0, posts < 30 ? 300000 : 1000000};
            nanosleep(&ts, NULL);
        }
        btf__relay_stop(r);
        for (int j = 0; j < 300; j++) /* once per post */
            assert_int_equal(atomic_load(&l.runs[j]), posts / 30 + (j / 10 < posts % 30));
        int ran = atomic_load(&b.ran);
        assert_int_equal(atomic_load(&b.wrong), 0);
        for (int i = 0; i < ran; i++)
            assert_int_equal(atomic_load(&b.order[i]), i);
        if (btf__cpu_count() < 2) {
            assert_int_equal(ran, 0);
            continue;
        }
        if (fail < 0) {
            assert_int_equal(bg.status, BTF_OK);
            assert_int_equal(bg.done, ran);
            assert_int_equal(ran, 40);
        } else {
            assert_int_equal(bg.status, BTF_E_IO);
            assert_string_equal(bg.error.msg, "background job 20 failed");
            assert_int_equal(bg.done, 20);
            assert_int_equal(ran, 21); /* none after the failure */
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_job_once),
        cmocka_unit_test(workers_clamped),
        cmocka_unit_test(first_failure_wins),
        cmocka_unit_test(progress_from_caller),
        cmocka_unit_test(relay_runs_every_job_once),
        cmocka_unit_test(relay_first_failure),
        cmocka_unit_test(relay_background_in_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
