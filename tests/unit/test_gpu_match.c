/* test_gpu_match.c — colour matching and the structure layer's multiply on
 * the device (gpu/match_gpu.c; docs/gpu.md, "Colour matching on the
 * device") against the CPU's (src/synth/colour_match.c,
 * btf__structure_apply): bit for bit on lavapipe, the Khronos validation
 * layer on and silent, for images of every shape the sample grid takes
 * (1 x 1, smaller than the sample, strided), values at the extremes
 * (negative, zero, constant, near the float limit), images straddling the
 * device array's buffers (a small buffer cap), and whole syntheses left on
 * the device (btf__gpu_synthesise_device) against btf_synthesise_image. */
#include "model/model.h"
#include "synth/synth.h"
#include "synth/synth_testing.h"
#include "synth_gpu.h"
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static btf_gpu *gpu;
static btf_model model; /* one fitted subspace, with the exemplar's Lab quantiles */

static int setup(void **state)
{
    (void)state;
    int rc = tu_gpu_open(&gpu, "test_gpu_match");
    if (rc)
        return rc;
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 64, 3, (btf_dir){0, 0}, (btf_dir){45, 30}, &img);
    btf_fit_opts fo = {.levels = 2};
    rc = btf_texture_fit(&img, &fo, &model, &e);
    btf_image_free(&img);
    return rc;
}

static int teardown(void **state)
{
    (void)state;
    btf_model_free(&model);
    btf_gpu_close(gpu);
    return 0;
}

/* Values of kind k at i: ordinary light, extremes, constants. */
static float value(int kind, size_t i, unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    float u = (float)(*s >> 8) / 16777216.0f;
    switch (kind) {
    case 0: return 0.05f + 0.5f * u;                         /* ordinary */
    case 1: return i % 7 == 0 ? -u : i % 11 == 0 ? 0.0f : u; /* negative light, zeros */
    case 2: return 0.25f;                                    /* constant */
    case 3: return i % 5 == 0 ? FLT_MAX * u : u * 1e-30f;    /* near both float limits */
    default: return u * 40.0f;                               /* far brighter than the exemplar */
    }
}

/* CPU and device results for one w x h image of kind `kind` placed at
 * float offset `off` of an array of buffers of `cap` floats, with the
 * pattern `pattern` (NULL: none), matched or not. */
static void compare(int w, int h, int kind, uint64_t off, uint64_t cap, const btf_image *pattern,
                    int match)
{
    btf_error e = {0};
    btf_image cpu;
    TU_OK(btf_image_alloc(&cpu, w, h, 3, &e), &e);
    size_t floats = (size_t)w * h * 3;
    unsigned s = 12345u + (unsigned)kind;
    for (size_t i = 0; i < floats; i++)
        cpu.data[i] = value(kind, i, &s);
    btf_gpu_images dev;
    TU_OK(btf__gpu_images_create(btf__gpu_vk(gpu), off + floats, cap, BTF_GPU_DEVICE_BUFFERS, "test", &dev, &e), &e);
    TU_OK(btf__gpu_images_upload(btf__gpu_vk(gpu), &dev, off, cpu.data, floats, &e), &e);
    TU_OK(btf__gpu_match_images(btf__gpu_vk(gpu), btf__gpu_match_pipes(gpu), &model, 0, match, &dev,
                                off, w, h, pattern, &e),
          &e);
    float *back = malloc(floats * sizeof(float));
    assert_non_null(back);
    TU_OK(btf__gpu_images_download(btf__gpu_vk(gpu), &dev, off, back, floats, &e), &e);
    for (int y = 0; pattern && y < h; y++)
        btf__structure_apply_row(pattern, y, cpu.data + (size_t)y * w * 3, w);
    if (match)
        TU_OK(btf__match_synthesised(&model, 0, &cpu, &e), &e);
    size_t diff = 0, first = floats;
    for (size_t i = 0; i < floats; i++)
        if (memcmp(&back[i], &cpu.data[i], sizeof(float))) {
            diff++;
            first = first < i ? first : i;
        }
    if (diff)
        print_error("%dx%d kind %d at %llu, cap %llu%s%s: %zu of %zu values differ, first %zu: "
                    "GPU %.9g CPU %.9g\n",
                    w, h, kind, (unsigned long long)off, (unsigned long long)cap,
                    pattern ? ", pattern" : "", match ? ", matched" : "", diff, floats, first,
                    back[first], cpu.data[first]);
    assert_int_equal(diff, 0);
    for (size_t i = 0; i < floats; i++)
        assert_true(isfinite(back[i]));
    free(back);
    btf__gpu_images_free(&dev);
    btf_image_free(&cpu);
    tu_gpu_no_validation_messages(gpu);
}

/* Sizes the CPU's sample grid treats differently: one pixel, all pixels
 * (under 16,384), strided along x, along both; every kind of value. */
static void matches_cpu_bits(void **state)
{
    (void)state;
    const int sizes[][2] = {{1, 1}, {7, 3}, {100, 90}, {640, 24}, {300, 257}};
    for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++)
        for (int kind = 0; kind < 5; kind++)
            compare(sizes[i][0], sizes[i][1], kind, 0, 1u << 26, NULL, 1);
    print_message("5 sizes x 5 kinds of values (negative, constant, 1e-30 .. FLT_MAX): the "
                  "CPU's bits\n");
}

