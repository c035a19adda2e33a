/*
 * core.h — the plumbing every stage shares (src/core/): one-line errors,
 * allocation, atomic files and paths, the CPU count, the thread pool,
 * direction-name tolerance. Private to the library; not installed.
 */
#ifndef BTF_CORE_H
#define BTF_CORE_H

#include "btfcar.h"

#include <stddef.h>

#if defined(__GNUC__)
#define BTF_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define BTF_PRINTF(a, b)
#endif

/* Image sides beyond this are refused before any allocation: 2^16 keeps
 * width*height*3 floats far from size_t overflow and matches EXR practice. */
#define BTF_MAX_SIDE 65536
/* btf_image_alloc for the library's own images of 1 to 4 channels (the
 * structure pattern's base: RGB and a cell index, model/structure_map.c). */
btf_status btf__image_alloc_any(btf_image *img, int width, int height, int channels,
                                btf_error *err);
/* The decoding cap (btf_read_opts.max_pixels; 0: BTF_DEFAULT_MAX_PIXELS):
 * BTF_E_UNSUPPORTED naming the file, its size and the cap when width x
 * height exceeds it (core/image.c). */
int btf__check_pixels(const char *name, int width, int height, uint64_t max_pixels,
                      btf_error *err);
/* Prefixes err's message with "NAME: " (out-of-memory messages of work on a
 * file); returns err's code. */
int btf__error_name(btf_error *err, const char *name);

/* Fills err (if non-NULL) with a formatted one-line message; returns code. */
int btf__fail(btf_error *err, int code, const char *fmt, ...) BTF_PRINTF(3, 4);

/* malloc/calloc that report BTF_E_NOMEM through err; size overflow checked. */
void *btf__alloc(size_t count, size_t size, btf_error *err);
void *btf__calloc(size_t count, size_t size, btf_error *err);
/* Frees every pointer of a list (NULL ones too, as free() does), so that a
 * free function names the arrays it owns in one statement. The list is
 * evaluated whole before the first free, so BTF_FREE_ALL(s->a, s) is safe. */
void btf__free_list(void *const *ptrs, size_t n);
#define BTF_FREE_ALL(...)                                                                          \
    btf__free_list((void *const[]){__VA_ARGS__},                                                    \
                   sizeof((void *const[]){__VA_ARGS__}) / sizeof(void *))
/* The caller's options struct as this library's (docs/api.md, "Options
 * structs"): every public options struct begins with size_t struct_size,
 * which btf_X_defaults() sets to the struct's size. NULL gives *defaults; a
 * struct_size of 0 (a zeroed struct) is this header's layout; a smaller
 * size (a caller built against an older header, before fields were added
 * at the end) is copied as far as it goes and the rest reads as zero, which
 * every option takes as its default. A size below the member itself or
 * above this library's struct is refused (BTF_E_ARG, naming `what`): the
 * caller was built against a newer header. dst's struct_size is set to
 * dst_size. */
btf_status btf__opts_take(void *dst, size_t dst_size, const void *src, const void *defaults,
                          const char *what, btf_error *err);
/* Bytes this process can still allocate, as far as the system says: the
 * kernel's MemAvailable plus free swap (the physical memory without /proc),
 * at most a cgroup's remaining limit and the address-space limit
 * (RLIMIT_AS). UINT64_MAX when nothing is known. */
uint64_t btf__memory_available(void);

/* Atomic file writing: btf__tmp_create makes a new temporary file beside
 * `path` (same folder, so rename() is atomic), PATH.btfcar-tmp-IDENTITY-PID-N, with
 * O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC (a taken name, a planted symlink
 * too, is skipped for the next N), and records it for
 * btf_remove_temporaries; *fd is open for writing. btf__commit_file renames
 * it over path (the caller has written, fsync'd and closed it),
 * btf__abort_file removes it. */
int btf__tmp_create(const char *path, char *tmp, size_t n, int *fd, btf_error *err);
/* The IDENTITY of temporary names (PATH.btfcar-tmp-IDENTITY-PID-N): 16 hex
 * digits naming this host's boot and the calling process's PID namespace,
 * into out. */
#define BTF_TMP_IDENTITY_SIZE 17
void btf__tmp_identity(char out[BTF_TMP_IDENTITY_SIZE]);
int btf__commit_file(const char *tmp, const char *path, btf_error *err);
void btf__abort_file(const char *tmp);
/* btf_write_file_atomic (a whole buffer) is public: include/btfcar.h. */
/* Opens an input file for reading if it is a regular file, else refuses it
 * before a byte is read: open with O_NONBLOCK (a FIFO without a writer
 * would block the open itself), fstat, then O_NONBLOCK cleared. Returns the
 * descriptor (close-on-exec) and, when size is non-NULL, the file's size;
 * or -1 with errno set (EINVAL: not a regular file) and err (may be NULL)
 * holding BTF_E_IO and "PATH: cannot open: REASON" or "PATH: not a regular
 * file". Every input opened by path goes through here. */
