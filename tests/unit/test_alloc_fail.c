/*
 * test_alloc_fail.c — allocation-failure testing in the manner of SQLite's
 * fault simulator: the n-th allocation made by the library fails, for
 * n = 1, 2, ... over the analysis and synthesis entry points, until a run
 * completes without reaching the n-th allocation. Every run that met the
 * failure must return an error status with a message (or, if the library
 * recovered from it, succeed with exactly the output of an undisturbed run),
 * never crash, and must leave no allocation behind.
 *
 * How: this program is linked with -Wl,--wrap=malloc,--wrap=calloc,... (the
 * Makefile's rule for it), so every call of those functions from the static
 * library's objects (and from this file) goes to the __wrap_* functions
 * below. They count calls, fail the armed one, and keep the live blocks in a
 * table, so "nothing leaked" is "the table holds what it held before the
 * call". Blocks that libc or the shared libraries (OpenEXR, OpenCV, zlib)
 * allocate for themselves do not pass through here and are not failed; nor
 * is C++ operator new (src/io/cv_bridge.cpp's vectors). Under `make asan`
 * the wrappers call the sanitizer's malloc and LeakSanitizer checks the
 * same at exit.
 *
 * Two modes per n: one-shot (only the n-th allocation fails, as most real
 * out-of-memory conditions are transient) and persistent (the n-th and
 * every later one fail, which exercises the allocations made on the error
 * paths themselves). Runtime: a few seconds; the long entry points (the
 * whole analysis) try every STEP-th n after the first FIRST ones.
 *
 * BTF_ALLOC_FAIL_VERBOSE=1 prints every run (entry point, n, status).
 */
#define _GNU_SOURCE /* dladdr */
#include "testutil.h"

#include <dlfcn.h>
#include <execinfo.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------- the wrappers */

void *__real_malloc(size_t size);
void *__real_calloc(size_t count, size_t size);
void *__real_realloc(void *p, size_t size);
void *__real_aligned_alloc(size_t align, size_t size);
int __real_posix_memalign(void **out, size_t align, size_t size);
void __real_free(void *p);

void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t count, size_t size);
void *__wrap_realloc(void *p, size_t size);
void *__wrap_aligned_alloc(size_t align, size_t size);
int __wrap_posix_memalign(void **out, size_t align, size_t size);
char *__wrap_strdup(const char *s);
char *__wrap_strndup(const char *s, size_t n);
void __wrap_free(void *p);

#define TRACE_FRAMES 8

typedef struct live_block {
    void *p;              /* NULL: empty slot */
    size_t size;
    unsigned long seq;    /* its number among the armed run's allocations (0: unarmed) */
    unsigned long run;    /* the armed run that made it (0: none) */
    void *caller;         /* who called malloc & co. */
    int frames;           /* backtrace, when tracing */
    void *frame[TRACE_FRAMES];
} live_block;

#define TABLE_BITS 17
#define TABLE_SIZE (1u << TABLE_BITS)

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static live_block table[TABLE_SIZE];
static size_t live;               /* blocks in the table */
static int armed;                 /* counting allocations of a run */
static int persistent;            /* fail every allocation from fail_at on */
static int tracing;               /* record backtraces (to name a leak) */
static unsigned long fail_at;     /* 0: never fail */
static unsigned long calls;       /* allocation calls since arming */
static unsigned long failures;    /* of them, failed */
static unsigned long run_id;      /* armed runs so far */

static size_t slot_of(const void *p)
{
    uintptr_t h = (uintptr_t)p;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return (size_t)h & (TABLE_SIZE - 1);
}

/* With lock held. */
static void table_add(void *p, size_t size, unsigned long seq, void *caller, void **frame,
                      int frames)
{
    if (live + 1 >= TABLE_SIZE / 2) {
        static const char msg[] = "test_alloc_fail: allocation table full\n";
        fwrite(msg, 1, sizeof msg - 1, stderr);
        abort();
    }
    size_t i = slot_of(p);
    while (table[i].p)
        i = (i + 1) & (TABLE_SIZE - 1);
    table[i] = (live_block){.p = p, .size = size, .seq = seq, .run = seq ? run_id : 0,
                            .caller = caller, .frames = frames};
    if (frames)
        memcpy(table[i].frame, frame, (size_t)frames * sizeof *frame);
    live++;
}

