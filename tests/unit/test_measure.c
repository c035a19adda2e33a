/* test_measure.c — texture distances without pixel correspondence and the
 * phase-randomisation baseline (src/measure/, docs/measure.md). */
#include "testutil.h"

#include "car/car.h"
#include "io/io.h"
#include "measure/measure.h"
#include "core/core.h"

#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const btf_dir VIEW = {0, 0}, LIGHT = {45, 30};

/* A w x h rectangle of src at (x0, y0). */
static void crop(const btf_image *src, int x0, int y0, int w, int h, btf_image *out)
{
    btf_error e = {0};
    TU_OK(btf_image_alloc(out, w, h, src->channels, &e), &e);
    int c = src->channels;
    for (int y = 0; y < h; y++)
        memcpy(out->data + (size_t)y * w * c, src->data + ((size_t)(y0 + y) * src->width + x0) * c,
               (size_t)w * c * sizeof(float));
}

static void copy(const btf_image *src, btf_image *out)
{
    crop(src, 0, 0, src->width, src->height, out);
}

/* The pixels in a seeded random order (Fisher-Yates): the same histogram,
 * no spatial structure. */
static void shuffle(btf_image *img, uint64_t seed)
{
    btf_rng r;
    btf__rng_seed(&r, seed);
    size_t n = (size_t)img->width * img->height;
    int c = img->channels;
    for (size_t i = n - 1; i > 0; i--) {
        size_t j = (size_t)(btf__rng_uniform(&r) * (double)(i + 1));
        for (int k = 0; k < c; k++) {
            float t = img->data[i * c + k];
            img->data[i * c + k] = img->data[j * c + k];
            img->data[j * c + k] = t;
        }
    }
}

/* `passes` 3 x 3 box blurs (clamped borders): a Gaussian-like blur. */
static void blur(btf_image *img, int passes)
{
    btf_error e = {0};
    btf_image tmp;
    copy(img, &tmp);
    int w = img->width, h = img->height, c = img->channels;
    for (int p = 0; p < passes; p++) {
        memcpy(tmp.data, img->data, (size_t)w * h * c * sizeof(float));
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                for (int k = 0; k < c; k++) {
                    double s = 0.0;
                    for (int dy = -1; dy <= 1; dy++)
                        for (int dx = -1; dx <= 1; dx++) {
                            int yy = y + dy < 0 ? 0 : y + dy >= h ? h - 1 : y + dy;
                            int xx = x + dx < 0 ? 0 : x + dx >= w ? w - 1 : x + dx;
                            s += tmp.data[((size_t)yy * w + xx) * c + k];
                        }
                    img->data[((size_t)y * w + x) * c + k] = (float)(s / 9.0);
                }
    }
    (void)e;
    btf_image_free(&tmp);
}

static void fill(btf_image *img, float v)
{
    for (size_t i = 0; i < (size_t)img->width * img->height * img->channels; i++)
        img->data[i] = v;
}

static void expect_finite(const btf_texture_distances *d)
{
    const btf_distance_component *c[3] = {&d->spectrum, &d->first_order, &d->structure};
    for (int i = 0; i < 3; i++) {
        assert_true(isfinite(c[i]->raw) && c[i]->raw >= 0.0);
        assert_true(isfinite(c[i]->self) && c[i]->self >= 0.0);
        assert_true(isfinite(c[i]->normalised) && c[i]->normalised >= 0.0);
    }
    assert_true(isfinite(d->combined));
    for (int k = 0; k < 3; k++)
        assert_true(isfinite(d->first_order_lab[k]));
}

static void measure(const btf_image *ref, const btf_image *img, btf_texture_distances *d)
{
    btf_error e = {0};
    TU_OK(btf_texture_distance(ref, img, NULL, d, &e), &e);
    expect_finite(d);
}

static void show(const char *what, const btf_texture_distances *d)
{
    print_message("%-22s spectrum %.3f dB (x%.2f)  first-order %.3f (x%.2f)  structure %.4f "
                  "(x%.2f)  combined %.2f\n", what, d->spectrum.raw, d->spectrum.normalised,
                  d->first_order.raw, d->first_order.normalised, d->structure.raw,
                  d->structure.normalised, d->combined);
}

