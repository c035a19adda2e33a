/* test_gpu_tileable.c — tileable synthesis on the GPU (Vulkan compute on
 * lavapipe, the Khronos validation layer on, no message allowed) against
 * the CPU (docs/synthesis.md, "Tileable synthesis"; docs/gpu.md): the same
 * bits at several sizes, models and buffer limits; images left on the
 * device (btf__gpu_synthesise_device, gpu/synth_gpu.h) are the downloaded
 * images bit for bit, refused clearly where one buffer cannot hold them;
 * `btfcar synthesise --tileable --backend gpu` gives the CPU's pixels. */
#include "synth/synth_testing.h"
#include "synth_gpu.h"
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static btf_gpu *gpu;

static int setup(void **state)
{
    (void)state;
    return tu_gpu_open(&gpu, "test_gpu_tileable");
}

static int teardown(void **state)
{
    (void)state;
    btf_gpu_close(gpu);
    return 0;
}

static void no_validation_messages(btf_gpu *g)
{
    tu_gpu_no_validation_messages(g);
}

static void fit(btf_model *m, int levels, const char *spec)
{
    btf_error e = {0};
    btf_image img;
    tu_material_image("fabric", 64, 5, (btf_dir){0, 0}, (btf_dir){45, 30}, &img);
    btf_fit_opts fo = {.levels = levels};
    if (spec)
        TU_OK(btf_neighbourhood_parse(spec, fo.car.fixed, &fo.car.n_fixed, &e), &e);
    TU_OK(btf_texture_fit(&img, &fo, m, &e), &e);
    btf_image_free(&img);
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* GPU and CPU tileable syntheses of every subspace of m at w x h: the same
 * bits; the wrap is really tileable (not the streaming image). */
static void compare(btf_gpu *g, const btf_model *m, int w, int h, uint64_t seed)
{
    btf_error e = {0};
    int n = m->n_subspaces, subs[8] = {0};
    assert_true(n <= 8);
    btf_image out[8];
    for (int k = 0; k < n; k++)
        subs[k] = k;
    btf_synth_opts o = {.width = w, .height = h, .seed = seed, .tileable = 1};
    double t0 = now();
    TU_OK(btf_gpu_synthesise(g, m, subs, n, &o, out, &e), &e);
    double t1 = now();
    for (int k = 0; k < n; k++) {
        btf_image cpu, stream;
        TU_OK(btf_synthesise_image(m, k, &o, &cpu, &e), &e);
        size_t count = (size_t)w * h * 3, diff = 0;
        for (size_t i = 0; i < count; i++)
            diff += memcmp(&out[k].data[i], &cpu.data[i], sizeof(float)) != 0;
        if (diff)
            print_error("tileable %dx%d seed %llu subspace %d: %zu of %zu values differ\n", w, h,
                        (unsigned long long)seed, k, diff, count);
        assert_int_equal(diff, 0);
        /* the fields differ from the streaming synthesis' (compared
         * without colour matching, which sends a single pixel to the
         * exemplar's median colour either way) */
        btf_image_free(&cpu);
        o.match_colours = -1;
        TU_OK(btf_synthesise_image(m, k, &o, &cpu, &e), &e);
        o.tileable = 0;
        TU_OK(btf_synthesise_image(m, k, &o, &stream, &e), &e);
        o.tileable = 1, o.match_colours = 0;
        assert_memory_not_equal(cpu.data, stream.data, count * sizeof(float));
        btf_image_free(&cpu), btf_image_free(&stream), btf_image_free(&out[k]);
    }
    print_message("tileable %dx%d, %d subspace(s), %d level(s): GPU = CPU bit for bit (GPU "
                  "%.3f s)\n", w, h, n, m->subspaces[0].levels, t1 - t0);
    no_validation_messages(g);
}

/* Models of 1 to 3 levels, fixed and fitted neighbourhoods, the smallest
 * tileable sizes (coarsest level 1 x 1), odd periods, tall and wide. */
static void tileable_parity(void **state)
{
    (void)state;
    btf_model m;
    fit(&m, 3, NULL);
    compare(gpu, &m, 64, 48, 1);
    compare(gpu, &m, 4, 4, 2);
    compare(gpu, &m, 12, 100, 3);
    compare(gpu, &m, 256, 256, 4);
    btf_model_free(&m);
    fit(&m, 2, "0:-1,0:-3,-1:0,-2:1,-1:2,-3:-2");
    compare(gpu, &m, 34, 18, 5);
    btf_model_free(&m);
    fit(&m, 1, "0:-1,-1:0,-1:-1,-1:1");
    compare(gpu, &m, 1, 1, 6);
    compare(gpu, &m, 7, 5, 7);
    btf_model_free(&m);
}

/* A low buffer limit forces strips of rows (and batches): the periodic
 * noise does not depend on the strip. */
static void tileable_parity_when_tiled(void **state)
{
    (void)state;
    btf_model a, b;
    fit(&a, 3, NULL);
    fit(&b, 2, "0:-1,-1:2,-3:0");
    btf_model m = {0};
    btf_subspace_model subs[2] = {a.subspaces[0], b.subspaces[0]};
    m.n_subspaces = 2;
    m.subspaces = subs;
    btf_error e = {0};
    btf_gpu *small;
    btf_gpu_opts o = {.allow_cpu = 1, .validation = 1};
    TU_OK(btf_gpu_open(&o, &small, &e), &e);
    btf__gpu_set_max_buffer_bytes(small, 4000000);
    compare(small, &m, 300, 256, 11);
    int batches, jobs;
    btf__gpu_last_tiling(small, &batches, &jobs);
    print_message("limit 4000000 bytes: %d batch(es), %d jobs\n", batches, jobs);
    assert_true(jobs >= 2 * batches);
    btf_gpu_close(small);
    btf_model_free(&a);
    btf_model_free(&b);
}

/* Sizes that do not tile: the CPU's error, before anything is allocated. */
static void tileable_bad_sizes(void **state)
{
    (void)state;
    btf_model m;
    fit(&m, 3, NULL);
    btf_error e = {0}, ce = {0};
    btf_image out[1], cpu;
    int zero = 0;
    btf_synth_opts o = {.width = 258, .height = 256, .tileable = 1};
    assert_int_equal(btf_gpu_synthesise(gpu, &m, &zero, 1, &o, out, &e), BTF_E_ARG);
    assert_int_equal(btf_synthesise_image(&m, 0, &o, &cpu, &ce), BTF_E_ARG);
    assert_string_equal(e.msg, ce.msg);
    assert_null(out[0].data);
    btf_gpu_images dev;
    for (int b = 0; b < BTF_GPU_DEVICE_BUFFERS; b++)
        dev.buf[b] = (btf_vk_buffer *)&e; /* must be reset to NULL */
    uint64_t off[1];
    assert_int_equal(btf__gpu_synthesise_device(gpu, &m, &zero, 1, &o, &dev, off, &e), BTF_E_ARG);
    for (int b = 0; b < BTF_GPU_DEVICE_BUFFERS; b++)
        assert_null(dev.buf[b]);
    assert_string_equal(e.msg, ce.msg);
    btf_model_free(&m);
}

/* Images left on the device: the one buffer, downloaded, holds
 * btf_gpu_synthesise's images at the offsets given, bit for bit (tileable
 * and streaming; strips and batches too); too much for one buffer is
 * BTF_E_UNSUPPORTED naming the sizes; no images is BTF_E_ARG. The btf_vk
 * of the btf_gpu is the device's. */
static void device_images(void **state)
{
    (void)state;
    btf_model a, b;
    fit(&a, 3, NULL);
    fit(&b, 2, "0:-1,-1:2,-3:0");
    btf_model m = {0};
    btf_subspace_model subs3[3] = {a.subspaces[0], b.subspaces[0], a.subspaces[0]};
    m.n_subspaces = 3;
    m.subspaces = subs3;
    btf_vk *vk = btf__gpu_vk(gpu);
    assert_non_null(vk);
    assert_string_equal(btf__vk_info(vk)->name, btf_gpu_device_name(gpu));
    btf_error e = {0};
    int subs[3] = {0, 1, 2};
    btf_gpu *small;
    btf_gpu_opts go = {.allow_cpu = 1, .validation = 1};
    TU_OK(btf_gpu_open(&go, &small, &e), &e);
    btf_gpu *gs[2] = {gpu, small};
    for (int gi = 0; gi < 2; gi++)
        for (int tileable = 0; tileable < 2; tileable++) {
            btf_gpu *g = gs[gi];
            int w = gi ? 300 : 96, h = gi ? 256 : 64;
            if (gi) /* strips of rows; the device buffer itself still fits */
                btf__gpu_set_max_buffer_bytes(g, 4000000);
            btf_synth_opts o = {.width = w, .height = h, .seed = 9, .tileable = tileable};
            btf_gpu_images dev;
            uint64_t off[3];
            TU_OK(btf__gpu_synthesise_device(g, &m, subs, 3, &o, &dev, off, &e), &e);
            size_t floats = (size_t)w * h * 3;
            assert_int_equal(btf__vk_buffer_size(dev.buf[0]), 4 * 3 * floats);
            assert_null(dev.buf[1]);
            float *host = malloc(4 * 3 * floats);
            TU_OK(btf__vk_buffer_download(btf__gpu_vk(g), dev.buf[0], 0, host, 4 * 3 * floats, &e),
                  &e);
            btf_image out[3];
            TU_OK(btf_gpu_synthesise(g, &m, subs, 3, &o, out, &e), &e);
            for (int k = 0; k < 3; k++) {
                assert_int_equal(off[k], k * floats);
                assert_memory_equal(host + off[k], out[k].data, floats * sizeof(float));
                btf_image_free(&out[k]);
            }
            assert_memory_not_equal(host, host + floats, floats * sizeof(float));
            print_message("%s %dx%d x 3 on the device (%s): the downloaded images, bit for bit\n",
                          tileable ? "tileable" : "streaming", w, h,
                          gi ? "4 MB buffers: strips" : "one job");
            free(host);
            btf__gpu_images_free(&dev);
            no_validation_messages(g);
        }
    /* 3 x 300 x 512 x 3 floats = 5.3 MiB over 3.2 MB buffers: the images
     * straddle two buffers (each 1.8 MiB: buffer 0 holds the first and
     * part of the second), each downloaded across them bit for bit */
    btf__gpu_set_max_buffer_bytes(small, 3200000); /* the strips' working set: 3.0 MiB */
    btf_synth_opts o = {.width = 300, .height = 512, .seed = 9, .tileable = 1};
    btf_gpu_images dev;
    uint64_t off[8]; /* offsets[j] for each of up to 8 images below */
    TU_OK(btf__gpu_synthesise_device(small, &m, subs, 3, &o, &dev, off, &e), &e);
    size_t floats = (size_t)300 * 512 * 3;
    assert_int_equal(dev.cap, 800000);
    assert_non_null(dev.buf[1]);
    assert_null(dev.buf[2]);
    btf_image out[3];
    TU_OK(btf_gpu_synthesise(small, &m, subs, 3, &o, out, &e), &e);
    float *host = malloc(4 * floats);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(off[k], k * floats);
        TU_OK(btf__gpu_images_download(btf__gpu_vk(small), &dev, off[k], host, floats, &e), &e);
        assert_memory_equal(host, out[k].data, floats * sizeof(float));
        btf_image_free(&out[k]);
    }
    free(host);
    btf__gpu_images_free(&dev);
    no_validation_messages(small);
    /* more than the device's 8 buffers hold: BTF_E_UNSUPPORTED naming the sizes */
    btf__gpu_set_max_buffer_bytes(small, 1000000);
    o.tileable = 0;
    o.height = 64;
    o.width = 2000;
    int many[8] = {0, 1, 2, 0, 1, 2, 0, 1};
    assert_int_equal(btf__gpu_synthesise_device(small, &m, many, 8, &o, &dev, off, &e),
                     BTF_E_UNSUPPORTED);
    print_message("%s\n", e.msg);
    for (int b = 0; b < BTF_GPU_DEVICE_BUFFERS; b++)
        assert_null(dev.buf[b]);
    assert_non_null(strstr(e.msg, "more than 8 storage buffers"));
    assert_int_equal(btf__gpu_synthesise_device(small, &m, subs, 0, &o, &dev, off, &e), BTF_E_ARG);
    btf_gpu_close(small);
    btf_model_free(&a);
    btf_model_free(&b);
}

