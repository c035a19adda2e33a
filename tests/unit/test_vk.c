/*
 * test_vk.c — the internal Vulkan compute layer (gpu/vk.h) on lavapipe, the
 * Mesa CPU driver: device listing and choice, create/destroy cycles, buffer
 * round trips (mapped and staged), fills and copies, the bit-exact parity of
 * the shader noise (gpu/noise_check.comp) with the C btf_noise4, limits
 * refused with clear errors, job timeouts, `btfcar info --devices`, and the
 * command's environment variables (BTF_VK_DEVICE, BTF_VK_VALIDATION), which
 * the command reads and the library does not.
 *
 * Every context runs with the validation layer, and every test ends by
 * asserting that the layer reported no error or warning — except the one
 * test that provokes an error on purpose to prove the counting works.
 */
#include "testutil.h"

#include "btf_noise.h"
#include "vk.h"
#include "noise_check_spv.h" /* gpu/noise_check.comp, built by the Makefile */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define LAVAPIPE_ICD "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json"

/* 1 when this program chose lavapipe itself (no driver variable was set). */
static int forced_lavapipe;

/* --------------------------------------------------------------- helpers */

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A context with validation on (plus the given options). */
static btf_vk *open_vk(const btf_vk_opts *extra)
{
    btf_vk_opts o = {0};
    if (extra)
        o = *extra;
    o.validation = 1;
    o.allow_cpu = 1;
    btf_error err = {0};
    btf_vk *vk = NULL;
    TU_OK(btf__vk_create(&o, &vk, &err), &err);
    assert_true(btf__vk_validating(vk));
    return vk;
}

/* Destroys vk; the validation layer must have said nothing, teardown
 * included (objects never destroyed are reported there). */
static void close_vk(btf_vk *vk)
{
    unsigned before = btf__vk_validation_errors(vk);
    char first[1024];
    unsigned n = btf__vk_destroy_checked(vk, first, sizeof first);
    if (n != 0)
        print_error("validation: %u message(s) (%u before teardown), the first: %s\n", n,
                    before, first);
    assert_int_equal(n, 0);
}

/* A whole (small) text file, malloc'd and NUL-terminated. */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *t = calloc(1, 1 << 16);
    assert_non_null(t);
    size_t n = fread(t, 1, (1 << 16) - 1, f);
    t[n] = '\0';
    fclose(f);
    return t;
}

static int contains(const char *text, const char *part)
{
    if (!strstr(text, part))
        print_error("expected '%s' in: %s\n", part, text);
    return strstr(text, part) != NULL;
}

/* Saves and restores one environment variable around a test step. */
typedef struct saved_env {
    const char *name;
    char *value; /* NULL: was unset */
} saved_env;

static saved_env env_set(const char *name, const char *value)
{
    saved_env s = {name, getenv(name) ? strdup(getenv(name)) : NULL};
    if (value)
        setenv(name, value, 1);
    else
        unsetenv(name);
    return s;
}

static void env_restore(saved_env s)
{
    if (s.value)
        setenv(s.name, s.value, 1);
    else
        unsetenv(s.name);
    free(s.value);
}

/* ------------------------------------------------------------- devices */

static void list_devices(void **state)
{
    (void)state;
    btf_vk_device_info *list;
    int n;
    btf_error err = {0};
    TU_OK(btf__vk_list_devices(&list, &n, &err), &err);
    assert_true(n >= 1);
    int lavapipe = -1;
    for (int i = 0; i < n; i++) {
        assert_int_equal(list[i].index, i);
        assert_true(list[i].name[0] != '\0');
        if (list[i].is_cpu && strstr(list[i].name, "llvmpipe"))
            lavapipe = i;
    }
    if (forced_lavapipe) {
        assert_true(lavapipe >= 0);
        const btf_vk_device_info *d = &list[lavapipe];
        assert_int_equal(d->type, BTF_VK_TYPE_CPU);
        assert_string_equal(btf__vk_type_name(d->type), "CPU");
        assert_true(d->usable);
        assert_true(d->api_version >= ((1u << 22) | (1u << 12))); /* 1.1 */
        assert_true(d->max_storage_buffer_range >= (1u << 27));    /* 128 MiB */
        assert_true(d->max_workgroup_count[0] >= 65535);
        assert_true(d->max_workgroup_invocations >= 128);
        assert_true(d->max_push_constants_bytes >= 128);
        assert_true(d->subgroup_size >= 1);
        assert_true(d->device_local_bytes > 0);
        char v[32];
        btf__vk_version_text(d->api_version, v, sizeof v);
        assert_true(v[0] == '1' && v[1] == '.');
    }
    free(list);
}

