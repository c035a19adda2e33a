/*
 * test_range_map.c — the range tile made periodic (btf_range_make_periodic,
 * src/model/range_periodic.c) and enlarged to a seamless height and normal
 * map of any size (btf__range_map, btf__normal_map, src/range/range_map.c;
 * docs/render.md, "Range and normal map"): wrap-around differences no
 * larger than inside ones, the tile's content kept, exact samples at whole
 * periods, unit finite normals with the x-right, y-up convention, the
 * extremes (1x1, 4097x3, huge heights, constant and absent tiles) and bad
 * input.
 */
#include "testutil.h"
#include "core/core.h"
#include "model/model.h"
#include "render/render.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A non-periodic tile: ripples of non-integer frequency (they do not wrap),
 * a bend and a slope. */
static float *rough_tile(int w, int h, unsigned seed)
{
    float *t = malloc(sizeof(float) * (size_t)w * h);
    assert_non_null(t);
    btf_rng r;
    btf__rng_seed(&r, seed);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            t[(size_t)y * w + x] = (float)(1.5 * sin(0.7 * x + 0.3) * cos(0.45 * y) +
                                           0.002 * (x - 7.0) * (x - 7.0) + 0.03 * y +
                                           0.2 * btf__rng_uniform(&r));
    return t;
}

/* Mean |step| across the wrap (last column to first, last row to first)
 * and inside, and the largest of each, over a w x h map. */
typedef struct steps {
    double wrap_mean, inside_mean, wrap_max, inside_max;
} steps;

static steps measure_steps(const float *t, int w, int h)
{
    steps s = {0};
    long nw = 0, ni = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double v = t[(size_t)y * w + x];
            double d[2] = {fabs(t[(size_t)y * w + (x + 1) % w] - v),
                           fabs(t[(size_t)((y + 1) % h) * w + x] - v)};
            int wraps[2] = {x == w - 1 && w > 1, y == h - 1 && h > 1};
            for (int k = 0; k < 2; k++) {
                if ((k == 0 && w == 1) || (k == 1 && h == 1))
                    continue;
                if (wraps[k]) {
                    s.wrap_mean += d[k], nw++;
                    s.wrap_max = fmax(s.wrap_max, d[k]);
                } else {
                    s.inside_mean += d[k], ni++;
                    s.inside_max = fmax(s.inside_max, d[k]);
                }
            }
        }
    s.wrap_mean /= nw ? nw : 1;
    s.inside_mean /= ni ? ni : 1;
    return s;
}

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++)
        n += *s == '\n';
    return n;
}

static double correlation(const float *a, const float *b, size_t n)
{
    double ma = 0, mb = 0, sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < n; i++)
        ma += a[i], mb += b[i];
    ma /= n, mb /= n;
    for (size_t i = 0; i < n; i++) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / sqrt(saa * sbb);
}

/* A texture-less model holding a copy of the tile (one subspace is enough
 * for btf__range_map, which reads only the range fields). */
static btf_model tile_model(const float *t, int w, int h, float texel)
{
    btf_model m;
    memset(&m, 0, sizeof m);
    m.range_width = w;
    m.range_height = h;
    m.range_texel = texel;
    if (t) {
        m.range = malloc(sizeof(float) * (size_t)w * h);
        assert_non_null(m.range);
        memcpy(m.range, t, sizeof(float) * (size_t)w * h);
    }
    return m;
}

static void assert_unit_normals(const btf_image *n)
{
    assert_int_equal(n->channels, 3);
    for (size_t i = 0; i < (size_t)n->width * n->height; i++) {
        const float *v = n->data + 3 * i;
        assert_true(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]));
        double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
        assert_float_equal(len, 1.0, 1e-5);
        assert_true(v[2] >= 0.0f);
    }
}

/* ------------------------------------------------------ periodic tile */