/* With lock held. Removes p if the table has it (linear probing, deletion
 * by moving the later entries of the run back); 1 if it was there. */
static int table_remove(const void *p)
{
    size_t i = slot_of(p);
    while (table[i].p && table[i].p != p)
        i = (i + 1) & (TABLE_SIZE - 1);
    if (!table[i].p)
        return 0;
    table[i].p = NULL;
    live--;
    size_t j = i;
    for (;;) {
        j = (j + 1) & (TABLE_SIZE - 1);
        if (!table[j].p)
            break;
        size_t k = slot_of(table[j].p);
        /* Move j back to i unless its home k lies cyclically in (i, j]. */
        int stays = (i <= j) ? (i < k && k <= j) : (i < k || k <= j);
        if (!stays) {
            table[i] = table[j];
            table[j].p = NULL;
            i = j;
        }
    }
    return 1;
}

/* Counts one allocation call; 1 when it is to fail. *seq gets its number. */
static int should_fail(unsigned long *seq)
{
    *seq = 0;
    if (!armed)
        return 0;
    *seq = ++calls;
    if (fail_at && (calls == fail_at || (persistent && calls > fail_at))) {
        failures++;
        return 1;
    }
    return 0;
}

static int trace(void **frame)
{
    return tracing ? backtrace(frame, TRACE_FRAMES) : 0;
}

/* The frames of the first failed call of the run, to name it. */
static void *fail_frame[TRACE_FRAMES];
static int fail_frames;

static void note_failure(void)
{
    void *frame[TRACE_FRAMES];
    int n = backtrace(frame, TRACE_FRAMES);
    pthread_mutex_lock(&lock);
    if (failures == 1) {
        memcpy(fail_frame, frame, sizeof frame);
        fail_frames = n;
    }
    pthread_mutex_unlock(&lock);
}

static void *track(void *p, size_t size, unsigned long seq, void *caller, void **frame,
                   int frames)
{
    if (p) {
        pthread_mutex_lock(&lock);
        table_add(p, size, seq, caller, frame, frames);
        pthread_mutex_unlock(&lock);
    }
    return p;
}

#define BEGIN_ALLOC(failed_value)                                                  \
    void *frame_[TRACE_FRAMES];                                                    \
    int frames_ = trace(frame_);                                                   \
    unsigned long seq_;                                                            \
    pthread_mutex_lock(&lock);                                                     \
    int fail_ = should_fail(&seq_);                                                \
    pthread_mutex_unlock(&lock);                                                   \
    if (fail_) {                                                                   \
        note_failure();                                                            \
        return failed_value;                                                       \
    }

void *__wrap_malloc(size_t size)
{
    BEGIN_ALLOC(NULL);
    return track(__real_malloc(size), size, seq_, __builtin_return_address(0), frame_,
                 frames_);
}

void *__wrap_calloc(size_t count, size_t size)
{
    BEGIN_ALLOC(NULL);
    return track(__real_calloc(count, size), count * size, seq_, __builtin_return_address(0),
                 frame_, frames_);
}

void *__wrap_aligned_alloc(size_t align, size_t size)
{
    BEGIN_ALLOC(NULL);
    return track(__real_aligned_alloc(align, size), size, seq_, __builtin_return_address(0),
                 frame_, frames_);
}

int __wrap_posix_memalign(void **out, size_t align, size_t size)
{
    BEGIN_ALLOC(12 /* ENOMEM */);
    int rc = __real_posix_memalign(out, align, size);
    if (rc == 0)
        track(*out, size, seq_, __builtin_return_address(0), frame_, frames_);
    return rc;
}