static void create_destroy_repeatedly(void **state)
{
    (void)state;
    for (int i = 0; i < 4; i++) {
        btf_vk *vk = open_vk(NULL);
        const btf_vk_device_info *in = btf__vk_info(vk);
        if (forced_lavapipe) {
            assert_true(in->is_cpu);
            assert_true(in->mapped_buffers);
        }
        close_vk(vk);
    }
    btf__vk_destroy(NULL);
}

static void device_choice_errors(void **state)
{
    (void)state;
    btf_error err = {0};
    btf_vk *vk = NULL;
    btf_vk_opts o = {.use_device = 1, .device = 99, .validation = 1};
    assert_int_equal(btf__vk_create(&o, &vk, &err), BTF_E_ARG);
    assert_null(vk);
    assert_true(contains(err.msg, "Vulkan device 99 does not exist"));

    /* The environment is the command's business: the library ignores it. */
    saved_env s = env_set("BTF_VK_DEVICE", "99");
    btf_vk_opts auto_opts = {.validation = 1, .allow_cpu = 1};
    TU_OK(btf__vk_create(&auto_opts, &vk, &err), &err);
    close_vk(vk);
    env_restore(s);

    if (forced_lavapipe) {
        /* Only a CPU device: refused unless allowed or named. */
        btf_vk_opts strict = {.validation = 1};
        assert_int_equal(btf__vk_create(&strict, &vk, &err), BTF_E_UNSUPPORTED);
        assert_true(contains(err.msg, "only a CPU Vulkan device"));
        btf_vk_opts named = {.use_device = 1, .device = 0, .validation = 1};
        TU_OK(btf__vk_create(&named, &vk, &err), &err);
        assert_int_equal(btf__vk_info(vk)->index, 0);
        close_vk(vk);
    }
}

static void validation_switches(void **state)
{
    (void)state;
    btf_error err = {0};
    btf_vk *vk = NULL;
    btf_vk_opts o = {.allow_cpu = 1};
    saved_env s = env_set("BTF_VK_VALIDATION", "1"); /* the command's, not the library's */
    TU_OK(btf__vk_create(&o, &vk, &err), &err);
    assert_false(btf__vk_validating(vk));
    btf__vk_destroy(vk);
    env_restore(s);

    /* No validation layer where the loader looks: a clear refusal. */
    s = env_set("VK_LAYER_PATH", "/nonexistent-btfcar-layers");
    saved_env s2 = env_set("VK_ADD_LAYER_PATH", NULL);
    o.validation = 1;
    assert_int_equal(btf__vk_create(&o, &vk, &err), BTF_E_UNSUPPORTED);
    assert_null(vk);
    assert_true(contains(err.msg, "VK_LAYER_KHRONOS_validation is not installed"));
    env_restore(s2);
    env_restore(s);
}

static void no_driver(void **state)
{
    (void)state;
    saved_env a = env_set("VK_DRIVER_FILES", "/nonexistent-btfcar/icd.json");
    saved_env b = env_set("VK_ICD_FILENAMES", "/nonexistent-btfcar/icd.json");
    btf_error err = {0};
    btf_vk_device_info *list = NULL;
    int n = -1;
    int rc = btf__vk_list_devices(&list, &n, &err);
    assert_int_equal(rc, BTF_E_UNSUPPORTED);
    assert_null(list);
    assert_int_equal(n, 0);
    assert_true(contains(err.msg, "no Vulkan device found"));
    btf_vk *vk = NULL;
    btf_vk_opts o = {.allow_cpu = 1};
    assert_int_equal(btf__vk_create(&o, &vk, &err), BTF_E_UNSUPPORTED);
    assert_null(vk);
    assert_true(contains(err.msg, "install mesa-vulkan-drivers"));
    env_restore(b);
    env_restore(a);
}

/* ------------------------------------------------------------- buffers */

static void fill_pattern(unsigned char *p, size_t n, unsigned salt)
{
    uint32_t x = 2463534242u ^ salt;
    for (size_t i = 0; i < n; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        p[i] = (unsigned char)x;
    }
}

