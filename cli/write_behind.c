/*
 * write_behind.c — a thread that writes whole images while the command goes
 * on computing the next one (btfcar synthesise with colour matching: image
 * i is written while image i + 1 is synthesised and image i colour-matched
 * on the synthesis' idle CPU, btf_synthesise_each). One image waits at
 * most: cli_behind_put blocks until the thread has written the previous
 * one, so the thread holds one image at a time. The first write failure is
 * kept and returned by the next put and by the finish; nothing is written
 * after it.
 */
#include "cli.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

struct cli_behind {
    cli_behind_fn write;
    void *user;
    pthread_t tid;
    int started;
    pthread_mutex_t lock;
    pthread_cond_t cond;     /* an image queued (for the thread), written (for the caller) */
    btf_image img;           /* the queued image, when have */
    int key, have, stop;
    int rc;                  /* the first failure, and its message */
    btf_error err;
};

static void *behind_main(void *arg)
{
    cli_behind *b = arg;
    pthread_mutex_lock(&b->lock);
    for (;;) {
        while (!b->have && !b->stop)
            pthread_cond_wait(&b->cond, &b->lock);
        if (!b->have)
            break;
        btf_image img = b->img;
        int key = b->key;
        memset(&b->img, 0, sizeof b->img); /* the thread's now */
        pthread_mutex_unlock(&b->lock);
        btf_error e = {0};
        int rc = b->rc ? 0 : b->write(b->user, key, &img, &e); /* none after a failure */
        btf_image_free(&img);
        pthread_mutex_lock(&b->lock);
        if (rc && !b->rc)
            b->rc = rc, b->err = e;
        b->have = 0;
        pthread_cond_broadcast(&b->cond);
    }
    pthread_mutex_unlock(&b->lock);
    return NULL;
}

cli_behind *cli_behind_start(cli_behind_fn write, void *user, btf_error *err)
{
    cli_behind *b = calloc(1, sizeof *b);
    if (!b) {
        cli_set_error(err, BTF_E_NOMEM, "out of memory");
        return NULL;
    }
    b->write = write, b->user = user;
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->cond, NULL);
    b->started = pthread_create(&b->tid, NULL, behind_main, b) == 0;
    return b;
}

int cli_behind_put(cli_behind *b, int key, btf_image *img, btf_error *err)
{
    if (!b->started) { /* no thread: written here */
        int rc = b->rc ? b->rc : b->write(b->user, key, img, err);
        btf_image_free(img);
        if (rc && !b->rc)
            b->rc = rc, b->err = *err;
        return rc;
    }
    pthread_mutex_lock(&b->lock);
    while (b->have && !b->rc)
        pthread_cond_wait(&b->cond, &b->lock);
    int rc = b->rc;
    if (rc) {
        *err = b->err;
        btf_image_free(img);
    } else {
        b->img = *img, b->key = key, b->have = 1;
        memset(img, 0, sizeof *img);
        pthread_cond_broadcast(&b->cond);
    }
    pthread_mutex_unlock(&b->lock);
    return rc;
}

int cli_behind_finish(cli_behind *b, double *wait_s, btf_error *err)
{
    if (!b)
        return 0;
    double t0 = cli_now();
    if (b->started) {
        pthread_mutex_lock(&b->lock);
        b->stop = 1;
        pthread_cond_broadcast(&b->cond);
        pthread_mutex_unlock(&b->lock);
        pthread_join(b->tid, NULL);
    }
    if (wait_s)
        *wait_s = cli_now() - t0;
    int rc = b->rc;
    if (rc && err)
        *err = b->err;
    btf_image_free(&b->img); /* queued when the thread could not start: none */
    pthread_cond_destroy(&b->cond);
    pthread_mutex_destroy(&b->lock);
    free(b);
    return rc;
}