/* Identical images: every component exactly 0 (the same descriptors). */
static void identical_is_zero(void **state)
{
    (void)state;
    const char *names[] = {"leather", "fabric", "wood"};
    for (int m = 0; m < 3; m++) {
        btf_image ref;
        tu_material_image(names[m], 128, 3, VIEW, LIGHT, &ref);
        btf_texture_distances d;
        measure(&ref, &ref, &d);
        assert_true(d.spectrum.raw == 0.0 && d.first_order.raw == 0.0 &&
                    d.structure.raw == 0.0 && d.combined == 0.0);
        /* The reference is a texture: its self-distances are real, above the floors. */
        assert_true(d.spectrum.self > 0.1 && d.first_order.self > 0.1 &&
                    d.structure.self > 0.01);
        assert_int_equal(d.spectrum_bins, 32);
        assert_int_equal(d.levels, 4);
        btf_image_free(&ref);
    }
}

/* Disjoint crops of the same material (the other three 128 x 128 regions
 * of one 256 x 256 rendering) are about as far from the reference (the
 * first region) as the reference's quadrants are from each other: near 1.
 * (The quadrants' self-distance is rescaled to the crops' sample size:
 * texture_distance.c.) One crop scatters around its expected value, more
 * so on materials with coarse structure (wood's grain): each crop's
 * figures stay within [0.2, 3.5], their mean combined within [0.5, 1.8]. */
static void crop_scores_near_one(void **state)
{
    (void)state;
    const char *names[] = {"leather", "fabric", "wood"};
    for (int m = 0; m < 3; m++) {
        btf_image big, ref, other;
        tu_material_image(names[m], 256, 4, VIEW, LIGHT, &big);
        crop(&big, 0, 0, 128, 128, &ref);
        btf_texture_distances d;
        double mean = 0.0;
        for (int q = 1; q < 4; q++) {
            crop(&big, 128 * (q & 1), 128 * (q >> 1), 128, 128, &other);
            measure(&ref, &other, &d);
            show(tu_fmt("%s crop %d", names[m], q), &d);
            assert_true(d.spectrum.normalised > 0.2 && d.spectrum.normalised < 3.5);
            assert_true(d.first_order.normalised > 0.2 && d.first_order.normalised < 3.5);
            assert_true(d.structure.normalised > 0.2 && d.structure.normalised < 3.5);
            mean += d.combined / 3.0;
            btf_image_free(&other);
        }
        print_message("%s: mean combined of 3 disjoint crops %.2f\n", names[m], mean);
        assert_true(mean > 0.5 && mean < 1.8);
        /* A crop of different size (a contained one: 96 x 64 of the
         * reference) also scores near 1 on the stochastic materials. Not on
         * the woven fabric: its spectrum is a set of sharp peaks, and a view
         * whose side is not a multiple of the weave's period smears them
         * differently (about 4 x its self-distance in spectrum). */
        if (m != 1) {
            btf_image part;
            crop(&ref, 20, 40, 96, 64, &part);
            measure(&ref, &part, &d);
            show("  contained 96x64", &d);
            assert_true(d.combined > 0.1 && d.combined < 2.0);
            btf_image_free(&part);
        }
        btf_image_free(&big);
        btf_image_free(&ref);
    }
}

/* Shuffled pixels: the same histogram (first order exactly 0), no spatial
 * structure (spectrum white, bands uncorrelated): far worse there. */
static void shuffled_pixels(void **state)
{
    (void)state;
    btf_image ref, img;
    tu_material_image("leather", 128, 5, VIEW, LIGHT, &ref);
    copy(&ref, &img);
    shuffle(&img, 9);
    btf_texture_distances d;
    measure(&ref, &img, &d);
    show("shuffled", &d);
    assert_true(d.first_order.raw == 0.0);
    assert_true(d.spectrum.normalised > 4.0);
    assert_true(d.structure.normalised > 4.0);
    btf_image_free(&ref);
    btf_image_free(&img);
}

/* Blurred: fine scales lose their power: spectrum and structure worse;
 * the histogram narrows less. */
static void blurred(void **state)
{
    (void)state;
    btf_image ref, img;
    tu_material_image("fabric", 128, 6, VIEW, LIGHT, &ref);
    copy(&ref, &img);
    blur(&img, 3);
    btf_texture_distances d;
    measure(&ref, &img, &d);
    show("blurred", &d);
    assert_true(d.spectrum.normalised > 3.0);
    assert_true(d.structure.normalised > 3.0);
    btf_image_free(&ref);
    btf_image_free(&img);
}