/* The command: --tileable --backend gpu (validation on) writes the CPU's
 * pixels. */
static void cli_tileable_gpu(void **state)
{
    (void)state;
    char *dir = tu_tmpdir();
    btf_model m;
    fit(&m, 2, NULL);
    btf_error e = {0};
    TU_OK(btf_model_write(tu_fmt("%s/m.btfcar", dir), &m, &e), &e);
    btf_model_free(&m);
    const char *validate = getenv("BTF_ASAN") ? "" : "BTF_VK_VALIDATION=1";
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s %s synthesise -q %s/m.btfcar --size 48x20 --tileable --float "
                           "--backend gpu -o %s/g", validate, tu_cli(), dir, dir), &err);
    if (rc)
        print_error("%s\n", err);
    assert_int_equal(rc, 0);
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s/m.btfcar --size 48x20 --tileable --float "
                                   "--backend cpu -o %s/c", tu_cli(), dir, dir), NULL), 0);
    btf_image g, c;
    TU_OK(btf_image_read(tu_fmt("%s/g/subspace_00.exr", dir), NULL, &g, &e), &e);
    TU_OK(btf_image_read(tu_fmt("%s/c/subspace_00.exr", dir), NULL, &c, &e), &e);
    assert_int_equal(g.width, 48);
    assert_memory_equal(g.data, c.data, 48 * 20 * 3 * sizeof(float));
    btf_image_free(&g);
    btf_image_free(&c);
    tu_rmtree(dir);
    free(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tileable_parity),
        cmocka_unit_test(tileable_parity_when_tiled),
        cmocka_unit_test(tileable_bad_sizes),
        cmocka_unit_test(device_images),
        cmocka_unit_test(cli_tileable_gpu),
    };
    return cmocka_run_group_tests_name("gpu_tileable", tests, setup, teardown);
}
