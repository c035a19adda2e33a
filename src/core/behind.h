/*
 * behind.h — writing behind (core/behind.c): a thread of the caller's that
 * runs jobs in the order they are put, while the caller goes on making the
 * next ones (btfcar synthesise's whole images, the EXR writer's slabs of
 * rows). Private to the library (and its command line).
 *
 * A bounded queue: put copies a job of spec.job_size bytes in and returns,
 * blocking first while `depth` jobs are held (the running one counted), so
 * memory stays bounded whatever the speed of either side; depth 1 is "put
 * waits until the previous job is done". Jobs run one at a time, in order.
 * The first failure is kept: the next put and the finish return its status
 * and message, and no job runs after it (spec.done still sees every job).
 */
#ifndef BTF_CORE_BEHIND_H
#define BTF_CORE_BEHIND_H

#include "btfcar.h"

#include <stddef.h>

/* Runs one job (on the thread, or in put without one); non-zero: a
 * btf_status with err filled. */
typedef btf_status (*btf_behind_fn)(void *user, void *job, btf_error *err);
/* Called once for every job put, after it ran or when it will not run
 * (a failure before it, an abort, a put that refused it): where a job
 * owns memory, this frees it. */
typedef void (*btf_behind_done_fn)(void *user, void *job);

typedef struct btf_behind_spec {
    btf_behind_fn run;
    btf_behind_done_fn done;  /* NULL: jobs own nothing */
    void *user;               /* passed to run and done */
    size_t job_size;          /* bytes of one job, copied by put (>= 1) */
    int depth;                /* jobs held at most, the running one included (>= 1) */
    /* When no thread can be started: 1, put runs each job itself (same
     * order, same failure rules, no overlap); 0, the start fails. */
    int run_here_without_thread;
} btf_behind_spec;

typedef struct btf_behind btf_behind;

/* NULL with err filled (BTF_E_ARG for a bad spec, else BTF_E_NOMEM: out of
 * memory, or no lock or thread to be had). */
btf_behind *btf__behind_start(const btf_behind_spec *spec, btf_error *err);
/* Hands a job over (job_size bytes at job, copied; the caller's copy is
 * done with, as what it owns now belongs to the job): waits while depth
 * jobs are held, then queues it; or returns the first failure so far (then
 * the job goes to done and never runs). */
btf_status btf__behind_put(btf_behind *b, void *job, btf_error *err);
/* Runs what is queued, stops the thread and frees b; returns the first
 * failure of all the jobs (err may be NULL). b NULL: BTF_OK. */
btf_status btf__behind_finish(btf_behind *b, btf_error *err);
/* Stops at once: the job running finishes, the queued ones do not run;
 * frees b. b NULL: nothing. */
void btf__behind_abort(btf_behind *b);

#endif