void *__wrap_realloc(void *p, size_t size)
{
    if (!p)
        return __wrap_malloc(size);
    if (size == 0) {
        __wrap_free(p);
        return NULL;
    }
    BEGIN_ALLOC(NULL);
    pthread_mutex_lock(&lock);
    int known = table_remove(p);
    pthread_mutex_unlock(&lock);
    void *q = __real_realloc(p, size);
    if (!q) {
        if (known) /* p stays valid and owned */
            track(p, size, seq_, __builtin_return_address(0), frame_, frames_);
        return NULL;
    }
    /* A block libc made for itself stays untracked when it moves. */
    return known ? track(q, size, seq_, __builtin_return_address(0), frame_, frames_) : q;
}

char *__wrap_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = __wrap_malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

char *__wrap_strndup(const char *s, size_t n)
{
    size_t len = strnlen(s, n);
    char *d = __wrap_malloc(len + 1);
    if (d) {
        memcpy(d, s, len);
        d[len] = 0;
    }
    return d;
}

void __wrap_free(void *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&lock);
    table_remove(p); /* one libc allocated for us (fopen's buffer...) is not there */
    pthread_mutex_unlock(&lock);
    __real_free(p);
}

static size_t live_blocks(void)
{
    pthread_mutex_lock(&lock);
    size_t n = live;
    pthread_mutex_unlock(&lock);
    return n;
}

static void arm(unsigned long n, int persist)
{
    pthread_mutex_lock(&lock);
    calls = 0;
    failures = 0;
    run_id++;
    fail_at = n;
    persistent = persist;
    armed = 1;
    pthread_mutex_unlock(&lock);
}

static void disarm(void)
{
    pthread_mutex_lock(&lock);
    armed = 0;
    fail_at = 0;
    pthread_mutex_unlock(&lock);
}

/* Names the code at addr: function and line by addr2line for this program's
 * own frames (static functions have no dynamic symbol), the shared object and
 * nearest symbol for the others. */
static void print_frame(void *addr)
{
    Dl_info info;
    if (!dladdr(addr, &info)) {
        print_message("      %p\n", addr);
        return;
    }
    static char exe[4096];
    static void *exe_base;
    if (!exe[0]) {
        ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
        exe[n > 0 ? n : 0] = 0;
        Dl_info self;
        if (dladdr((void *)&print_frame, &self))
            exe_base = self.dli_fbase;
    }
    /* The return address points after the call: name the call itself. */
    unsigned long off = (unsigned long)((char *)addr - (char *)info.dli_fbase) - 1;
    if (exe[0] && info.dli_fbase == exe_base) {
        char cmd[4400];
        snprintf(cmd, sizeof cmd, "addr2line -f -i -s -p -e '%s' 0x%lx", exe, off);
        FILE *f = popen(cmd, "r");
        char line[512];
        int any = 0;
        while (f && fgets(line, sizeof line, f)) {
            print_message("      %s", line);
            any = 1;
        }
        if (f)
            pclose(f);
        if (any)
            return;
    }
    print_message("      %s(%s+0x%lx)\n", info.dli_fname ? info.dli_fname : "?",
                  info.dli_sname ? info.dli_sname : "", off);
}

/* Lists the blocks allocated by the latest armed run that are still live. */
static void report_leaks(void)
{
    live_block shown[10];
    int n = 0;
    pthread_mutex_lock(&lock);
    for (size_t i = 0; i < TABLE_SIZE && n < 10; i++)
        if (table[i].p && table[i].run == run_id)
            shown[n++] = table[i];
    pthread_mutex_unlock(&lock);
    for (int k = 0; k < n; k++) {
        const live_block *b = &shown[k];
        print_message("    leaked: allocation %lu of the run, %zu bytes, from:\n", b->seq,
                      b->size);
        if (b->frames > 1)
            for (int f = 1; f < b->frames; f++)
                print_frame(b->frame[f]);
        else
            print_frame(b->caller);
    }
}

/* ------------------------------------------------------- the driver */