static void round_trips(int force_staging)
{
    btf_vk_opts o = {.force_staging = force_staging};
    btf_vk *vk = open_vk(&o);
    assert_int_equal(btf__vk_info(vk)->mapped_buffers, !force_staging);
    static const uint64_t sizes[] = {1, 3, 4, 4093, 65536 + 12, 1 << 20, 64u << 20};
    btf_error err = {0};
    unsigned char *in = malloc(64u << 20), *out = malloc(64u << 20);
    assert_non_null(in);
    assert_non_null(out);
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        uint64_t n = sizes[k];
        btf_vk_buffer *b;
        TU_OK(btf__vk_buffer_create(vk, n, &b, &err), &err);
        assert_int_equal(btf__vk_buffer_size(b), n);
        assert_true((btf__vk_buffer_mapped(b) != NULL) == !force_staging);
        fill_pattern(in, n, (unsigned)k);
        TU_OK(btf__vk_buffer_upload(vk, b, 0, in, n, &err), &err);
        memset(out, 0xAB, n);
        TU_OK(btf__vk_buffer_download(vk, b, 0, out, n, &err), &err);
        assert_memory_equal(in, out, n);
        if (n > 40) { /* a sub-range at odd offsets */
            uint64_t off = n / 3 + 1, len = n / 2 - 3;
            fill_pattern(in + off, len, 99u + (unsigned)k);
            TU_OK(btf__vk_buffer_upload(vk, b, off, in + off, len, &err), &err);
            TU_OK(btf__vk_buffer_download(vk, b, 7, out, n - 7, &err), &err);
            assert_memory_equal(in + 7, out, n - 7);
        }
        /* Ranges beyond the end are refused; a zero-byte copy is fine. */
        assert_int_equal(btf__vk_buffer_upload(vk, b, n, in, 1, &err), BTF_E_ARG);
        assert_true(contains(err.msg, "outside the Vulkan buffer"));
        assert_int_equal(btf__vk_buffer_download(vk, b, 1, out, n, &err), BTF_E_ARG);
        assert_int_equal(btf__vk_buffer_download(vk, b, UINT64_MAX, out, 2, &err), BTF_E_ARG);
        TU_OK(btf__vk_buffer_upload(vk, b, n, in, 0, &err), &err);
        btf__vk_buffer_destroy(b);
    }
    free(in);
    free(out);
    close_vk(vk);
}

static void buffer_round_trip_mapped(void **state)
{
    (void)state;
    round_trips(0);
}

static void buffer_round_trip_staged(void **state)
{
    (void)state;
    round_trips(1);
}

static void buffer_limits(void **state)
{
    (void)state;
    btf_vk *vk = open_vk(NULL);
    const btf_vk_device_info *in = btf__vk_info(vk);
    btf_error err = {0};
    btf_vk_buffer *b = NULL;
    assert_int_equal(btf__vk_buffer_create(vk, 0, &b, &err), BTF_E_ARG);
    assert_null(b);
    assert_int_equal(btf__vk_buffer_create(vk, in->max_storage_buffer_range + 1, &b, &err),
                     BTF_E_ARG);
    assert_true(contains(err.msg, "maxStorageBufferRange"));
    /* The largest one is fine (not touched, so cheap). */
    TU_OK(btf__vk_buffer_create(vk, in->max_storage_buffer_range, &b, &err), &err);
    btf__vk_buffer_destroy(b);
    btf__vk_buffer_destroy(NULL);
    close_vk(vk);
}