static void periodic_tile_keeps_content(void **state)
{
    (void)state;
    int w = 24, h = 17;
    float *u = rough_tile(w, h, 3), *p = malloc(sizeof(float) * w * h);
    memcpy(p, u, sizeof(float) * w * h);
    btf_error e = {0};
    TU_OK(btf_range_make_periodic(p, w, h, &e), &e);
    steps su = measure_steps(u, w, h), sp = measure_steps(p, w, h);
    /* The middle half along both axes is mostly the tile itself (the
     * cross-fade's weight of the original is >= 0.7 there). */
    int mw = w - 2 * (w / 4), mh = h - 2 * (h / 4);
    float *cu = malloc(sizeof(float) * mw * mh), *cp = malloc(sizeof(float) * mw * mh);
    for (int y = 0; y < mh; y++)
        for (int x = 0; x < mw; x++) {
            cu[y * mw + x] = u[(y + h / 4) * w + x + w / 4];
            cp[y * mw + x] = p[(y + h / 4) * w + x + w / 4];
        }
    double corr = correlation(cu, cp, (size_t)mw * mh);
    free(cu);
    free(cp);
    print_message("tile %dx%d: wrap/inside mean step %.3f -> %.3f; correlation %.4f\n", w, h,
                  su.wrap_mean / su.inside_mean, sp.wrap_mean / sp.inside_mean, corr);
    assert_true(su.wrap_mean > 1.5 * su.inside_mean); /* the input does not wrap */
    /* The output wraps with steps like the inside ones: neither a jump nor a
     * flattened seam (a seam of small steps shows as a line under a grazing
     * light). */
    assert_true(sp.wrap_mean <= 1.3 * sp.inside_mean);
    assert_true(sp.wrap_mean >= 0.5 * sp.inside_mean); /* this tile's steps at w/2: 0.56 */
    assert_true(sp.wrap_max <= 1.3 * sp.inside_max);
    assert_true(corr > 0.75);
    /* On a rough (white-noise) surface the steps across the wrap are the
     * inside ones: no flattened seam (Moisan's periodic component gave 0.4
     * to 0.5 here), and the variance is kept. */
    {
        int n = 48 * 40;
        float *r = malloc(sizeof(float) * n), *q = malloc(sizeof(float) * n);
        btf_rng g;
        btf__rng_seed(&g, 11);
        double vr = 0, vq = 0;
        for (int i = 0; i < n; i++)
            r[i] = q[i] = (float)btf__rng_uniform(&g) + 0.01f * (i % 48);
        TU_OK(btf_range_make_periodic(q, 48, 40, &e), &e);
        steps sq = measure_steps(q, 48, 40);
        double mr = 0, mq = 0;
        for (int i = 0; i < n; i++)
            mr += r[i] - 0.01 * (i % 48), mq += q[i];
        mr /= n, mq /= n;
        for (int i = 0; i < n; i++)
            vr += pow(r[i] - 0.01 * (i % 48) - mr, 2), vq += pow(q[i] - mq, 2);
        print_message("white-noise tile: wrap/inside mean step %.3f, variance ratio %.3f\n",
                      sq.wrap_mean / sq.inside_mean, vq / vr);
        assert_true(sq.wrap_mean >= 0.8 * sq.inside_mean && sq.wrap_mean <= 1.25 * sq.inside_mean);
        assert_true(vq / vr > 0.85 && vq / vr < 1.15);
        free(r);
        free(q);
    }
    double mu = 0, mp = 0;
    for (int i = 0; i < w * h; i++)
        mu += u[i], mp += p[i];
    assert_float_equal(mp / (w * h), mu / (w * h), 1e-5);
    free(u);
    free(p);
}