/* One entry point under test. run() makes the call with the allocator armed
 * and returns its status; on success it leaves the result in the context,
 * which same() compares with the undisturbed run's and done() frees. */
typedef struct entry {
    const char *name;
    int (*run)(void *ctx, btf_error *err);
    int (*same)(void *ctx); /* 1: the result equals the reference */
    void (*done)(void *ctx);
    void *ctx;
    unsigned long first, step; /* every n up to first, then every step-th */
} entry;

static int verbose;

/* Runs e with the n-th allocation failing (persistently or once). Returns 1
 * when the run did not reach the n-th allocation (the loop is over). */
static int run_once(const entry *e, unsigned long n, int persist, int *nomem, int *other,
                    int *benign, int *bad)
{
    size_t before = live_blocks();
    btf_error err = {0};
    arm(n, persist);
    int rc = e->run(e->ctx, &err);
    pthread_mutex_lock(&lock);
    unsigned long made = calls, failed = failures;
    pthread_mutex_unlock(&lock);
    disarm();
    int ok = 1;
    if (verbose)
        print_message("%s: n = %lu%s: %lu calls, %lu failed, rc %d %s\n", e->name, n,
                      persist ? " (persistent)" : "", made, failed, rc, rc ? err.msg : "");
    if (rc == 0) {
        if (!e->same(e->ctx)) {
            print_error("%s: allocation %lu failed%s, the call succeeded with another "
                        "result than an undisturbed run\n",
                        e->name, n, persist ? " (and every later one)" : "");
            if (*bad < 3) {
                print_message("    the failed allocation:\n");
                for (int f = 2; f < fail_frames; f++)
                    print_frame(fail_frame[f]);
            }
            ok = 0;
        }
        e->done(e->ctx);
        if (failed)
            (*benign)++;
    } else {
        if (rc < BTF_E_NUMERIC || rc > BTF_E_ARG) {
            print_error("%s: allocation %lu failed: status %d is no btf_status\n", e->name, n,
                        rc);
            ok = 0;
        }
        if (!err.msg[0] || err.code != rc) {
            print_error("%s: allocation %lu failed: status %d but err = {%d, \"%s\"}\n",
                        e->name, n, rc, err.code, err.msg);
            ok = 0;
        }
        if (!failed) {
            print_error("%s: failed (%d: %s) though no allocation failed\n", e->name, rc,
                        err.msg);
            ok = 0;
        }
        if (rc == BTF_E_NOMEM)
            (*nomem)++;
        else
            (*other)++;
    }
    size_t after = live_blocks();
    if (after != before) {
        print_error("%s: allocation %lu failed%s (status %d: %s): %zu block(s) leaked\n",
                    e->name, n, persist ? " (and every later one)" : "", rc, err.msg,
                    after - before);
        ok = 0;
    }
    if (!ok)
        (*bad)++;
    return failed == 0;
}

/* A leak is named by the frames recorded at allocation time, which cost
 * too much to record on every run: a leaking n is run again, traced. */
static void rerun_traced(const entry *e, unsigned long n, int persist)
{
    pthread_mutex_lock(&lock);
    tracing = 1;
    pthread_mutex_unlock(&lock);
    size_t before = live_blocks();
    btf_error err = {0};
    arm(n, persist);
    int rc = e->run(e->ctx, &err);
    disarm();
    if (rc == 0)
        e->done(e->ctx);
    if (live_blocks() != before) {
        print_message("  %s, allocation %lu failing%s, traced:\n", e->name, n,
                      persist ? " persistently" : "");
        report_leaks();
    }
    pthread_mutex_lock(&lock);
    tracing = 0;
    pthread_mutex_unlock(&lock);
}