/* Colour shifted (red up, blue down by 30 %): the first order catches it;
 * the structure of L* barely changes. */
static void colour_shift(void **state)
{
    (void)state;
    btf_image ref, img;
    tu_material_image("wood", 128, 7, VIEW, LIGHT, &ref);
    copy(&ref, &img);
    for (size_t i = 0; i < (size_t)img.width * img.height; i++) {
        img.data[3 * i] *= 1.3f;
        img.data[3 * i + 2] *= 0.7f;
    }
    btf_texture_distances d;
    measure(&ref, &img, &d);
    show("colour shifted", &d);
    assert_true(d.first_order.normalised > 4.0);
    assert_true(d.first_order.normalised > 2.0 * d.structure.normalised);
    /* a* (red-green) and b* (blue-yellow) moved more than L*. */
    assert_true(d.first_order_lab[1] > d.first_order_lab[0]);
    assert_true(d.first_order_lab[2] > d.first_order_lab[0]);
    btf_image_free(&ref);
    btf_image_free(&img);
}

/* The baseline keeps the exemplar's power spectrum: measured (Hann window,
 * rings) it is about as close as the material's own samples are (two
 * samples of one spectrum differ by the periodogram's estimation noise,
 * which is what the self-distance is; normalised 0.65 leather, 0.81 wood).
 * The woven fabric scores 2.4: its colour channels are coupled per
 * frequency (yellow and blue threads), and independent phases per
 * decorrelated channel, as the CAR model assumes, do not keep the cross
 * spectrum, so the luminance spectrum changes. The exact property is
 * tested in baseline_amplitudes_exact. It is real, finite, deterministic,
 * keeps the mean colour and wraps at other sizes. */
static void baseline_keeps_spectrum(void **state)
{
    (void)state;
    btf_error e = {0};
    const char *names[] = {"leather", "fabric", "wood"};
    for (int m = 0; m < 3; m++) {
        btf_image ex, out, again;
        tu_material_image(names[m], 128, 8, VIEW, LIGHT, &ex);
        TU_OK(btf_phase_randomise(&ex, 128, 128, 42, &out, &e), &e);
        assert_int_equal(out.width, 128);
        assert_int_equal(out.channels, 3);
        double mean_ex[3] = {0}, mean_out[3] = {0};
        for (size_t i = 0; i < 128 * 128; i++)
            for (int k = 0; k < 3; k++) {
                assert_true(isfinite(out.data[3 * i + k]));
                mean_ex[k] += ex.data[3 * i + k] / (128.0 * 128.0);
                mean_out[k] += out.data[3 * i + k] / (128.0 * 128.0);
            }
        for (int k = 0; k < 3; k++)
            assert_true(fabs(mean_ex[k] - mean_out[k]) < 1e-4 * (1.0 + fabs(mean_ex[k])));
        btf_texture_distances d;
        measure(&ex, &out, &d);
        show(names[m], &d);
        assert_true(d.spectrum.normalised < (m == 1 ? 3.0 : 1.0));
        /* deterministic; another seed another image */
        TU_OK(btf_phase_randomise(&ex, 128, 128, 42, &again, &e), &e);
        assert_memory_equal(out.data, again.data, 128 * 128 * 3 * sizeof(float));
        btf_image_free(&again);
        TU_OK(btf_phase_randomise(&ex, 128, 128, 43, &again, &e), &e);
        assert_true(memcmp(out.data, again.data, 128 * 128 * 3 * sizeof(float)) != 0);
        btf_image_free(&again);
        /* other sizes wrap the periodic texture */
        TU_OK(btf_phase_randomise(&ex, 300, 70, 42, &again, &e), &e);
        for (int y = 0; y < 70; y++)
            for (int x = 0; x < 300; x++)
                for (int k = 0; k < 3; k++)
                    assert_true(again.data[((size_t)y * 300 + x) * 3 + k] ==
                                out.data[((size_t)(y % 128) * 128 + x % 128) * 3 + k]);
        btf_image_free(&again);
        btf_image_free(&out);
        btf_image_free(&ex);
    }
    /* the storage: 3 half-spectra of h x (w/2 + 1) floats, mean and basis */
    assert_true(btf_phase_randomise_bytes(256, 256) == 4ull * (3ull * 256 * 129 + 12));
    assert_true(btf_phase_randomise_bytes(0, 10) == 0);
}