static void fill_and_copy(void **state)
{
    (void)state;
    for (int staged = 0; staged < 2; staged++) {
        btf_vk_opts o = {.force_staging = staged};
        btf_vk *vk = open_vk(&o);
        btf_error err = {0};
        btf_vk_buffer *a, *b;
        TU_OK(btf__vk_buffer_create(vk, 4096, &a, &err), &err);
        TU_OK(btf__vk_buffer_create(vk, 4096, &b, &err), &err);
        btf_vk_job *job;
        TU_OK(btf__vk_job_begin(vk, &job, &err), &err);
        TU_OK(btf__vk_job_fill(job, a, 0, 4096, 0x11223344u, &err), &err);
        TU_OK(btf__vk_job_fill(job, b, 0, 4096, 0, &err), &err);
        TU_OK(btf__vk_job_fill(job, a, 1024, 1024, 0xDEADBEEFu, &err), &err);
        TU_OK(btf__vk_job_copy(job, a, 1000, b, 3, 100, &err), &err);
        TU_OK(btf__vk_job_copy(job, a, 0, a, 2048, 1024, &err), &err);
        /* Refused: unaligned fill, overlap, out of range; the job stays fine. */
        assert_int_equal(btf__vk_job_fill(job, a, 2, 4, 0, &err), BTF_E_ARG);
        assert_true(contains(err.msg, "multiples of 4"));
        assert_int_equal(btf__vk_job_copy(job, a, 0, a, 100, 200, &err), BTF_E_ARG);
        assert_true(contains(err.msg, "overlap"));
        assert_int_equal(btf__vk_job_copy(job, a, 4000, b, 0, 200, &err), BTF_E_ARG);
        TU_OK(btf__vk_job_submit_wait(job, &err), &err);
        uint32_t wa[1024];
        unsigned char wb[4096];
        TU_OK(btf__vk_buffer_download(vk, a, 0, wa, sizeof wa, &err), &err);
        TU_OK(btf__vk_buffer_download(vk, b, 0, wb, sizeof wb, &err), &err);
        for (int i = 0; i < 1024; i++) {
            uint32_t want = (i >= 256 && i < 512) ? 0xDEADBEEFu : 0x11223344u;
            assert_int_equal(wa[i], want);
        }
        for (int i = 0; i < 4096; i++) {
            unsigned char want = 0;
            if (i >= 3 && i < 103) {
                uint32_t w = 0x11223344u;
                int src = 1000 + i - 3; /* bytes 1000..1023 of the 0x11223344 words, then beef */
                if (src >= 1024)
                    w = 0xDEADBEEFu;
                want = (unsigned char)(w >> (8 * (src & 3)));
            }
            assert_int_equal(wb[i], want);
        }
        /* An aborted job runs nothing. */
        TU_OK(btf__vk_job_begin(vk, &job, &err), &err);
        TU_OK(btf__vk_job_fill(job, a, 0, 4096, 0, &err), &err);
        btf__vk_job_abort(job);
        btf__vk_job_abort(NULL);
        TU_OK(btf__vk_buffer_download(vk, a, 0, wa, 16, &err), &err);
        assert_int_equal(wa[0], 0x11223344u);
        btf__vk_buffer_destroy(a);
        btf__vk_buffer_destroy(b);
        close_vk(vk);
    }
}

/* ------------------------------------------------------ noise parity */

typedef struct noise_params {
    uint32_t seed_lo, seed_hi, stream, row0, block0, nblocks, count;
} noise_params;

typedef struct noise_gpu {
    btf_vk *vk;
    btf_vk_pipeline *pipe[2]; /* workgroup size 64 (default) and 32 */
    btf_vk_buffer *buf[3];    /* z, raw, z1: vec4 / uvec4 each */
    uint32_t capacity;        /* invocations the buffers hold */
} noise_gpu;

static void noise_gpu_open(noise_gpu *g, int force_staging, uint32_t capacity)
{
    btf_vk_opts o = {.force_staging = force_staging};
    btf_error err = {0};
    g->vk = open_vk(&o);
    g->capacity = capacity;
    TU_OK(btf__vk_pipeline_create(g->vk, noise_check_spv, sizeof noise_check_spv, 3,
                                  sizeof(noise_params), NULL, 0, &g->pipe[0], &err),
          &err);
    const uint32_t local32 = 32;
    TU_OK(btf__vk_pipeline_create(g->vk, noise_check_spv, sizeof noise_check_spv, 3,
                                  sizeof(noise_params), &local32, 1, &g->pipe[1], &err),
          &err);
    for (int i = 0; i < 3; i++)
        TU_OK(btf__vk_buffer_create(g->vk, (uint64_t)capacity * 16, &g->buf[i], &err), &err);
}

static void noise_gpu_close(noise_gpu *g)
{
    for (int i = 0; i < 3; i++)
        btf__vk_buffer_destroy(g->buf[i]);
    btf__vk_pipeline_destroy(g->pipe[0]);
    btf__vk_pipeline_destroy(g->pipe[1]);
    close_vk(g->vk);
}

/* Runs the shader for p (buffers first filled with a sentinel) with
 * workgroup size 64 or 32, and downloads the three arrays (capacity
 * entries of 4 words each). */
static void noise_gpu_run(noise_gpu *g, const noise_params *p, int small_groups,
                          uint32_t *out[3])
{
    btf_error err = {0};
    btf_vk_job *job;
    uint32_t local = small_groups ? 32 : 64;
    TU_OK(btf__vk_job_begin(g->vk, &job, &err), &err);
    for (int i = 0; i < 3; i++)
        TU_OK(btf__vk_job_fill(job, g->buf[i], 0, (uint64_t)g->capacity * 16, 0x7FC0DEADu, &err),
              &err);
    TU_OK(btf__vk_job_dispatch(job, g->pipe[small_groups], g->buf, 3, p, sizeof *p,
                               (p->count + local - 1) / local, 1, 1, &err),
          &err);
    TU_OK(btf__vk_job_submit_wait(job, &err), &err);
    for (int i = 0; i < 3; i++)
        TU_OK(btf__vk_buffer_download(g->vk, g->buf[i], 0, out[i], (uint64_t)g->capacity * 16,
                                      &err),
              &err);
}