static void fault_loop(const entry *e)
{
    /* The undisturbed run: it must succeed, and it gives the call count. */
    size_t before = live_blocks();
    btf_error err = {0};
    arm(0, 0);
    int rc = e->run(e->ctx, &err);
    unsigned long total = calls;
    disarm();
    if (rc != 0)
        fail_msg("%s: undisturbed run failed: %s", e->name, err.msg);
    assert_true(e->same(e->ctx));
    e->done(e->ctx);
    assert_int_equal(live_blocks(), before);
    assert_true(total > 0);

    int tried = 0, nomem = 0, other = 0, benign = 0, bad = 0;
    for (int persist = 0; persist <= 1; persist++) {
        for (unsigned long n = 1;;) {
            tried++;
            int bad_before = bad;
            int end = run_once(e, n, persist, &nomem, &other, &benign, &bad);
            if (bad != bad_before && bad <= 3)
                rerun_traced(e, n, persist);
            if (end || bad > 20)
                break;
            if (n > 4 * total + 100)
                fail_msg("%s: the calls never end (n = %lu)", e->name, n);
            /* Sampled beyond first; total + 1 (no failure) is always run. */
            unsigned long next = n < e->first || n >= total ? n + 1 : n + e->step;
            n = next > total && n < total ? total + 1 : next;
        }
    }
    print_message("[ alloc    ] %s: %lu allocations; %d runs, %d BTF_E_NOMEM, %d other "
                  "errors, %d recovered%s\n",
                  e->name, total, tried, nomem, other, benign,
                  e->step > 1 ? " (sampled)" : "");
    if (bad)
        fail_msg("%s: %d run(s) with an allocation failure went wrong (above)", e->name, bad);
}

/* ------------------------------------------------------- the fixtures */

/* A small texture model (3 levels), encoded, and the reference synthesis. */
static btf_image texture;
static btf_model texmodel;
static unsigned char *texmodel_bytes;
static size_t texmodel_size;

/* A tiny manifest dataset: one view (theta_v = 0), six lights, 16 x 16 EXR. */
static char manifest[4096];
static unsigned char *analysed_bytes;
static size_t analysed_size;

#define DS_SIZE 16
#define DS_LIGHTS 6

static void make_dataset(const char *dir)
{
    btf_error e = {0};
    btf_procedural mat;
    TU_OK(btf_procedural_make("leather", DS_SIZE, 3, &mat, &e), &e);
    snprintf(manifest, sizeof manifest, "%s/list.tsv", dir);
    FILE *f = fopen(manifest, "w");
    assert_non_null(f);
    fprintf(f, "path\ttheta_l\tphi_l\ttheta_v\tphi_v\n");
    for (int l = 0; l < DS_LIGHTS; l++) {
        btf_dir light = {l < 3 ? 30 : 60, 120.0 * (l % 3) + (l < 3 ? 0 : 60)};
        btf_image img;
        TU_OK(btf_procedural_render(&mat, (btf_dir){0, 0}, light, &img, &e), &e);
        TU_OK(btf_image_write_exr_opts(tu_fmt("%s/l%d.exr", dir, l), &img, NULL, NULL, &e), &e);
        fprintf(f, "l%d.exr\t%g\t%g\t0\t0\n", l, light.theta, light.phi);
        btf_image_free(&img);
    }
    assert_int_equal(fclose(f), 0);
    btf_procedural_free(&mat);
}

static btf_fit_opts texture_fit_opts(void)
{
    btf_fit_opts o = {.levels = 3};
    o.car.max_neighbours = 6;
    return o;
}

static btf_analyse_opts analyse_opts(void)
{
    btf_analyse_opts o = {.range_size = 8};
    o.segment.subspaces = 2;
    o.segment.features.threads = 1; /* one thread: the same allocation order each run */
    o.segment.kmeans.seed = 1;
    o.segment.kmeans.restarts = 2;
    o.photostereo.threads = 1;
    o.fit.levels = 2;
    o.fit.car.max_neighbours = 4;
    return o;
}