/* Exactly the exemplar's amplitude spectrum: the output, decorrelated with
 * the exemplar's basis, has at every frequency but DC the DFT amplitude of
 * the exemplar's decorrelated channel's periodic component (odd and even
 * sides). Dropping the imaginary part loses nothing: the phases are
 * Hermitian-symmetric. */
static void baseline_amplitudes_exact(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image big, ex, out;
    tu_material_image("leather", 128, 14, VIEW, LIGHT, &big);
    crop(&big, 3, 7, 63, 50, &ex);
    TU_OK(btf_phase_randomise(&ex, 63, 50, 77, &out, &e), &e);
    size_t n = 63 * 50;
    float mean[3], basis[9];
    TU_OK(btf__pca3(&ex, mean, basis, NULL, &e), &e);
    double *mem = calloc(10 * n, sizeof(double));
    assert_non_null(mem);
    double *be[3] = {mem, mem + n, mem + 2 * n}, *bo[3] = {mem + 3 * n, mem + 4 * n, mem + 5 * n};
    double *ri = mem + 6 * n, *oi = mem + 7 * n;
    btf__decorrelate(&ex, mean, basis, be);
    btf__decorrelate(&out, mean, basis, bo);
    char why[256];
    for (int c = 0; c < 3; c++) {
        TU_OK(ms_periodic_component(be[c], 63, 50, &e), &e);
        memset(ri, 0, 2 * n * sizeof(double));
        assert_int_equal(btfcv_dft2(be[c], ri, 63, 50, 0, why, sizeof why), 0);
        assert_int_equal(btfcv_dft2(bo[c], oi, 63, 50, 0, why, sizeof why), 0);
        double top = 0.0, worst = 0.0;
        for (size_t i = 1; i < n; i++)
            top = fmax(top, hypot(be[c][i], ri[i]));
        for (size_t i = 1; i < n; i++)
            worst = fmax(worst, fabs(hypot(be[c][i], ri[i]) - hypot(bo[c][i], oi[i])));
        print_message("channel %d: amplitude error %.2e of the largest %.3g\n", c, worst, top);
        assert_true(top > 0.0);
        assert_true(worst < 1e-4 * top);
    }
    free(mem);
    btf_image_free(&out);
    btf_image_free(&ex);
    btf_image_free(&big);
}

/* The periodic component takes the border cross out: a horizontal ramp
 * (all its power in the jump between the left and right borders) becomes
 * nearly constant, so its baseline has no streaks. */
static void baseline_of_ramp(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image ramp, out;
    TU_OK(btf_image_alloc(&ramp, 64, 32, 1, &e), &e);
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 64; x++)
            ramp.data[y * 64 + x] = (float)x / 63.0f;
    TU_OK(btf_phase_randomise(&ramp, 64, 32, 1, &out, &e), &e);
    double lo = 1e30, hi = -1e30;
    for (int i = 0; i < 64 * 32; i++) {
        lo = fmin(lo, out.data[i]);
        hi = fmax(hi, out.data[i]);
    }
    /* without the decomposition the range would be about 1 (a ramp's power) */
    assert_true(hi - lo < 0.25);
    btf_image_free(&out);
    btf_image_free(&ramp);
}

/* Different sizes, grey images, the smallest size allowed, and what is
 * refused below it. */
