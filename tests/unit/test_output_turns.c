/*
 * test_output_turns.c — two writers of one existing output folder take turns
 * (a lock on the folder while a set moves in): before, `btfcar synthesise`
 * runs into the same folder could interleave their files and commit a mixed
 * set, both exiting 0. The library's rename() calls are wrapped (Makefile:
 * --wrap=rename) so that two committing writers follow a schedule that
 * interleaves them (may_go): without turns the set is mixed for certain, not
 * by a timing race; with them one writer waits for the other's whole set (the
 * schedule's waits then time out and let the lone writer go on).
 */
#include "testutil.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

int __real_rename(const char *from, const char *to);

#define FILES 12

static pthread_mutex_t turn_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t turn_cond = PTHREAD_COND_INITIALIZER;
static _Thread_local int writer = -1; /* 0 or 1 in the test's threads */
static int done[2];                   /* renames each writer has made */
static int forcing;                   /* the schedule on */

/* The forced schedule: writer 1 moves half its files, then writer 0 all of
 * its own (one failed rename of the whole folder first, then FILES), then
 * writer 1 the rest. Interleaved so, the first half of the files ends up
 * 0's, the second half 1's: a mixed set. */
static int may_go(int w)
{
    if (w == 1)
        return done[1] < 1 + FILES / 2 || done[0] >= 1 + FILES;
    return done[1] >= 1 + FILES / 2;
}

/* A writer's rename waits (at most 50 ms) for its place in the schedule:
 * a writer left alone by the other (which waits for its turn at the
 * folder) goes on after the wait. */
int __wrap_rename(const char *from, const char *to)
{
    if (writer < 0 || !forcing)
        return __real_rename(from, to);
    pthread_mutex_lock(&turn_lock);
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += 50 * 1000000L;
    if (until.tv_nsec >= 1000000000L)
        until.tv_sec++, until.tv_nsec -= 1000000000L;
    while (!may_go(writer) &&
           pthread_cond_timedwait(&turn_cond, &turn_lock, &until) != ETIMEDOUT)
        ;
    int rc = __real_rename(from, to);
    done[writer]++;
    pthread_cond_broadcast(&turn_cond);
    pthread_mutex_unlock(&turn_lock);
    return rc;
}

typedef struct {
    const char *dir;
    int id;
    pthread_barrier_t *ready;
    btf_status rc;
} job;

/* A set of FILES files, each holding the writer's letter, committed into
 * the existing folder once both writers have their sets ready. */
static void *write_set(void *user)
{
    job *j = user;
    writer = j->id;
    btf_error e = {0};
    btf_output_dir *od;
    j->rc = btf_output_dir_begin(j->dir, &od, &e);
    if (j->rc) {
        pthread_barrier_wait(j->ready);
        return NULL;
    }
    char letter = (char)('A' + j->id), name[4096];
    for (int i = 0; i < FILES; i++) {
        snprintf(name, sizeof name, "%s/f%02d", btf_output_dir_path(od), i);
        tu_write_file(name, &letter, 1);
    }
    pthread_barrier_wait(j->ready);
    j->rc = btf_output_dir_commit(od, &e);
    if (j->rc)
        print_message("commit: %s\n", e.msg);
    return NULL;
}

/* The letters of the folder's files: 1 when they are all the same. */
static int one_writer(const char *dir)
{
    char first = 0;
    for (int i = 0; i < FILES; i++) {
        FILE *f = fopen(tu_fmt("%s/f%02d", dir, i), "rb");
        assert_non_null(f);
        int c = fgetc(f);
        fclose(f);
        if (!first)
            first = (char)c;
        if (c != first)
            return 0;
    }
    return 1;
}

static void writers_of_one_folder_take_turns(void **state)
{
    (void)state;
    char *root = tu_tmpdir();
    const char *dir = tu_fmt("%s/out", root);
    char path[4096];
    snprintf(path, sizeof path, "%s", dir);
    assert_int_equal(mkdir(path, 0777), 0);
    tu_write_file(tu_fmt("%s/keep", path), "k", 1); /* existing, not empty */
    for (int round = 0; round < 3; round++) {
        pthread_barrier_t ready;
        pthread_barrier_init(&ready, NULL, 2);
        job jobs[2] = {{path, 0, &ready, 0}, {path, 1, &ready, 0}};
        pthread_t t[2];
        done[0] = done[1] = 0;
        forcing = 1;
        for (int i = 0; i < 2; i++)
            assert_int_equal(pthread_create(&t[i], NULL, write_set, &jobs[i]), 0);
        for (int i = 0; i < 2; i++)
            pthread_join(t[i], NULL);
        forcing = 0;
        pthread_barrier_destroy(&ready);
        assert_int_equal(jobs[0].rc, 0);
        assert_int_equal(jobs[1].rc, 0);
        assert_true(one_writer(path));
        assert_int_equal(access(tu_fmt("%s/keep", path), F_OK), 0);
    }
    tu_rmtree(root);
    free(root);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(writers_of_one_folder_take_turns),
    };
    return cmocka_run_group_tests_name("output turns", tests, NULL, NULL);
}