/* The image straddles buffers (a cap of 10,007 floats puts its pixels and
 * even a pixel's channels across them), after other images (an offset). */
static void straddles_buffers(void **state)
{
    (void)state;
    compare(100, 90, 0, 0, 10007, NULL, 1);
    compare(64, 64, 4, 20000, 10007, NULL, 1);
    print_message("over 3 and 4 buffers of 10,007 floats, at offsets 0 and 20,000: the CPU's "
                  "bits\n");
}

/* The structure layer's pattern: grey and RGB, periodic (smaller than the
 * image), with and without matching. */
static void pattern_multiply(void **state)
{
    (void)state;
    btf_error e = {0};
    for (int ch = 1; ch <= 3; ch += 2) {
        btf_image pat;
        TU_OK(btf_image_alloc(&pat, 13, 7, ch, &e), &e);
        for (size_t i = 0; i < (size_t)13 * 7 * ch; i++)
            pat.data[i] = 0.5f + (float)(i % 17) / 16.0f;
        compare(100, 90, 0, 0, 1u << 26, &pat, 0);
        compare(100, 90, 0, 0, 1u << 26, &pat, 1);
        compare(300, 257, 1, 333, 80000, &pat, 1);
        btf_image_free(&pat);
    }
    print_message("grey and RGB 13x7 patterns, matched or not, straddling buffers: the CPU's "
                  "bits\n");
}

/* A synthesis left on the device, colour matched there, against the CPU's
 * synthesis (btf_synthesise_image matches on the host). */
static void synthesis_on_device(void **state)
{
    (void)state;
    btf_error e = {0};
    int subs[2] = {0, 0};
    btf_synth_opts o = {.width = 200, .height = 150, .seed = 5, .match_colours = 1};
    for (int small = 0; small < 2; small++) {
        if (small) /* the two images over 3 buffers */
            btf__gpu_set_max_buffer_bytes(gpu, 250000);
        btf_gpu_images dev;
        uint64_t off[2];
        TU_OK(btf__gpu_synthesise_device(gpu, &model, subs, 2, &o, &dev, off, &e), &e);
        btf_image cpu;
        o.seed = 5;
        TU_OK(btf_synthesise_image(&model, 0, &o, &cpu, &e), &e);
        size_t floats = (size_t)o.width * o.height * 3;
        float *back = malloc(floats * sizeof(float));
        assert_non_null(back);
        for (int k = 0; k < 2; k++) {
            TU_OK(btf__gpu_images_download(btf__gpu_vk(gpu), &dev, off[k], back, floats, &e), &e);
            assert_memory_equal(back, cpu.data, floats * sizeof(float));
        }
        free(back);
        btf_image_free(&cpu);
        btf__gpu_images_free(&dev);
        btf__gpu_set_max_buffer_bytes(gpu, 0);
        tu_gpu_no_validation_messages(gpu);
    }
    print_message("200x150 synthesised and matched on the device (one buffer, then 3): the "
                  "CPU's synthesis, bit for bit\n");
}

/* btf_gpu_synthesise_each past the memory budget (lowered with the buffer
 * limit: 8 buffers of 250,000 bytes, a 2 MB budget): 200 x 150 images
 * (0.36 MB) go to the device together, 300 x 400 (1.44 MB) one at a time,
 * 300 x 600 images (2.16 MB) alone in strips to the host and are finished
 * there; every image the CPU's bits, in order. */
typedef struct seen {
    const btf_synth_opts *o;
    int count;
} seen;

static int check_image(void *user, int i, btf_image *img, btf_error *err)
{
    seen *s = user;
    assert_int_equal(i, s->count);
    s->count++;
    btf_image cpu;
    TU_OK(btf_synthesise_image(&model, 0, s->o, &cpu, err), err);
    assert_memory_equal(img->data, cpu.data, (size_t)img->width * img->height * 3 * sizeof(float));
    btf_image_free(&cpu);
    return 0;
}

static void synthesis_past_budget(void **state)
{
    (void)state;
    btf_error e = {0};
    int subs[3] = {0, 0, 0};
    btf__gpu_set_max_buffer_bytes(gpu, 250000);
    assert_int_equal(btf_gpu_memory_budget(gpu), 2000000);
    const int sizes[3][2] = {{200, 150}, {300, 400}, {300, 600}};
    for (int i = 0; i < 3; i++) {
        btf_synth_opts o = {.width = sizes[i][0], .height = sizes[i][1], .seed = 7,
                            .match_colours = 1};
        seen s = {&o, 0};
        TU_OK(btf_gpu_synthesise_each(gpu, &model, subs, 3, &o, check_image, &s, &e), &e);
        assert_int_equal(s.count, 3);
    }
    btf__gpu_set_max_buffer_bytes(gpu, 0);
    tu_gpu_no_validation_messages(gpu);
    print_message("a 2 MB budget: 3 x 200x150 in one group, 3 x 300x400 one by one on the "
                  "device, 3 x 300x600 in strips to the host: the CPU's bits, in order\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(matches_cpu_bits),
        cmocka_unit_test(straddles_buffers),
        cmocka_unit_test(pattern_multiply),
        cmocka_unit_test(synthesis_on_device),
        cmocka_unit_test(synthesis_past_budget),
    };
    return cmocka_run_group_tests_name("gpu_match", tests, setup, teardown);
}