static void sizes(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image big, ref, img, tiny, grey;
    tu_material_image("leather", 256, 9, VIEW, LIGHT, &big);
    crop(&big, 0, 0, 128, 96, &ref);
    crop(&big, 0, 100, 200, 64, &img);
    btf_texture_distances d;
    measure(&ref, &img, &d);
    show("128x96 vs 200x64", &d);
    assert_int_equal(d.spectrum_bins, 24); /* quadrants 64 x 48: s = 48 */
    assert_true(d.combined < 3.0);
    measure(&img, &ref, &d);
    crop(&big, 0, 0, 16, 16, &tiny);
    measure(&tiny, &tiny, &d);
    assert_true(d.combined == 0.0);
    assert_int_equal(d.spectrum_bins, 4);
    measure(&tiny, &ref, &d);
    measure(&ref, &tiny, &d);
    TU_OK(btf_image_alloc(&grey, 64, 64, 1, &e), &e);
    for (int i = 0; i < 64 * 64; i++)
        grey.data[i] = big.data[3 * i + 1];
    measure(&grey, &ref, &d);
    measure(&grey, &grey, &d);
    assert_true(d.combined == 0.0);
    btf_image_free(&tiny);
    /* below 16: refused, naming the image and its size */
    crop(&big, 0, 0, 15, 64, &tiny);
    btf_texture_distance_opts o = {.reference_name = "ref.png", .image_name = "img.png"};
    assert_int_equal(btf_texture_distance(&ref, &tiny, &o, &d, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "img.png: 15x64"));
    assert_true(d.combined == 0.0);
    assert_int_equal(btf_texture_distance(&tiny, &ref, &o, &d, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "ref.png"));
    btf_image_free(&tiny);
    crop(&big, 0, 0, 1, 256, &tiny); /* one pixel wide */
    assert_int_equal(btf_texture_distance(&tiny, &ref, NULL, &d, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "reference: 1x256"));
    o.levels = 7;
    assert_int_equal(btf_texture_distance(&ref, &ref, &o, &d, &e), BTF_E_ARG);
    o.levels = 6; /* more levels than the size suggests: still finite */
    TU_OK(btf_texture_distance(&ref, &img, &o, &d, &e), &e);
    expect_finite(&d);
    assert_int_equal(d.levels, 6);
    btf_image_free(&tiny);
    btf_image_free(&grey);
    btf_image_free(&big);
    btf_image_free(&ref);
    btf_image_free(&img);
}

/* Constant, huge, negative and non-finite input: finite figures or a
 * clear error, never NaN. */
static void extremes(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image tex, flat, flat2, scaled;
    tu_material_image("wood", 64, 10, VIEW, LIGHT, &tex);
    TU_OK(btf_image_alloc(&flat, 64, 64, 3, &e), &e);
    TU_OK(btf_image_alloc(&flat2, 32, 48, 3, &e), &e);
    fill(&flat, 0.3f);
    fill(&flat2, 0.3f);
    btf_texture_distances d;
    measure(&flat, &flat2, &d); /* constant vs constant: equal */
    assert_true(d.combined == 0.0);
    assert_true(d.spectrum.self == 0.0 && d.first_order.self == 0.0);
    measure(&flat, &tex, &d); /* constant reference: floors, large but finite */
    assert_true(d.combined > 10.0);
    measure(&tex, &flat, &d);
    assert_true(d.combined > 3.0);
    fill(&flat2, 0.6f);
    measure(&flat, &flat2, &d); /* another constant: first order only */
    assert_true(d.first_order.raw > 5.0 && d.spectrum.raw == 0.0);
    copy(&tex, &scaled);
    const float big[] = {1e30f, FLT_MAX, -FLT_MAX, 1e-30f};
    for (int b = 0; b < 4; b++) {
        for (size_t i = 0; i < 64 * 64 * 3; i++)
            scaled.data[i] = tex.data[i] * big[b];
        measure(&scaled, &tex, &d);
        measure(&tex, &scaled, &d);
        measure(&scaled, &scaled, &d);
        assert_true(d.combined == 0.0);
    }
    /* one exposure for both: the texture scaled by 1e30 compared with
     * itself scaled by 2e30 differs as 0.5x does from 1x */
    btf_image twice;
    copy(&tex, &twice);
    for (size_t i = 0; i < 64 * 64 * 3; i++) {
        scaled.data[i] = tex.data[i] * 1e30f;
        twice.data[i] = tex.data[i] * 2e30f;
    }
    measure(&twice, &scaled, &d);
    assert_true(d.first_order.normalised > 2.0);
    btf_image_free(&twice);
    btf_image_free(&scaled);
    copy(&tex, &scaled);
    scaled.data[77] = NAN;
    btf_texture_distance_opts o = {.image_name = "nan.exr"};
    assert_int_equal(btf_texture_distance(&tex, &scaled, &o, &d, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "nan.exr: pixel (25, 0) is not finite"));
    scaled.data[77] = INFINITY;
    assert_int_equal(btf_texture_distance(&scaled, &tex, NULL, &d, &e), BTF_E_DATA);
    /* the baseline: constant in, the constant out; 1 x 1; huge values give
     * finite pixels or an error, never NaN; NaN refused */
    btf_image out;
    TU_OK(btf_phase_randomise(&flat, 64, 64, 3, &out, &e), &e);
    for (size_t i = 0; i < 64 * 64 * 3; i++)
        assert_true(fabsf(out.data[i] - 0.3f) < 1e-6f);
    btf_image_free(&out);
    btf_image one;
    crop(&tex, 5, 5, 1, 1, &one);
    TU_OK(btf_phase_randomise(&one, 3, 2, 3, &out, &e), &e);
    for (int i = 0; i < 3 * 2 * 3; i++)
        assert_true(fabsf(out.data[i] - one.data[i % 3]) < 1e-6f);
    btf_image_free(&out);
    btf_image_free(&one);
    for (int b = 0; b < 3; b++) {
        for (size_t i = 0; i < 64 * 64 * 3; i++)
            scaled.data[i] = tex.data[i] * big[b];
        int rc = btf_phase_randomise(&scaled, 64, 64, 3, &out, &e);
        if (rc == BTF_OK) {
            for (size_t i = 0; i < 64 * 64 * 3; i++)
                assert_true(isfinite(out.data[i]));
            btf_image_free(&out);
        } else {
            assert_int_equal(rc, BTF_E_NUMERIC);
            assert_null(out.data);
        }
    }
    scaled.data[5] = NAN;
    assert_int_equal(btf_phase_randomise(&scaled, 64, 64, 3, &out, &e), BTF_E_DATA);
    assert_int_equal(btf_phase_randomise(&tex, 0, 64, 3, &out, &e), BTF_E_ARG);
    btf_image_free(&scaled);
    btf_image_free(&flat);
    btf_image_free(&flat2);
    btf_image_free(&tex);
}