static void periodic_tile_extremes(void **state)
{
    (void)state;
    btf_error e = {0};
    float one = 3.25f;
    TU_OK(btf_range_make_periodic(&one, 1, 1, &e), &e);
    assert_true(one == 3.25f);
    float flat[12];
    for (int i = 0; i < 12; i++)
        flat[i] = -7.5f;
    TU_OK(btf_range_make_periodic(flat, 4, 3, &e), &e);
    for (int i = 0; i < 12; i++)
        assert_float_equal(flat[i], -7.5f, 1e-5);
    float row[5] = {1, 4, 2, 8, 5}; /* 1 x N and N x 1 */
    TU_OK(btf_range_make_periodic(row, 5, 1, &e), &e);
    TU_OK(btf_range_make_periodic(row, 1, 5, &e), &e);
    for (int i = 0; i < 5; i++)
        assert_true(isfinite(row[i]));
    float huge[6] = {FLT_MAX, -FLT_MAX, FLT_MAX, -FLT_MAX, FLT_MAX, FLT_MAX};
    TU_OK(btf_range_make_periodic(huge, 3, 2, &e), &e);
    for (int i = 0; i < 6; i++)
        assert_true(isfinite(huge[i]));
    float bad[2] = {1.0f, NAN};
    assert_int_equal(btf_range_make_periodic(bad, 2, 1, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "expected finite"));
    assert_int_equal(btf_range_make_periodic(bad, 0, 1, &e), BTF_E_ARG);
}

/* ------------------------------------------------------ enlarged map */

static void enlarged_map_wraps(void **state)
{
    (void)state;
    int tw = 24, th = 17;
    float *t = rough_tile(tw, th, 5);
    btf_error e = {0};
    TU_OK(btf_range_make_periodic(t, tw, th, &e), &e);
    btf_model m = tile_model(t, tw, th, 2.0f);
    /* 48 x 34 analysed texels per period: 300 x 200 holds 6 x 6 periods,
     * stretched by 288/300 and 204/200 */
    const int sizes[][2] = {{300, 200}, {48, 34}, {37, 91}, {7, 5}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        btf_image hm, nm;
        TU_OK(btf__range_map(&m, w, h, &hm, &nm, &e), &e);
        assert_int_equal(hm.width, w);
        assert_int_equal(hm.height, h);
        assert_int_equal(hm.channels, 1);
        steps s = measure_steps(hm.data, w, h);
        print_message("%dx%d: wrap step mean %.4f max %.4f; inside mean %.4f max %.4f\n", w, h,
                      s.wrap_mean, s.wrap_max, s.inside_mean, s.inside_max);
        assert_true(s.wrap_max <= s.inside_max);
        assert_true(s.wrap_mean <= 1.25 * s.inside_mean);
        assert_unit_normals(&nm);
        btf_image_free(&hm);
        btf_image_free(&nm);
    }
    btf_model_free(&m);
    free(t);
}

/* At texel 1 (the analysed resolution, format 1.4) the map is quilted, not
 * stretched: away from the blocks' joins every height is one of the
 * measured ones (blocks are copies; near a join they are relaxed, within
 * the measured range: joins_are_relaxed), a map of the tile's own size is
 * the tile itself, and the map is the same for the same seed and another
 * for another seed. */
static void texel_one_is_quilted(void **state)
{
    (void)state;
    int tw = 64, th = 56; /* blocks of 48: positions are drawn, by the seed */
    float *t = rough_tile(tw, th, 8);
    btf_model m = tile_model(t, tw, th, 1.0f);
    btf_image hm, same, again, other;
    btf_error e = {0};
    TU_OK(btf_structure_maps(&m, 2 * tw, 2 * th, 5, &hm, NULL, NULL, &e), &e);
    float lo = t[0], hi = t[0];
    for (int j = 1; j < tw * th; j++)
        lo = fminf(lo, t[j]), hi = fmaxf(hi, t[j]);
    int measured = 0;
    for (int i = 0; i < 2 * tw * 2 * th; i++) {
        int found = 0;
        for (int j = 0; j < tw * th && !found; j++)
            found = hm.data[i] == t[j];
        measured += found;
        assert_true(hm.data[i] >= lo && hm.data[i] <= hi);
    }
    assert_true(measured >= tw * th); /* a quarter: the blocks' inner parts */
    TU_OK(btf_structure_maps(&m, tw, th, 5, &same, NULL, NULL, &e), &e);
    assert_memory_equal(same.data, t, (size_t)tw * th * sizeof(float));
    TU_OK(btf_structure_maps(&m, 2 * tw, 2 * th, 5, &again, NULL, NULL, &e), &e);
    assert_memory_equal(again.data, hm.data, (size_t)2 * tw * 2 * th * sizeof(float));
    /* another seed, another quilt: on a tile without a repeat (this one's
     * sines repeat every 9 and 14 texels, which the lattice of
     * model/structure_lattice.c holds, leaving few blocks to draw from) */
    btf_rng r;
    btf__rng_seed(&r, 9);
    for (int i = 0; i < tw * th; i++)
        m.range[i] = (float)btf__rng_uniform(&r);
    btf_image_free(&hm);
    TU_OK(btf_structure_maps(&m, 2 * tw, 2 * th, 5, &hm, NULL, NULL, &e), &e);
    TU_OK(btf_structure_maps(&m, 2 * tw, 2 * th, 6, &other, NULL, NULL, &e), &e);
    assert_true(memcmp(other.data, hm.data, (size_t)2 * tw * 2 * th * sizeof(float)) != 0);
    btf_image_free(&hm);
    btf_image_free(&same);
    btf_image_free(&again);
    btf_image_free(&other);
    btf_model_free(&m);
    free(t);
}