/* The C side of one invocation, compared word for word; returns the number
 * of differing words. */
static unsigned check_invocation(const noise_params *p, uint32_t i, uint32_t *out[3])
{
    uint32_t row = p->row0 + i / p->nblocks, block = p->block0 + i % p->nblocks;
    btf_vec4 z = btf_noise4(p->seed_lo, p->seed_hi, p->stream, row, block);
    btf_uvec4 raw = btf_philox(BTF_UVEC4(block, row, p->stream, BTF_NOISE_TAG),
                               BTF_UVEC2(p->seed_lo, p->seed_hi));
    uint32_t want[3][4] = {
        {btf_float_bits(z.x), btf_float_bits(z.y), btf_float_bits(z.z), btf_float_bits(z.w)},
        {raw.x, raw.y, raw.z, raw.w},
        {0, 0, 0, 0}};
    for (uint32_t c = 0; c < 4; c++)
        want[2][c] = btf_float_bits(btf_noise1(p->seed_lo, p->seed_hi, p->stream, row,
                                               4u * block + c));
    unsigned bad = 0;
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 4; c++)
            bad += out[a][4 * (size_t)i + c] != want[a][c];
    return bad;
}

static void noise_parity_run(int force_staging)
{
    enum { CAP = 16384 };
    noise_gpu g;
    noise_gpu_open(&g, force_staging, CAP);
    uint32_t *out[3];
    for (int i = 0; i < 3; i++) {
        out[i] = malloc((size_t)CAP * 16);
        assert_non_null(out[i]);
    }
    /* (seed, stream, first row, first block): zero and all-ones words,
     * rows about the burn-in origin 2^28 and wrapping past 2^32, streams of
     * real (subspace, band, level) triples, and mixed bits. */
    uint64_t s = 0x5EEDBA5Eull;
    const int n_cfg = force_staging ? 4 : 24;
    unsigned long long checked = 0, bad = 0;
    for (int k = 0; k < n_cfg; k++) {
        noise_params p = {0};
        uint64_t r1 = (s += 0x9E3779B97F4A7C15ull) * 0xBF58476D1CE4E5B9ull;
        uint64_t r2 = (r1 ^ (r1 >> 29)) * 0x94D049BB133111EBull;
        p.seed_lo = k == 0 ? 0 : k == 1 ? 0xFFFFFFFFu : (uint32_t)r1;
        p.seed_hi = k == 0 ? 0 : k == 1 ? 0xFFFFFFFFu : (uint32_t)(r1 >> 32);
        p.stream = k == 1 ? 0xFFFFFFFFu
                          : btf_noise_stream((uint32_t)k * 37u, (uint32_t)k % 3u, (uint32_t)k % 7u);
        p.row0 = k % 4 == 0   ? 0
                 : k % 4 == 1 ? (1u << 28) - 64 /* the burn-in origin */
                 : k % 4 == 2 ? 0xFFFFFFFFu - 40
                              : (uint32_t)r2;
        p.block0 = k % 3 == 0 ? 0 : (uint32_t)(r2 >> 40);
        p.nblocks = k % 2 ? 97 : 256;
        p.count = CAP - (uint32_t)(k % 5) * 13; /* partial last workgroups too */
        noise_gpu_run(&g, &p, k % 2, out);
        for (uint32_t i = 0; i < p.count; i++) {
            unsigned b = check_invocation(&p, i, out);
            if (b && bad < 5)
                print_error("config %d: invocation %u differs in %u words\n", k, i, b);
            bad += b != 0;
        }
        for (uint32_t i = p.count * 4; i < CAP * 4u; i++) /* untouched past count */
            for (int a = 0; a < 3; a++)
                bad += out[a][i] != 0x7FC0DEADu;
        checked += p.count;
    }
    print_message("noise parity (%s): %llu blocks, %llu mismatches\n",
                  force_staging ? "staged" : "mapped", checked, bad);
    assert_int_equal(bad, 0);
    for (int i = 0; i < 3; i++)
        free(out[i]);
    noise_gpu_close(&g);
}

static void noise_parity(void **state)
{
    (void)state;
    noise_parity_run(0);
}

static void noise_parity_staged(void **state)
{
    (void)state;
    noise_parity_run(1);
}

/* ------------------------------------------------------ limits, errors */