int btf__open_regular(const char *path, uint64_t *size, btf_error *err);
/* Reads a whole regular file (at most max_bytes) into a malloc'd buffer. */
int btf__read_file(const char *path, size_t max_bytes, unsigned char **data,
                   size_t *n, btf_error *err);

/* rm -r: removes a folder and everything below it (links are not
 * followed); errors are ignored. For temporary output after a failure. */
void btf__remove_tree(const char *path);
/* Joins a folder and a name into out (size n); BTF_E_ARG when too long. */
int btf__path_join(char *out, size_t n, const char *dir, const char *name, btf_error *err);

/* Number of online CPUs (at least 1). */
int btf__cpu_count(void);
/* Monotonic wall-clock seconds, for the times stages report. */
double btf__now(void);

/* The thread pool (core/pool.c): btf__pool_run runs jobs 0..jobs-1, each
 * exactly once, over btf__pool_workers(threads, jobs) threads (threads 0:
 * every CPU), the calling thread among them, and returns when all are done.
 * job(user, j, worker, err) does job j; worker (0 = the calling thread,
 * < btf__pool_workers) lets the caller keep scratch per thread; a job's
 * output must depend on j alone, so that results do not depend on the
 * thread count. The first job to fail stops the batch (no new job starts)
 * and its status and message are returned. progress (NULL: none) is called
 * from the calling thread only, after every `every` jobs and once at the
 * end, with from + (to - from) x the fraction of jobs done. */
#define BTF_POOL_MAX_THREADS 64
typedef btf_status (*btf_pool_job_fn)(void *user, int job, int worker, btf_error *err);
typedef struct btf_pool_progress {
    btf_progress_fn fn;   /* NULL: no reports */
    void *user;
    const char *what;     /* the step's name, passed to fn */
    double from, to;      /* the fractions reported at the start and the end */
    int every;            /* report after this many jobs (< 1: after each) */
} btf_pool_progress;
int btf__pool_workers(int threads, int jobs);
btf_status btf__pool_run(int jobs, int threads, btf_pool_job_fn job, void *user,
                         const btf_pool_progress *progress, btf_error *err);

/* A relay (core/pool.c): a helper thread that works through a batch of
 * jobs while the calling thread goes on with its own work (a pipeline:
 * synthesis colours one block of rows while it computes the next).
 * btf__relay_post(r, first, count) hands jobs first .. first + count - 1
 * over and returns at once; btf__relay_wait runs the jobs the helper has
 * not taken yet on the calling thread, so a helper that gets no CPU holds
 * nothing up, then returns when all are done, with the first failure's
 * status and message (which stops the hand-out). Every post is followed by
 * one wait before the next. job gets worker 0 on the calling thread, 1 on
 * the helper; as with the pool, a job's output must depend on its index
 * alone. With one CPU, or when no thread can be started, the wait runs
 * them all. btf__relay_start returns NULL only when out of memory. */
typedef struct btf_relay btf_relay;
btf_relay *btf__relay_start(btf_pool_job_fn job, void *user, btf_error *err);
void btf__relay_post(btf_relay *r, int first, int count);
btf_status btf__relay_wait(btf_relay *r, btf_error *err);
void btf__relay_stop(btf_relay *r);
/* Background work for a relay's helper: jobs 0 .. count - 1 of fn (worker
 * 1), in this order, one at a time, whenever the helper has no batch of the
 * pipeline to run; it looks for a batch after each job, so a job should be
 * short (tens of microseconds: a batch posted meanwhile waits that long, or
 * the caller's wait takes it over). `done` counts the jobs run; the first
 * failure stops the background (status, error). The caller owns bg and,
 * once btf__relay_stop has returned, runs what is left itself: the helper
 * uses the CPU the pipeline leaves idle (synthesis.c colour-matches the
 * previous image so, beside the next one's fields). With one CPU the helper
 * runs nothing. */
typedef struct btf_background {
    btf_pool_job_fn fn;
    void *user;
    int count;
    int done;
    btf_status status;
    btf_error error;
} btf_background;
void btf__relay_background(btf_relay *r, btf_background *bg);

/* Directions named in whole degrees (file names) match a known set within
 * this many degrees (core/directions.c, dataset/dataset.c). */
#define BTF_DIR_NAME_TOLERANCE 0.75

/* The mean linear RGB of an image (a grey image's value three times). */
void btf__image_mean_rgb(const btf_image *img, float *rgb);

/* A deterministic random stream (splitmix64) for seeded choices. */
typedef struct btf_rng {
    uint64_t state;
} btf_rng;
void btf__rng_seed(btf_rng *r, uint64_t seed);
uint64_t btf__rng_next(btf_rng *r);
double btf__rng_uniform(btf_rng *r); /* [0, 1), 53 bits */

/* sRGB transfer function (IEC 61966-2-1), per value. */
float btf__srgb_to_linear(float v);
float btf__linear_to_srgb(float v);

/* A copy of src into dst (dst's old content is not freed). */
btf_status btf__dirset_copy(btf_dirset *dst, const btf_dirset *src, btf_error *err);

/* The UBO2014 151-direction dome (per-ring azimuth offsets). */
btf_status btf__dirset_ubo151(btf_dirset *set, btf_error *err);

#endif