/* The steepest step between neighbours of a w x h torus. */
static double steepest(const float *t, int w, int h)
{
    steps s = measure_steps(t, w, h);
    return fmax(s.wrap_max, s.inside_max);
}

/* Quilting joins blocks along a minimum-error cut, and where the blocks
 * still differ the heights step: a bright or dark line under grazing light.
 * The joins are relaxed in the gradient domain (model/structure_seams.c):
 * on a smooth tile without a repeat the placed heights step by 5.1 times
 * the tile's steepest step, the relaxed map by 1.24 times (a join's
 * residual step spread over the 9 texels around it); the same seed gives
 * the same heights (texel_one_is_quilted: a tile-sized map is the tile). */
static void joins_are_relaxed(void **state)
{
    (void)state;
    int tw = 96, th = 96, w = 288, h = 288;
    float *t = malloc(sizeof(float) * (size_t)tw * th);
    assert_non_null(t);
    for (int y = 0; y < th; y++)
        for (int x = 0; x < tw; x++)
            t[(size_t)y * tw + x] = (float)(sin(0.37 * x + 0.9 * sin(0.11 * y)) +
                                            cos(0.29 * y + 0.7 * sin(0.13 * x)));
    btf_model m = tile_model(t, tw, th, 1.0f);
    double inside = measure_steps(t, tw, th).inside_max;
    uint16_t *map;
    btf_error e = {0};
    TU_OK(btf__structure_coords(&m, w, h, 3, &map, &e), &e);
    float *placed = malloc(sizeof(float) * (size_t)w * h);
    assert_non_null(placed);
    for (int i = 0; i < w * h; i++)
        placed[i] = t[(size_t)map[2 * i + 1] * tw + map[2 * i]];
    btf_image hm, again;
    TU_OK(btf_structure_maps(&m, w, h, 3, &hm, NULL, NULL, &e), &e);
    print_message("steepest step: tile %.3f, placed %.3f, relaxed %.3f\n", inside,
                  steepest(placed, w, h), steepest(hm.data, w, h));
    assert_true(steepest(placed, w, h) > 3.0 * inside);
    assert_true(steepest(hm.data, w, h) <= 1.3 * inside);
    TU_OK(btf_structure_maps(&m, w, h, 3, &again, NULL, NULL, &e), &e);
    assert_memory_equal(again.data, hm.data, sizeof(float) * (size_t)w * h);
    free(map);
    free(placed);
    btf_image_free(&hm);
    btf_image_free(&again);
    btf_model_free(&m);
    free(t);
}