static int setup(void **state)
{
    verbose = getenv("BTF_ALLOC_FAIL_VERBOSE") && atoi(getenv("BTF_ALLOC_FAIL_VERBOSE"));
    /* backtrace() loads libgcc on its first call (allocating): do it now. */
    void *frame[2];
    backtrace(frame, 2);
    tu_setup_dir(state);
    btf_error e = {0};
    tu_material_image("fabric", 32, 7, (btf_dir){0, 0}, (btf_dir){45, 30}, &texture);
    btf_fit_opts fo = texture_fit_opts();
    TU_OK(btf_texture_fit(&texture, &fo, &texmodel, &e), &e);
    TU_OK(btf_model_encode(&texmodel, &texmodel_bytes, &texmodel_size, &e), &e);

    char dir[4096];
    snprintf(dir, sizeof dir, "%s/ds", tu_dir);
    mkdir(dir, 0777);
    make_dataset(dir);
    btf_dataset *ds;
    TU_OK(btf_dataset_open(manifest, NULL, &ds, &e), &e);
    btf_analyse_opts ao = analyse_opts();
    btf_model m;
    TU_OK(btf_analyse(ds, &ao, &m, &e), &e);
    TU_OK(btf_model_encode(&m, &analysed_bytes, &analysed_size, &e), &e);
    btf_model_free(&m);
    btf_dataset_close(ds);
    return 0;
}

static int teardown(void **state)
{
    btf_image_free(&texture);
    btf_model_free(&texmodel);
    free(texmodel_bytes);
    free(analysed_bytes);
    return tu_teardown_dir(state);
}

/* A model result compared by its encoding (the encoder itself unarmed). */
typedef struct model_ctx {
    btf_model m;
    const unsigned char *want;
    size_t want_size;
    btf_dataset *ds;
} model_ctx;

static int model_same(void *p)
{
    model_ctx *c = p;
    unsigned char *b;
    size_t n;
    btf_error e = {0};
    if (btf_model_encode(&c->m, &b, &n, &e) != 0)
        return 0;
    int same = n == c->want_size && memcmp(b, c->want, n) == 0;
    free(b);
    return same;
}

static void model_done(void *p)
{
    btf_model_free(&((model_ctx *)p)->m);
}

/* ------------------------------------------------------- model file */

static int run_decode(void *p, btf_error *err)
{
    model_ctx *c = p;
    return btf_model_decode(c->want, c->want_size, "texture.btfcar", &c->m, err);
}

static void model_decode(void **state)
{
    (void)state;
    model_ctx c = {.want = texmodel_bytes, .want_size = texmodel_size};
    entry e = {"btf_model_decode", run_decode, model_same, model_done, &c, ~0ul, 1};
    fault_loop(&e);
}

/* A model of format 1.7 with periodic cells (the fuzz corpus' seed):
 * its CELL section's reader under every failing allocation. */
static void model_decode_cells(void **state)
{
    (void)state;
    size_t n = 0;
    unsigned char *bytes = tu_slurp("tests/fuzz/corpus/fuzz_model/cells-1.7.btfcar", &n);
    assert_non_null(bytes);
    assert_int_equal(bytes[13], 7);
    model_ctx c = {.want = bytes, .want_size = n};
    entry e = {"btf_model_decode (cells)", run_decode, model_same, model_done, &c, ~0ul, 1};
    fault_loop(&e);
    free(bytes);
}

typedef struct encode_ctx {
    unsigned char *data;
    size_t size;
} encode_ctx;

static int run_encode(void *p, btf_error *err)
{
    encode_ctx *c = p;
    return btf_model_encode(&texmodel, &c->data, &c->size, err);
}

static int encode_same(void *p)
{
    encode_ctx *c = p;
    return c->size == texmodel_size && memcmp(c->data, texmodel_bytes, c->size) == 0;
}

static void encode_done(void *p)
{
    free(((encode_ctx *)p)->data);
}

static void model_encode(void **state)
{
    (void)state;
    encode_ctx c = {0};
    entry e = {"btf_model_encode", run_encode, encode_same, encode_done, &c, ~0ul, 1};
    fault_loop(&e);
}