static void dispatch_limits(void **state)
{
    (void)state;
    noise_gpu g;
    noise_gpu_open(&g, 0, 64);
    const btf_vk_device_info *in = btf__vk_info(g.vk);
    btf_error err = {0};
    btf_vk_job *job;
    noise_params p = {.nblocks = 1, .count = 0}; /* every invocation returns at once */
    TU_OK(btf__vk_job_begin(g.vk, &job, &err), &err);
    const uint32_t *mx = in->max_workgroup_count;
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, sizeof p, mx[0] + 1, 1,
                                          1, &err),
                     BTF_E_ARG);
    assert_true(contains(err.msg, "maxComputeWorkGroupCount"));
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, sizeof p, 1, mx[1] + 1,
                                          1, &err),
                     BTF_E_ARG);
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, sizeof p, 1, 1,
                                          mx[2] + 1, &err),
                     BTF_E_ARG);
    /* Wrong buffer count or push size: refused before Vulkan sees them. */
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 2, &p, sizeof p, 1, 1, 1, &err),
                     BTF_E_ARG);
    assert_true(contains(err.msg, "2 buffers given, the pipeline binds 3"));
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, 8, 1, 1, 1, &err),
                     BTF_E_ARG);
    btf_vk_buffer *with_null[3] = {g.buf[0], NULL, g.buf[2]};
    assert_int_equal(btf__vk_job_dispatch(job, g.pipe[0], with_null, 3, &p, sizeof p, 1, 1, 1,
                                          &err),
                     BTF_E_ARG);
    /* The largest count is fine; a zero count records nothing. */
    TU_OK(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, sizeof p, mx[0], 1, 1, &err), &err);
    TU_OK(btf__vk_job_dispatch(job, g.pipe[0], g.buf, 3, &p, sizeof p, 0, 1, 1, &err), &err);
    TU_OK(btf__vk_job_submit_wait(job, &err), &err);
    noise_gpu_close(&g);
}

static void pipeline_errors(void **state)
{
    (void)state;
    btf_vk *vk = open_vk(NULL);
    const btf_vk_device_info *in = btf__vk_info(vk);
    btf_error err = {0};
    btf_vk_pipeline *p = NULL;
    static const uint32_t junk[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    assert_int_equal(btf__vk_pipeline_create(vk, junk, sizeof junk, 3, 28, NULL, 0, &p, &err),
                     BTF_E_ARG);
    assert_true(contains(err.msg, "not a SPIR-V module"));
    assert_int_equal(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv - 2, 3,
                                             28, NULL, 0, &p, &err),
                     BTF_E_ARG);
    assert_int_equal(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 3,
                                             in->max_push_constants_bytes + 4, NULL, 0, &p, &err),
                     BTF_E_ARG);
    assert_true(contains(err.msg, "maxPushConstantsSize"));
    assert_int_equal(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 3, 30,
                                             NULL, 0, &p, &err),
                     BTF_E_ARG);
    assert_int_equal(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv,
                                             BTF_VK_MAX_BUFFERS + 1, 28, NULL, 0, &p, &err),
                     BTF_E_ARG);
    assert_int_equal(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 3, 28,
                                             NULL, 2, &p, &err),
                     BTF_E_ARG);
    assert_null(p);
    close_vk(vk);
}

/* A pipeline layout that lacks binding 2 the shader uses: the validation
 * layer reports it (at pipeline creation, nothing is run), and the count
 * proves the messenger works. */
static void validation_counts_errors(void **state)
{
    (void)state;
    btf_vk *vk = open_vk(NULL);
    btf_error err = {0};
    btf_vk_pipeline *p = NULL;
    assert_int_equal(btf__vk_validation_errors(vk), 0);
    assert_string_equal(btf__vk_first_validation_message(vk), "");
    btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 2, 28, NULL, 0, &p,
                            &err);
    btf__vk_pipeline_destroy(p);
    assert_true(btf__vk_validation_errors(vk) > 0);
    const char *m = btf__vk_first_validation_message(vk);
    print_message("provoked validation message: %.200s...\n", m);
    assert_true(strlen(m) > 10);
    assert_null(strchr(m, '\n'));
    btf__vk_destroy(vk);
}

/* A job far longer than its 1 ms limit: a clear error, the context refuses
 * more work, and everything is still destroyed cleanly. */