static void extreme_sizes(void **state)
{
    (void)state;
    int tw = 16, th = 12;
    float *t = rough_tile(tw, th, 11);
    btf_error e = {0};
    TU_OK(btf_range_make_periodic(t, tw, th, &e), &e);
    btf_model m = tile_model(t, tw, th, 2.0f);
    /* 1x1: the tile's average (one pixel spans a whole period) */
    btf_image hm, nm;
    TU_OK(btf__range_map(&m, 1, 1, &hm, &nm, &e), &e);
    double mean = 0;
    for (int i = 0; i < tw * th; i++)
        mean += t[i];
    mean /= tw * th;
    assert_float_equal(hm.data[0], mean, 1e-4);
    assert_true(nm.data[0] == 0.0f && nm.data[1] == 0.0f && nm.data[2] == 1.0f);
    btf_image_free(&hm);
    btf_image_free(&nm);
    /* 4097 x 3: 128 periods across (stretched by 4096/4097), one squeezed
     * period down */
    TU_OK(btf__range_map(&m, 4097, 3, &hm, &nm, &e), &e);
    for (size_t i = 0; i < (size_t)4097 * 3; i++)
        assert_true(isfinite(hm.data[i]));
    steps s = measure_steps(hm.data, 4097, 3);
    assert_true(s.wrap_max <= s.inside_max);
    assert_unit_normals(&nm);
    btf_image_free(&hm);
    btf_image_free(&nm);
    btf_model_free(&m);
    /* heights near FLT_MAX: finite heights and unit normals */
    float huge[4] = {FLT_MAX, -FLT_MAX, -FLT_MAX, FLT_MAX};
    m = tile_model(huge, 2, 2, 1.0f);
    TU_OK(btf__range_map(&m, 13, 7, &hm, &nm, &e), &e);
    for (size_t i = 0; i < 13 * 7; i++)
        assert_true(isfinite(hm.data[i]));
    assert_unit_normals(&nm);
    btf_image_free(&hm);
    btf_image_free(&nm);
    btf_model_free(&m);
    /* a constant tile: a constant map, flat normals; a 1x1 tile too */
    float c[6] = {2.5f, 2.5f, 2.5f, 2.5f, 2.5f, 2.5f};
    for (int k = 0; k < 2; k++) {
        m = tile_model(c, k ? 1 : 3, k ? 1 : 2, 0.75f);
        TU_OK(btf__range_map(&m, 31, 4, &hm, &nm, &e), &e);
        for (size_t i = 0; i < 31 * 4; i++) {
            assert_float_equal(hm.data[i], 2.5f, 1e-6);
            assert_true(nm.data[3 * i] == 0.0f && nm.data[3 * i + 1] == 0.0f &&
                        nm.data[3 * i + 2] == 1.0f);
        }
        btf_image_free(&hm);
        btf_image_free(&nm);
        btf_model_free(&m);
    }
    /* a tiny texel (many periods per pixel) stays bounded and finite */
    m = tile_model(t, tw, th, 1e-30f);
    TU_OK(btf__range_map(&m, 5, 3, &hm, NULL, &e), &e);
    for (int i = 0; i < 15; i++)
        assert_float_equal(hm.data[i], mean, 1e-4);
    btf_image_free(&hm);
    btf_model_free(&m);
    free(t);
}

static void no_range_is_flat(void **state)
{
    (void)state;
    btf_model m = tile_model(NULL, 0, 0, 0.0f);
    btf_image hm, nm;
    btf_error e = {0};
    TU_OK(btf__range_map(&m, 5, 4, &hm, &nm, &e), &e);
    for (int i = 0; i < 20; i++) {
        assert_true(hm.data[i] == 0.0f);
        assert_true(nm.data[3 * i] == 0.0f && nm.data[3 * i + 1] == 0.0f &&
                    nm.data[3 * i + 2] == 1.0f);
    }
    btf_image_free(&hm);
    btf_image_free(&nm);
    TU_OK(btf__range_map(&m, 5, 4, NULL, &nm, &e), &e); /* normals alone */
    assert_int_equal(nm.width, 5);
    btf_image_free(&nm);
}