/* Writing a model file: also no temporary file may be left beside it. */
static int run_write(void *p, btf_error *err)
{
    (void)p;
    return btf_model_write(tu_fmt("%s/w/m.btfcar", tu_dir), &texmodel, err);
}

static int write_same(void *p)
{
    (void)p;
    model_ctx c = {.want = texmodel_bytes, .want_size = texmodel_size};
    btf_error e = {0};
    if (btf_model_read(tu_fmt("%s/w/m.btfcar", tu_dir), &c.m, &e) != 0)
        return 0;
    int same = model_same(&c);
    btf_model_free(&c.m);
    return same;
}

static void write_done(void *p)
{
    (void)p;
    remove(tu_fmt("%s/w/m.btfcar", tu_dir));
}

static void model_write(void **state)
{
    (void)state;
    mkdir(tu_fmt("%s/w", tu_dir), 0777);
    entry e = {"btf_model_write", run_write, write_same, write_done, NULL, ~0ul, 1};
    fault_loop(&e);
    assert_int_equal(tu_count_files(tu_fmt("%s/w", tu_dir)), 0);
}

/* ------------------------------------------------------- analysis */

static int run_texture_fit(void *p, btf_error *err)
{
    model_ctx *c = p;
    btf_fit_opts fo = texture_fit_opts();
    return btf_texture_fit(&texture, &fo, &c->m, err);
}

static void texture_fit(void **state)
{
    (void)state;
    model_ctx c = {.want = texmodel_bytes, .want_size = texmodel_size};
    entry e = {"btf_texture_fit", run_texture_fit, model_same, model_done, &c, ~0ul, 1};
    fault_loop(&e);
}

typedef struct dataset_ctx {
    btf_dataset *ds;
} dataset_ctx;

static int run_dataset_open(void *p, btf_error *err)
{
    return btf_dataset_open(manifest, NULL, &((dataset_ctx *)p)->ds, err);
}

static int dataset_same(void *p)
{
    const btf_dataset_info *in = btf_dataset_get_info(((dataset_ctx *)p)->ds);
    return in->n_views == 1 && in->n_lights == DS_LIGHTS && in->width == DS_SIZE &&
           in->height == DS_SIZE;
}

static void dataset_done(void *p)
{
    btf_dataset_close(((dataset_ctx *)p)->ds);
}

static void dataset_open(void **state)
{
    (void)state;
    dataset_ctx c = {0};
    entry e = {"btf_dataset_open", run_dataset_open, dataset_same, dataset_done, &c, ~0ul, 1};
    fault_loop(&e);
}

static int run_analyse(void *p, btf_error *err)
{
    model_ctx *c = p;
    btf_analyse_opts o = analyse_opts();
    return btf_analyse(c->ds, &o, &c->m, err);
}

static void analyse(void **state)
{
    (void)state;
    btf_error e = {0};
    model_ctx c = {.want = analysed_bytes, .want_size = analysed_size};
    TU_OK(btf_dataset_open(manifest, NULL, &c.ds, &e), &e);
    entry en = {"btf_analyse", run_analyse, model_same, model_done, &c, 200, 3};
    fault_loop(&en);
    btf_dataset_close(c.ds);
}

/* ------------------------------------------------------- synthesis */

#define SYN_W 40
#define SYN_H 24
#define SYN_SEED 11

/* The one call of the synthesis API. */
static int synthesise_cpu(const btf_model *m, int subspace, int width, int height,
                          uint64_t seed, btf_rows_fn fn, void *user, btf_error *err)
{
    btf_synth_opts o = {.width = width, .height = height, .seed = seed};
    return btf_synthesise(m, subspace, &o, fn, user, err);
}

typedef struct synth_ctx {
    float *got, *want; /* SYN_W * SYN_H * 3 */
} synth_ctx;

static int to_buffer(void *user, int y, int nrows, const float *rows, btf_error *err)
{
    (void)err;
    memcpy(((synth_ctx *)user)->got + (size_t)y * SYN_W * 3, rows,
           (size_t)nrows * SYN_W * 3 * sizeof(float));
    return 0;
}