/* Two runs, the same figures to the bit; and the time of one compare of
 * two 256 x 256 images. */
static void deterministic_and_timed(void **state)
{
    (void)state;
    btf_image a, b;
    tu_material_image("leather", 256, 11, VIEW, LIGHT, &a);
    tu_material_image("leather", 256, 12, VIEW, LIGHT, &b);
    btf_texture_distances d1, d2;
    double t[5];
    for (int i = 0; i < 5; i++) {
        double t0 = tu_now();
        measure(&a, &b, i ? &d2 : &d1);
        t[i] = tu_now() - t0;
        if (i)
            assert_memory_equal(&d1, &d2, sizeof d1);
    }
    print_message("one compare of two 256x256 images: %.1f ms (median of 5)\n",
                  1e3 * tu_median(t, 5));
    show("leather seed 11 vs 12", &d1);
    btf_image_free(&a);
    btf_image_free(&b);
}

/* btfcar compare: the text, --json (parsed with cJSON, the documented
 * keys), --baseline, and the errors. */
static void command(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image big, ref, img;
    tu_material_image("fabric", 128, 13, VIEW, LIGHT, &big);
    crop(&big, 0, 0, 64, 64, &ref);
    crop(&big, 64, 64, 64, 64, &img);
    const char *rp = tu_fmt("%s/ref.png", tu_dir), *ip = tu_fmt("%s/img.exr", tu_dir);
    char rpath[512], ipath[512];
    snprintf(rpath, sizeof rpath, "%s", rp);
    snprintf(ipath, sizeof ipath, "%s", ip);
    TU_OK(btf_image_write_png(rpath, &ref, &e), &e);
    TU_OK(btf_image_write_exr_opts(ipath, &img, NULL, NULL, &e), &e);
    int st;
    char *out = tu_capture(tu_fmt("%s compare %s %s", tu_cli(), rpath, ipath), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "spectrum"));
    assert_non_null(strstr(out, "first-order"));
    assert_non_null(strstr(out, "combined"));
    free(out);
    out = tu_capture(tu_fmt("%s compare %s %s --json", tu_cli(), rpath, ipath), &st);
    assert_int_equal(st, 0);
    cJSON *j = cJSON_Parse(out);
    assert_non_null(j);
    assert_string_equal(cJSON_GetObjectItem(j, "format")->valuestring, "btfcar-compare");
    assert_string_equal(
        cJSON_GetObjectItem(cJSON_GetObjectItem(j, "reference"), "path")->valuestring, rpath);
    assert_int_equal(
        cJSON_GetObjectItem(cJSON_GetObjectItem(j, "image"), "width")->valueint, 64);
    const char *comps[] = {"spectrum", "first_order", "structure"};
    double sum = 0.0;
    for (int i = 0; i < 3; i++) {
        cJSON *c = cJSON_GetObjectItem(j, comps[i]);
        assert_non_null(c);
        const char *keys[] = {"raw", "self", "normalised"};
        for (int k = 0; k < 3; k++) {
            cJSON *v = cJSON_GetObjectItem(c, keys[k]);
            assert_true(cJSON_IsNumber(v) && isfinite(v->valuedouble) && v->valuedouble >= 0);
        }
        assert_true(cJSON_IsString(cJSON_GetObjectItem(c, "unit")));
        sum += cJSON_GetObjectItem(c, "normalised")->valuedouble;
    }
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "spectrum"), "bins")));
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "structure"), "levels")));
    cJSON *fo = cJSON_GetObjectItem(j, "first_order");
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(fo, "L")) &&
                cJSON_IsNumber(cJSON_GetObjectItem(fo, "a")) &&
                cJSON_IsNumber(cJSON_GetObjectItem(fo, "b")));
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(j, "exposure")));
    double combined = cJSON_GetObjectItem(j, "combined")->valuedouble;
    assert_true(fabs(combined - sum / 3.0) < 1e-12 * (1.0 + combined));
    assert_null(cJSON_GetObjectItem(j, "baseline"));
    cJSON_Delete(j);
    free(out);
    /* --baseline: written, measured, its storage in the JSON */
    const char *bp = tu_fmt("%s/base.png", tu_dir);
    out = tu_capture(tu_fmt("%s compare %s --baseline %s --seed 5 --json", tu_cli(), rpath, bp),
                     &st);
    assert_int_equal(st, 0);
    j = cJSON_Parse(out);
    assert_non_null(j);
    cJSON *b = cJSON_GetObjectItem(j, "baseline");
    assert_non_null(b);
    assert_true(cJSON_GetObjectItem(b, "bytes")->valuedouble ==
                (double)btf_phase_randomise_bytes(64, 64));
    assert_int_equal(cJSON_GetObjectItem(b, "seed")->valueint, 5);
    cJSON_Delete(j);
    free(out);
    btf_image base;
    TU_OK(btf_image_read(bp, NULL, &base, &e), &e);
    assert_int_equal(base.width, 64);
    btf_image_free(&base);
    /* errors: usage (2), a too small image (1, naming the file) */
    assert_int_equal(tu_run(tu_fmt("%s compare %s", tu_cli(), rpath), NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s compare %s %s --baseline %s", tu_cli(), rpath, ipath, bp),
                            NULL), 2);
    assert_int_equal(tu_run(tu_fmt("%s compare %s --baseline %s/b.jpg", tu_cli(), rpath, tu_dir),
                            NULL), 2);
    btf_image small;
    crop(&big, 0, 0, 12, 40, &small);
    const char *sp = tu_fmt("%s/small.png", tu_dir);
    char spath[512];
    snprintf(spath, sizeof spath, "%s", sp);
    TU_OK(btf_image_write_png(spath, &small, &e), &e);
    char *why = NULL;
    assert_int_equal(tu_run(tu_fmt("%s compare %s %s", tu_cli(), rpath, spath), &why), 1);
    assert_non_null(strstr(why, "small.png: 12x40"));
    free(why);
    why = NULL;
    assert_int_equal(tu_run(tu_fmt("%s compare %s %s/none.png", tu_cli(), rpath, tu_dir), &why), 1);
    assert_non_null(strstr(why, "none.png"));
    free(why);
    btf_image_free(&small);
    btf_image_free(&big);
    btf_image_free(&ref);
    btf_image_free(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(identical_is_zero),
        cmocka_unit_test(crop_scores_near_one),
        cmocka_unit_test(shuffled_pixels),
        cmocka_unit_test(blurred),
        cmocka_unit_test(colour_shift),
        cmocka_unit_test(baseline_keeps_spectrum),
        cmocka_unit_test(baseline_amplitudes_exact),
        cmocka_unit_test(baseline_of_ramp),
        cmocka_unit_test(sizes),
        cmocka_unit_test(extremes),
        cmocka_unit_test(deterministic_and_timed),
        cmocka_unit_test(command),
    };
    return cmocka_run_group_tests_name("measure", tests, tu_setup_dir, tu_teardown_dir);
}