static void bad_input(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image hm = {0};
    btf_model m = tile_model(NULL, 0, 0, 0.0f);
    assert_int_equal(btf__range_map(&m, 0, 4, &hm, NULL, &e), BTF_E_ARG);
    assert_non_null(strstr(e.msg, "range map: size 0x4"));
    assert_null(hm.data);
    assert_int_equal(btf__range_map(NULL, 4, 4, &hm, NULL, &e), BTF_E_ARG);
    float t[2] = {1.0f, INFINITY};
    m = tile_model(t, 2, 1, 1.0f);
    assert_int_equal(btf__range_map(&m, 4, 4, &hm, NULL, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "expected finite heights"));
    assert_null(hm.data);
    m.range[1] = 0.0f;
    m.range_texel = NAN;
    assert_int_equal(btf__range_map(&m, 4, 4, &hm, NULL, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "texel"));
    btf_model_free(&m);
}

/* ------------------------------------------------------------ normals */

/* h = a x: n = normalize(-a, 0, 1); h = b row (rising down the image, i.e.
 * towards -y): n = normalize(0, b, 1), y being up. Checked away from the
 * wrap columns and rows, where the map does not wrap. */
static void normals_of_known_slopes(void **state)
{
    (void)state;
    const double a = 0.75, b = -2.0;
    btf_image hx, hy, nx, ny;
    btf_error e = {0};
    TU_OK(btf_image_alloc(&hx, 8, 5, 1, &e), &e);
    TU_OK(btf_image_alloc(&hy, 8, 5, 1, &e), &e);
    for (int y = 0; y < 5; y++)
        for (int x = 0; x < 8; x++) {
            hx.data[y * 8 + x] = (float)(a * x);
            hy.data[y * 8 + x] = (float)(b * y);
        }
    TU_OK(btf__normal_map(&hx, 1.0, &nx, &e), &e);
    TU_OK(btf__normal_map(&hy, 1.0, &ny, &e), &e);
    double lx = sqrt(a * a + 1.0), ly = sqrt(b * b + 1.0);
    for (int y = 1; y < 4; y++)
        for (int x = 1; x < 7; x++) {
            const float *p = nx.data + 3 * (y * 8 + x), *q = ny.data + 3 * (y * 8 + x);
            assert_float_equal(p[0], -a / lx, 1e-6);
            assert_float_equal(p[1], 0.0, 1e-6);
            assert_float_equal(p[2], 1.0 / lx, 1e-6);
            assert_float_equal(q[0], 0.0, 1e-6);
            assert_float_equal(q[1], b / ly, 1e-6);
            assert_float_equal(q[2], 1.0 / ly, 1e-6);
        }
    /* the wrap: column 0's left neighbour is column 7 */
    const float *w0 = nx.data + 3 * (2 * 8);
    double d = 0.5 * (a * 1 - a * 7), lw = sqrt(d * d + 1.0);
    assert_float_equal(w0[0], -d / lw, 1e-6);
    btf_image_free(&nx);
    btf_image_free(&ny);
    /* scale: relief x 2 doubles the slope; a huge scale stays finite */
    TU_OK(btf__normal_map(&hx, 2.0, &nx, &e), &e);
    double l2 = sqrt(4 * a * a + 1.0);
    assert_float_equal(nx.data[3 * (2 * 8 + 3)], -2 * a / l2, 1e-6);
    btf_image_free(&nx);
    TU_OK(btf__normal_map(&hx, 1e308, &nx, &e), &e);
    assert_unit_normals(&nx);
    btf_image_free(&nx);
    assert_int_equal(btf__normal_map(&hx, NAN, &nx, &e), BTF_E_ARG);
    assert_int_equal(btf__normal_map(&nx, 1.0, &ny, &e), BTF_E_ARG); /* no height map */
    btf_image_free(&hx);
    btf_image_free(&hy);
}

/* ---------------------------------------------------------------- CLI */

#define OLD_MODEL "tests/data/model-v1.0.btfcar"

/* btfcar synthesise --range writes range.exr and normal.exr beside the
 * subspace images, the same floats btf__range_map gives; --subspace none
 * writes only them. */