static void job_timeout(void **state)
{
    (void)state;
    enum { CAP = 1 << 19 };
    btf_vk_opts o = {.timeout_ms = 1};
    btf_vk *vk = open_vk(&o);
    btf_error err = {0};
    btf_vk_pipeline *pipe;
    btf_vk_buffer *buf[3];
    TU_OK(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 3,
                                  sizeof(noise_params), NULL, 0, &pipe, &err),
          &err);
    for (int i = 0; i < 3; i++)
        TU_OK(btf__vk_buffer_create(vk, (uint64_t)CAP * 16, &buf[i], &err), &err);
    noise_params p = {.seed_lo = 1, .nblocks = 1024, .count = CAP};
    btf_vk_job *job;
    TU_OK(btf__vk_job_begin(vk, &job, &err), &err);
    for (int rep = 0; rep < 4; rep++)
        TU_OK(btf__vk_job_dispatch(job, pipe, buf, 3, &p, sizeof p, CAP / 64, 1, 1, &err), &err);
    int rc = btf__vk_job_submit_wait(job, &err);
    if (rc == BTF_OK && !btf__vk_info(vk)->is_cpu) { /* a GPU may be that fast */
        for (int i = 0; i < 3; i++)
            btf__vk_buffer_destroy(buf[i]);
        btf__vk_pipeline_destroy(pipe);
        close_vk(vk);
        skip();
    }
    assert_int_equal(rc, BTF_E_UNSUPPORTED);
    assert_true(contains(err.msg, "did not finish within 1 ms"));
    assert_true(contains(err.msg, "VK_TIMEOUT"));
    assert_int_equal(btf__vk_job_begin(vk, &job, &err), BTF_E_UNSUPPORTED);
    assert_true(contains(err.msg, "unusable"));
    for (int i = 0; i < 3; i++)
        btf__vk_buffer_destroy(buf[i]);
    btf__vk_pipeline_destroy(pipe);
    close_vk(vk);
}

/* ------------------------------------------------------------- timings */

static void timings(void **state)
{
    (void)state;
    for (int validation = 1; validation >= 0; validation--) {
        btf_vk_opts o = {.allow_cpu = 1, .validation = validation};
        btf_error err = {0};
        btf_vk *vk;
        double t0 = now_s();
        TU_OK(btf__vk_create(&o, &vk, &err), &err);
        double t1 = now_s();
        btf_vk_pipeline *pipe;
        TU_OK(btf__vk_pipeline_create(vk, noise_check_spv, sizeof noise_check_spv, 3,
                                      sizeof(noise_params), NULL, 0, &pipe, &err),
              &err);
        double t2 = now_s();
        btf_vk_buffer *buf[3];
        for (int i = 0; i < 3; i++)
            TU_OK(btf__vk_buffer_create(vk, 64 * 16, &buf[i], &err), &err);
        noise_params p = {.nblocks = 8, .count = 64};
        double submit[21];
        for (int k = 0; k < 21; k++) {
            btf_vk_job *job;
            double a = now_s();
            TU_OK(btf__vk_job_begin(vk, &job, &err), &err);
            TU_OK(btf__vk_job_dispatch(job, pipe, buf, 3, &p, sizeof p, 1, 1, 1, &err), &err);
            TU_OK(btf__vk_job_submit_wait(job, &err), &err);
            submit[k] = now_s() - a;
        }
        double later = 0, best = 1e9;
        for (int k = 1; k < 21; k++) {
            later += submit[k] / 20;
            best = submit[k] < best ? submit[k] : best;
        }
        print_message("timings (validation %s): create %.1f ms, pipeline %.1f ms, first job "
                      "%.2f ms, later jobs %.3f ms mean / %.3f ms best\n",
                      validation ? "on" : "off", 1e3 * (t1 - t0), 1e3 * (t2 - t1),
                      1e3 * submit[0], 1e3 * later, 1e3 * best);
        for (int i = 0; i < 3; i++)
            btf__vk_buffer_destroy(buf[i]);
        btf__vk_pipeline_destroy(pipe);
        close_vk(vk);
    }
}

/* ----------------------------------------------------------------- CLI */