static int run_synth(void *p, btf_error *err)
{
    memset(((synth_ctx *)p)->got, 0, (size_t)SYN_W * SYN_H * 3 * sizeof(float));
    return synthesise_cpu(&texmodel, 0, SYN_W, SYN_H, SYN_SEED, to_buffer, p, err);
}

static int synth_same(void *p)
{
    synth_ctx *c = p;
    return memcmp(c->got, c->want, (size_t)SYN_W * SYN_H * 3 * sizeof(float)) == 0;
}

static void synth_done(void *p)
{
    (void)p;
}

static void synthesise(void **state)
{
    (void)state;
    size_t n = (size_t)SYN_W * SYN_H * 3;
    synth_ctx c = {calloc(n, sizeof(float)), calloc(n, sizeof(float))};
    assert_non_null(c.got);
    assert_non_null(c.want);
    btf_error e = {0};
    synth_ctx ref = {c.want, NULL};
    TU_OK(synthesise_cpu(&texmodel, 0, SYN_W, SYN_H, SYN_SEED, to_buffer, &ref, &e), &e);
    entry en = {"btf_synthesise", run_synth, synth_same, synth_done, &c, ~0ul, 1};
    fault_loop(&en);
    free(c.got);
    free(c.want);
}

/* ------------------------------------------------------- structure maps */

/* The quilted structure layer of the cells-1.7 model (the range map at the
 * analysed resolution, its albedo and colour), placed on a surface twice
 * its size: the quilting, the joins' relaxation (model/structure_seams.c)
 * and the normals under every failing allocation. */
typedef struct maps_ctx {
    btf_model m;
    btf_image h, n, a;
    btf_image want_h, want_a;
} maps_ctx;

static int run_maps(void *p, btf_error *err)
{
    maps_ctx *c = p;
    return btf_structure_maps(&c->m, 2 * c->m.range_width, 2 * c->m.range_height, 3, &c->h,
                              &c->n, &c->a, err);
}

static int maps_same(void *p)
{
    maps_ctx *c = p;
    size_t n = (size_t)c->h.width * c->h.height;
    return memcmp(c->h.data, c->want_h.data, n * sizeof(float)) == 0 &&
           memcmp(c->a.data, c->want_a.data, n * c->a.channels * sizeof(float)) == 0;
}

static void maps_done(void *p)
{
    maps_ctx *c = p;
    btf_image_free(&c->h);
    btf_image_free(&c->n);
    btf_image_free(&c->a);
}

static void structure_maps(void **state)
{
    (void)state;
    size_t size = 0;
    unsigned char *bytes = tu_slurp("tests/fuzz/corpus/fuzz_model/cells-1.7.btfcar", &size);
    assert_non_null(bytes);
    maps_ctx c;
    memset(&c, 0, sizeof c);
    btf_error e = {0};
    TU_OK(btf_model_decode(bytes, size, "cells-1.7.btfcar", &c.m, &e), &e);
    free(bytes);
    assert_true(c.m.range && c.m.range_texel == 1.0f && c.m.albedo);
    btf_image nm;
    TU_OK(btf_structure_maps(&c.m, 2 * c.m.range_width, 2 * c.m.range_height, 3, &c.want_h,
                             &nm, &c.want_a, &e), &e);
    btf_image_free(&nm);
    entry en = {"btf_structure_maps", run_maps, maps_same, maps_done, &c, ~0ul, 1};
    fault_loop(&en);
    btf_image_free(&c.want_h);
    btf_image_free(&c.want_a);
    btf_model_free(&c.m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(model_decode), cmocka_unit_test(model_decode_cells),
        cmocka_unit_test(model_encode),
        cmocka_unit_test(model_write),  cmocka_unit_test(texture_fit),
        cmocka_unit_test(dataset_open), cmocka_unit_test(analyse),
        cmocka_unit_test(synthesise),   cmocka_unit_test(structure_maps),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