static void cli_writes_range_maps(void **state)
{
    (void)state;
    const char *out = tu_fmt("%s/with", tu_dir);
    char *msg = NULL;
    int rc = tu_run(tu_fmt("%s synthesise %s --range --size 70x45 --quiet -o %s", tu_cli(),
                           OLD_MODEL, out), &msg);
    if (rc)
        fail_msg("synthesise --range: %s", msg ? msg : "");
    free(msg);
    btf_model m;
    btf_error e = {0};
    TU_OK(btf_model_read(OLD_MODEL, &m, &e), &e);
    assert_int_equal(tu_count_files(out), m.n_subspaces + 2);
    btf_image want_h, want_n, got_h, got_n;
    TU_OK(btf__range_map(&m, 70, 45, &want_h, &want_n, &e), &e);
    TU_OK(btf_image_read(tu_fmt("%s/range.exr", out), NULL, &got_h, &e), &e);
    TU_OK(btf_image_read(tu_fmt("%s/normal.exr", out), NULL, &got_n, &e), &e);
    assert_int_equal(got_h.channels, 1);
    assert_int_equal(got_n.channels, 3);
    assert_int_equal(got_h.width, 70);
    assert_int_equal(got_h.height, 45);
    assert_memory_equal(got_h.data, want_h.data, sizeof(float) * 70 * 45);
    assert_memory_equal(got_n.data, want_n.data, sizeof(float) * 70 * 45 * 3);
    btf_image_free(&got_h);
    btf_image_free(&got_n);
    const char *only = tu_fmt("%s/only", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s synthesise %s --range --subspace none --size 70x45 "
                                   "--quiet -o %s", tu_cli(), OLD_MODEL, only), NULL), 0);
    assert_int_equal(tu_count_files(only), 2);
    TU_OK(btf_image_read(tu_fmt("%s/range.exr", only), NULL, &got_h, &e), &e);
    assert_memory_equal(got_h.data, want_h.data, sizeof(float) * 70 * 45);
    btf_image_free(&got_h);
    btf_image_free(&want_h);
    btf_image_free(&want_n);
    btf_model_free(&m);
}

/* A model without a range map: --range is a one-line error naming the
 * model, and no output folder is left; --subspace none alone is a usage
 * error. */
static void cli_range_errors(void **state)
{
    (void)state;
    btf_model m;
    btf_error e = {0};
    TU_OK(btf_model_read(OLD_MODEL, &m, &e), &e);
    free(m.range);
    m.range = NULL;
    m.range_width = m.range_height = 0;
    char *model = strdup(tu_fmt("%s/norange.btfcar", tu_dir));
    TU_OK(btf_model_write(model, &m, &e), &e);
    btf_model_free(&m);
    const char *out = tu_fmt("%s/none", tu_dir);
    char *msg = NULL;
    int rc = tu_run(tu_fmt("%s synthesise %s --range --size 8x8 -o %s", tu_cli(), model, out),
                    &msg);
    assert_int_equal(rc, 1);
    assert_non_null(msg);
    assert_non_null(strstr(msg, model));
    assert_non_null(strstr(msg, "no range map"));
    assert_int_equal(count_lines(msg), 1);
    free(msg);
    assert_int_equal(tu_count_files(out), 0);
    rc = tu_run(tu_fmt("%s synthesise %s --subspace none --size 8x8 -o %s", tu_cli(), OLD_MODEL,
                       out), &msg);
    assert_int_equal(rc, 2);
    assert_non_null(strstr(msg, "--subspace none"));
    free(msg);
    free(model);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(periodic_tile_keeps_content),
        cmocka_unit_test(periodic_tile_extremes),
        cmocka_unit_test(enlarged_map_wraps),
        cmocka_unit_test(texel_one_is_quilted),
        cmocka_unit_test(joins_are_relaxed),
        cmocka_unit_test(extreme_sizes),
        cmocka_unit_test(no_range_is_flat),
        cmocka_unit_test(bad_input),
        cmocka_unit_test(normals_of_known_slopes),
        cmocka_unit_test(cli_writes_range_maps),
        cmocka_unit_test(cli_range_errors),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