static void cli_info_devices(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    const char *out = tu_fmt("%s/out.txt", dir);
    char *errtext = NULL;
    int rc = tu_run(tu_fmt("%s info --devices >%s", tu_cli(), out), &errtext);
    if (rc != 0)
        print_error("btfcar info --devices: %s\n", errtext);
    assert_int_equal(rc, 0);
    free(errtext);
    char *t = slurp(out);
    if (forced_lavapipe) {
        assert_true(contains(t, "llvmpipe"));
        assert_true(contains(t, "CPU"));
        assert_true(contains(t, "128.0 MiB")); /* maxStorageBufferRange */
        assert_true(contains(t, "16-bit storage"));
    }
    free(t);

    /* No driver: exit 1 with the clear message. */
    rc = tu_run(tu_fmt("VK_DRIVER_FILES=/nonexistent/icd.json VK_ICD_FILENAMES=/nonexistent/"
                       "icd.json %s info --devices >%s",
                       tu_cli(), out),
                &errtext);
    assert_int_equal(rc, 1);
    assert_true(contains(errtext, "no Vulkan device found"));
    free(errtext);

    rc = tu_run(tu_fmt("%s info --help >%s", tu_cli(), out), NULL);
    assert_int_equal(rc, 0);
    t = slurp(out);
    assert_true(contains(t, "--devices"));
    free(t);

    rc = tu_run(tu_fmt("%s info --devices somewhere >%s", tu_cli(), out), NULL);
    assert_int_equal(rc, 2);
    tu_rmtree(dir);
    free(dir);
}

/* The command reads BTF_VK_DEVICE and BTF_VK_VALIDATION and says which
 * variable is wrong; --device names a device as BTF_VK_DEVICE does. */
static void cli_environment(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    btf_image img;
    tu_material_image("leather", 16, 1, (btf_dir){0, 0}, (btf_dir){45, 30}, &img);
    btf_model m;
    btf_fit_opts fo = {.levels = 1};
    btf_error e = {0};
    TU_OK(btf_texture_fit(&img, &fo, &m, &e), &e);
    TU_OK(btf_model_write(tu_fmt("%s/m.btfcar", dir), &m, &e), &e);
    btf_model_free(&m);
    btf_image_free(&img);
    char *run = strdup(tu_fmt("%s synthesise -q %s/m.btfcar --size 8x8 --backend gpu -o %s/o",
                              tu_cli(), dir, dir));
    char *errtext = NULL;
    assert_int_equal(tu_run(tu_fmt("BTF_VK_DEVICE=99 %s", run), &errtext), 1);
    assert_true(contains(errtext, "BTF_VK_DEVICE=99"));
    assert_true(contains(errtext, "does not exist"));
    free(errtext);
    assert_int_equal(tu_run(tu_fmt("BTF_VK_DEVICE=one %s", run), &errtext), 1);
    assert_true(contains(errtext, "BTF_VK_DEVICE='one'"));
    free(errtext);
    assert_int_equal(tu_run(tu_fmt("BTF_VK_VALIDATION=yes %s", run), &errtext), 1);
    assert_true(contains(errtext, "BTF_VK_VALIDATION='yes'"));
    free(errtext);
    if (forced_lavapipe) {
        /* A named device is taken even when it is the CPU driver. */
        assert_int_equal(tu_run(tu_fmt("BTF_VK_DEVICE=0 %s synthesise -q %s/m.btfcar --size 8x8 "
                                       "-o %s/n", tu_cli(), dir, dir), NULL), 0);
        assert_int_equal(tu_run(tu_fmt("%s --device 0", run), NULL), 0);
    }
    free(run);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    /* lavapipe, unless the caller chose a driver; no device or validation
     * overrides from the caller's environment. */
    forced_lavapipe = !getenv("VK_DRIVER_FILES") && !getenv("VK_ICD_FILENAMES");
    if (!getenv("VK_DRIVER_FILES"))
        setenv("VK_DRIVER_FILES", LAVAPIPE_ICD, 1);
    if (!getenv("VK_ICD_FILENAMES"))
        setenv("VK_ICD_FILENAMES", LAVAPIPE_ICD, 1);
    unsetenv("BTF_VK_DEVICE");
    unsetenv("BTF_VK_VALIDATION");
    tu_vk_keep_layer_loaded();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(list_devices),
        cmocka_unit_test(create_destroy_repeatedly),
        cmocka_unit_test(device_choice_errors),
        cmocka_unit_test(validation_switches),
        cmocka_unit_test(no_driver),
        cmocka_unit_test(buffer_round_trip_mapped),
        cmocka_unit_test(buffer_round_trip_staged),
        cmocka_unit_test(buffer_limits),
        cmocka_unit_test(fill_and_copy),
        cmocka_unit_test(noise_parity),
        cmocka_unit_test(noise_parity_staged),
        cmocka_unit_test(dispatch_limits),
        cmocka_unit_test(pipeline_errors),
        cmocka_unit_test(validation_counts_errors),
        cmocka_unit_test(job_timeout),
        cmocka_unit_test(timings),
        cmocka_unit_test(cli_info_devices),
        cmocka_unit_test(cli_environment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
