/*
 * each_behind.c — btf_synthesise_each with the writes behind it
 * (each_behind.h): the batch hands each finished image to a write-behind
 * thread of depth 1 (core/behind.h), so that writing image i (EXR
 * encoding, a preview, the disk) overlaps the synthesis of image i + 1
 * instead of adding to it. Depth 1: an image may be up to 256 MiB
 * (btf_synth_holds_whole), and one waiting keeps the writer busy.
 */
#include "synth/each_behind.h"
#include "core/behind.h"
#include "core/core.h"

#include <string.h>

/* What the thread holds: image i, whole. */
typedef struct image_job {
    int i;
    btf_image img;
} image_job;

typedef struct hand_over {
    btf_each_behind *b;
    btf_behind *behind;
    int n;
} hand_over;

static btf_status write_job(void *user, void *job, btf_error *err)
{
    btf_each_behind *b = user;
    image_job *j = job;
    int got = b->write(b->user, j->i, &j->img, err);
    /* btf_image_fn: a btf_status, or any other non-zero value for I/O */
    btf_status rc = got > 0 ? BTF_E_IO : (btf_status)got;
    if (rc && err && !err->msg[0])
        btf__fail(err, rc, "writing image %d failed", j->i);
    return rc;
}

static void free_job(void *user, void *job)
{
    (void)user;
    btf_image_free(&((image_job *)job)->img);
}

/* btf_synthesise_each's consumer: image i goes to the thread. */
static int put_image(void *user, int i, btf_image *img, btf_error *err)
{
    hand_over *h = user;
    double t0 = btf__now();
    image_job job = {i, *img};
    memset(img, 0, sizeof *img); /* the job's now */
    btf_status rc = btf__behind_put(h->behind, &job, err);
    h->b->hand_s += btf__now() - t0;
    h->b->write_failed = rc != BTF_OK;
    if (rc == BTF_OK && h->b->progress)
        h->b->progress(h->b->progress_user, (double)(i + 1) / h->n, "synthesising");
    return rc;
}

btf_status btf__synthesise_each_behind(const btf_model *m, const int *subspaces, int n,
                                       const btf_synth_opts *opts, btf_each_behind *b,
                                       btf_error *err)
{
    if (!b || !b->write)
        return btf__fail(err, BTF_E_ARG, "synthesis written behind: no writer");
    b->hand_s = b->wait_s = 0;
    b->write_failed = 0;
    btf_behind_spec spec = {.run = write_job, .done = free_job, .user = b,
                            .job_size = sizeof(image_job), .depth = 1,
                            .run_here_without_thread = 1};
    hand_over h = {b, btf__behind_start(&spec, err), n};
    if (!h.behind)
        return err ? (btf_status)err->code : BTF_E_NOMEM;
    btf_status rc = btf_synthesise_each(m, subspaces, n, opts, put_image, &h, err);
    double t0 = btf__now();
    btf_error werr = {0};
    btf_status wrc = btf__behind_finish(h.behind, &werr); /* the last image's write */
    b->wait_s = btf__now() - t0;
    if (rc == BTF_OK && wrc) {
        rc = wrc, b->write_failed = 1;
        if (err)
            *err = werr;
    }
    return rc;
}
