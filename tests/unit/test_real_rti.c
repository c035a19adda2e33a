/* test_real_rti.c — RTI light files (.lp, layout BTF_LAYOUT_RTI,
 * src/dataset/rti_lp.c) and the real light-dome capture
 * tests/data/real/rti-lion: the parser's directions and every refused input;
 * the frame of the light vectors against a procedural material's truth; the
 * lion head through `btfcar info`, `photostereo`, `analyse` and `synthesise`,
 * and the reflectance-field family's report with lights held out of its fit.
 *
 * The captures are read from $BTF_TEST_DATA/real (default tests/data/real:
 * `make test` runs the programs from the repository root, as a clean clone
 * in CI does). */
#include "testutil.h"

#include "dataset/dataset.h"
#include "io/io.h"
#include "range/range.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *real_dir(void)
{
    const char *d = getenv("BTF_TEST_DATA");
    return d && *d ? tu_fmt("%s/real", d) : "tests/data/real";
}

static const char *lion_lp(void)
{
    return tu_fmt("%s/rti-lion/dirs.lp", real_dir());
}

/* A W x H grey PNG of value v at dir/name. */
static void write_png(const char *path, int w, int h, float v)
{
    btf_image img;
    btf_error e = {0};
    TU_OK(btf_image_alloc(&img, w, h, 3, &e), &e);
    for (int i = 0; i < w * h * 3; i++)
        img.data[i] = v;
    TU_OK(btf_image_write_png(path, &img, &e), &e);
    btf_image_free(&img);
}

static void write_text(const char *path, const char *text)
{
    tu_write_file(path, text, strlen(text));
}

/* ------------------------------------------------------------ the parser */

/* Directions from the vectors (btfcar's frame: x right, y up, z to the
 * camera), paths beside the file and with blanks in them, CRLF line ends,
 * blank lines, no final newline, a length off 1 by under 1 %. */
static void lp_directions(void **state)
{
    (void)state;
    const char *dir = tu_fmt("%s/good", tu_dir);
    char d[4096];
    snprintf(d, sizeof d, "%s", dir);
    mkdir(d, 0777);
    mkdir(tu_fmt("%s/img", d), 0777);
    const char *names[5] = {"img/a.png", "img/b b.png", "c.png", "img/d.png", "e.png"};
    for (int i = 0; i < 5; i++)
        write_png(tu_fmt("%s/%s", d, names[i]), 6, 4, 0.1f * (float)(i + 1));
    double s60 = sqrt(3.0) / 2.0;
    char text[1024];
    snprintf(text, sizeof text,
             "5\r\n"
             "img/a.png 0 0 1.005\r\n"              /* the pole, 0.5 % long */
             "\r\n"
             "  img/b b.png\t%.9f 0 0.5 \r\n"       /* theta 60, phi 0 (image right) */
             "c.png 0 %.9f %.9f\n"                  /* theta 30, phi 90 (image top) */
             "img/d.png -0.5 0 %.9f\n"              /* theta 30, phi 180 (image left) */
             "e.png 0 -0.5 %.9f",                   /* theta 30, phi 270 (image bottom) */
             s60, 0.5, s60, s60, s60);
    write_text(tu_fmt("%s/lights.LP", d), text);
    btf_dataset *ds;
    btf_error e = {0};
    TU_OK(btf_dataset_open(tu_fmt("%s/lights.LP", d), NULL, &ds, &e), &e);
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    assert_int_equal(in->layout, BTF_LAYOUT_RTI);
    assert_string_equal(btf_layout_name(in->layout), "RTI");
    assert_int_equal(in->n_views, 1);
    assert_int_equal(in->n_lights, 5);
    assert_true(in->views->dirs[0].theta == 0.0);
    assert_int_equal(in->width, 6);
    static const double want[5][2] = {{0, 0}, {60, 0}, {30, 90}, {30, 180}, {30, 270}};
    for (int i = 0; i < 5; i++) {
        btf_dir want_dir = {want[i][0], want[i][1]};
        int li = btf_dirset_find(in->lights, want_dir, 1e-6);
        assert_true(li >= 0);
        const char *p = btf_dataset_path(ds, 0, li);
        assert_string_equal(p, tu_fmt("%s/%s", d, names[i]));
        /* the vector comes back (normalised) */
        double v[3];
        btf_dir_to_vec(in->lights->dirs[li], v);
        assert_true(fabs(hypot(hypot(v[0], v[1]), v[2]) - 1.0) < 1e-12);
    }
    btf_dataset_close(ds);

    /* The parser on a buffer, files not checked: absolute paths are kept. */
    btf_dataset_entries l;
    const char *buf = "2\n/abs/x.png 1 0 0.0001\nrel.png 0.6 0 0.8\n";
    TU_OK(btf__rti_lp_parse(buf, strlen(buf), "mem", "/base", 0, &l, &e), &e);
    assert_int_equal(l.count, 2);
    assert_int_equal(l.layout, BTF_LAYOUT_RTI);
    assert_string_equal(l.items[0].path, "/abs/x.png");
    assert_string_equal(l.items[1].path, "/base/rel.png");
    assert_true(fabs(l.items[1].light.theta - acos(0.8) * 180.0 / M_PI) < 1e-9);
    assert_true(l.items[1].light.phi == 0.0);
    btf__dataset_entries_free(&l);
    assert_int_equal(btf__rti_lp_name("x/dirs.lp"), 1);
    assert_int_equal(btf__rti_lp_name("x/dirs.LP"), 1);
    assert_int_equal(btf__rti_lp_name("x/.lp"), 0);
    assert_int_equal(btf__rti_lp_name("x/dirs.lpx"), 0);
    assert_int_equal(btf__rti_lp_name("x/manifest.tsv"), 0);
}

/* Opening text as tu_dir/bad/bad.lp (images a.png, b.png, c.png beside it)
 * fails with code and one line "PATH:LINE: ..." containing what. */
static void expect_lp_fails(const char *text, int code, int line, const char *what)
{
    const char *p = tu_fmt("%s/bad/bad.lp", tu_dir);
    char path[4096];
    snprintf(path, sizeof path, "%s", p);
    write_text(path, text);
    btf_dataset *ds = NULL;
    btf_error e = {0};
    int rc = btf_dataset_open(path, NULL, &ds, &e);
    if (rc != code || !strstr(e.msg, what) || strchr(e.msg, '\n') ||
        strncmp(e.msg, tu_fmt("%s:%d: ", path, line), strlen(tu_fmt("%s:%d: ", path, line))))
        print_error("text:\n%s\ngot %d '%s', want %d, line %d, '%s'\n", text, rc, e.msg, code, line,
                    what);
    assert_int_equal(rc, code);
    assert_null(ds);
    assert_non_null(strstr(e.msg, what));
    assert_null(strchr(e.msg, '\n'));
    assert_memory_equal(e.msg, tu_fmt("%s:%d: ", path, line), strlen(tu_fmt("%s:%d: ", path, line)));
}

static void lp_errors(void **state)
{
    (void)state;
    const char *bad = tu_fmt("%s/bad", tu_dir);
    char d[4096];
    snprintf(d, sizeof d, "%s", bad);
    mkdir(d, 0777);
    write_png(tu_fmt("%s/a.png", d), 4, 4, 0.2f);
    write_png(tu_fmt("%s/b.png", d), 4, 4, 0.4f);
    write_png(tu_fmt("%s/c.png", d), 4, 4, 0.6f);
    mkdir(tu_fmt("%s/folder.png", d), 0777);
    /* the count */
    expect_lp_fails("", BTF_E_FORMAT, 1, "no image count");
    expect_lp_fails("\n\n", BTF_E_FORMAT, 2, "no image count");
    expect_lp_fails("three\na.png 0 0 1\n", BTF_E_FORMAT, 1, "bad image count 'three'");
    expect_lp_fails("0\n", BTF_E_FORMAT, 1, "bad image count '0'");
    expect_lp_fails("-1\na.png 0 0 1\n", BTF_E_FORMAT, 1, "bad image count");
    expect_lp_fails("1 2\na.png 0 0 1\n", BTF_E_FORMAT, 1, "bad image count");
    expect_lp_fails("1.5\na.png 0 0 1\n", BTF_E_FORMAT, 1, "bad image count");
    expect_lp_fails("99999999999999999999\na.png 0 0 1\n", BTF_E_FORMAT, 1, "bad image count");
    /* fewer or more lines than the count */
    expect_lp_fails("3\na.png 0 0 1\nb.png 0.6 0 0.8\n\n", BTF_E_FORMAT, 4,
                    "2 image lines, fewer than the count 3 of line 1");
    expect_lp_fails("1\na.png 0 0 1\nb.png 0.6 0 0.8\n", BTF_E_FORMAT, 3,
                    "more image lines than the count 1 of line 1");
    /* the line's fields */
    expect_lp_fails("2\na.png 0 0 1\n0.6 0 0.8\n", BTF_E_FORMAT, 3, "expected 'PATH X Y Z'");
    expect_lp_fails("1\na.png 0 1\n", BTF_E_FORMAT, 2, "expected 'PATH X Y Z'");
    expect_lp_fails("1\na.png\n", BTF_E_FORMAT, 2, "expected 'PATH X Y Z'");
    /* non-finite or not a number */
    expect_lp_fails("1\na.png nan 0 1\n", BTF_E_FORMAT, 2, "X 'nan' is not a finite decimal");
    expect_lp_fails("1\na.png 0 inf 1\n", BTF_E_FORMAT, 2, "Y 'inf' is not a finite decimal");
    expect_lp_fails("1\na.png 0 0 1e999\n", BTF_E_FORMAT, 2, "Z '1e999' is not a finite");
    expect_lp_fails("1\na.png 0x0 0 1\n", BTF_E_FORMAT, 2, "X '0x0' is not a finite");
    expect_lp_fails("1\na.png 0 0 1,0\n", BTF_E_FORMAT, 2, "Z '1,0' is not a finite");
    /* not a unit vector (1 % allowed), below the surface */
    expect_lp_fails("2\na.png 0 0 1\nb.png 0 0 1.02\n", BTF_E_DATA, 3, "has length 1.02, not 1");
    expect_lp_fails("1\na.png 0.3 0.4 0.5\n", BTF_E_DATA, 2, "not 1 (within 1 %)");
    expect_lp_fails("1\na.png 0 0 0\n", BTF_E_DATA, 2, "has length 0");
    expect_lp_fails("1\na.png 1 0 0\n", BTF_E_DATA, 2, "Z <= 0: a light below the surface");
    expect_lp_fails("1\na.png 0.6 0 -0.8\n", BTF_E_DATA, 2, "a light below the surface");
    /* the images */
    expect_lp_fails("2\na.png 0 0 1\nmissing.png 0.6 0 0.8\n", BTF_E_IO, 3,
                    "bad/missing.png: No such file or directory");
    expect_lp_fails("1\nfolder.png 0 0 1\n", BTF_E_IO, 2, "folder.png: not a regular file");
    expect_lp_fails("3\na.png 0 0 1\nb.png 0.6 0 0.8\na.png 0 0.6 0.8\n", BTF_E_DATA, 4,
                    "a.png is listed again (first on line 2)");
    {
        const char nul[] = "2\na.png 0 0 1\nb.png\0 0.6 0 0.8\n";
        const char *p = tu_fmt("%s/bad.lp", d);
        tu_write_file(p, nul, sizeof nul - 1);
        btf_dataset *ds = NULL;
        btf_error e = {0};
        assert_int_equal(btf_dataset_open(p, NULL, &ds, &e), BTF_E_FORMAT);
        assert_non_null(strstr(e.msg, "bad.lp:3: a NUL byte"));
    }
    /* Two lights in one direction: two images of one pair (dataset/dataset.c). */
    {
        const char *p = tu_fmt("%s/bad.lp", d);
        write_text(p, "2\na.png 0 0 1\nb.png 0 0 1\n");
        btf_dataset *ds = NULL;
        btf_error e = {0};
        assert_int_equal(btf_dataset_open(p, NULL, &ds, &e), BTF_E_DATA);
        assert_non_null(strstr(e.msg, "second file"));
    }
    /* Images of two sizes (dataset/dataset.c's check, as for every layout). */
    write_png(tu_fmt("%s/big.png", d), 5, 4, 0.5f);
    {
        const char *p = tu_fmt("%s/bad.lp", d);
        write_text(p, "2\na.png 0 0 1\nbig.png 0.6 0 0.8\n");
        btf_dataset *ds = NULL;
        btf_error e = {0};
        assert_int_equal(btf_dataset_open(p, NULL, &ds, &e), BTF_E_DATA);
        assert_non_null(strstr(e.msg, "big.png: size 5x4 differs"));
    }
}

/* The command names the file and line, one line, and fails. */
static void lp_error_through_cli(void **state)
{
    (void)state;
    const char *d = tu_fmt("%s/cli", tu_dir);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", d);
    mkdir(dir, 0777);
    write_text(tu_fmt("%s/dirs.lp", dir), "1\nnone.jpg 0 0 1\n");
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s info %s/dirs.lp", tu_cli(), dir), &err);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(err, tu_fmt("%s/dirs.lp:2: ", dir)));
    assert_non_null(strstr(err, "none.jpg"));
    char *nl = strchr(err, '\n');
    assert_true(nl == NULL || nl[1] == '\0');
    free(err);
}

/* ------------------------------------------- the frame against a truth */

static double angle_deg(const float *a, const float *b)
{
    double d = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
    return acos(d > 1.0 ? 1.0 : d < -1.0 ? -1.0 : d) * 180.0 / M_PI;
}

/* A procedural material rendered under the ubo81 lights from above (view
 * theta 0), written as PNGs with an .lp file of the lights' vectors: the
 * normals photometric stereo recovers from the .lp match the material's
 * truth. The same images with the vectors' x negated (a light from the
 * image's right read as one from its left) do not: the frame is checked,
 * not only the parser. */
static void lp_frame_matches_truth(void **state)
{
    (void)state;
    const int n = 32;
    btf_error e = {0};
    btf_procedural m;
    TU_OK(btf_procedural_make("leather", n, 5, &m, &e), &e);
    btf_dirset lights;
    TU_OK(btf_dirset_ubo81(&lights, &e), &e);
    const char *d0 = tu_fmt("%s/truth", tu_dir);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", d0);
    mkdir(dir, 0777);
    mkdir(tu_fmt("%s/images", dir), 0777);
    size_t cap = 64 * (size_t)lights.count + 16, len[2] = {0, 0};
    char *text[2] = {malloc(cap), malloc(cap)};
    for (int k = 0; k < 2; k++)
        len[k] = (size_t)snprintf(text[k], cap, "%d\n", lights.count);
    for (int i = 0; i < lights.count; i++) {
        btf_image img;
        btf_dir view = {0, 0};
        TU_OK(btf_procedural_render(&m, view, lights.dirs[i], &img, &e), &e);
        TU_OK(btf_image_write_png(tu_fmt("%s/images/light %02d.png", dir, i), &img, &e), &e);
        btf_image_free(&img);
        double v[3];
        btf_dir_to_vec(lights.dirs[i], v);
        for (int k = 0; k < 2; k++)
            len[k] += (size_t)snprintf(text[k] + len[k], cap - len[k],
                                       "images/light %02d.png %.9f %.9f %.9f\n", i,
                                       k ? -v[0] : v[0], v[1], v[2]);
    }
    double err[2];
    for (int k = 0; k < 2; k++) {
        const char *lp = tu_fmt("%s/%s.lp", dir, k ? "mirrored" : "lights");
        char path[4096];
        snprintf(path, sizeof path, "%s", lp);
        tu_write_file(path, text[k], len[k]);
        btf_dataset *ds;
        TU_OK(btf_dataset_open(path, NULL, &ds, &e), &e);
        assert_int_equal(btf_dataset_get_info(ds)->n_lights, lights.count);
        btf_photostereo_opts o = btf_photostereo_defaults();
        btf_ps_result r;
        TU_OK(btf__photostereo_dataset(ds, &o, &r, &e), &e);
        double s = 0.0;
        for (int p = 0; p < n * n; p++)
            s += angle_deg(r.normal.data + 3 * p, m.normal + 3 * p);
        err[k] = s / (n * n);
        btf_ps_result_free(&r);
        btf_dataset_close(ds);
        free(text[k]);
    }
    print_message("leather %dx%d from an .lp: mean normal error %.2f deg; x mirrored %.2f deg\n",
                  n, n, err[0], err[1]);
    assert_true(err[0] < 3.0);
    assert_true(err[1] > 10.0);
    btf_dirset_free(&lights);
    btf_procedural_free(&m);
}

/* ------------------------------------------------- the real lion head */

static void read_exr(const char *path, int channels, btf_image *img)
{
    btf_error e = {0};
    btf_read_opts ro = btf_read_defaults();
    ro.channels = channels;
    TU_OK(btf_image_read(path, &ro, img, &e), &e);
    for (size_t i = 0; i < (size_t)img->width * img->height * img->channels; i++)
        assert_true(isfinite(img->data[i]));
}

static void lion_info(void **state)
{
    (void)state;
    int st;
    char *out = tu_capture(tu_fmt("%s info %s", tu_cli(), lion_lp()), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "layout      RTI\n"));
    assert_non_null(strstr(out, "images      240 (1 views x 240 lights)"));
    assert_non_null(strstr(out, "image size  64 x 43, 3 channels, JPEG"));
    free(out);
}

/* `btfcar photostereo` on the lion: normals unit and finite, their mean near
 * +z, varied (a relief, not a flat plate), pointing away from the middle
 * (a raised head: the light frame's x and y are the image's right and top);
 * the range map higher in the middle than at the edges. */
static void lion_photostereo(void **state)
{
    (void)state;
    const char *out = tu_fmt("%s/lion-ps", tu_dir);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", out);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s photostereo %s -o %s --quiet", tu_cli(), lion_lp(), dir), &err);
    if (rc)
        print_error("%s", err);
    free(err);
    assert_int_equal(rc, 0);
    btf_image nm, h;
    read_exr(tu_fmt("%s/normals.exr", dir), 3, &nm);
    read_exr(tu_fmt("%s/height.exr", dir), 1, &h);
    int w = nm.width, ht = nm.height, np = w * ht;
    assert_int_equal(w, 64);
    assert_int_equal(ht, 43);
    double mean[3] = {0, 0, 0}, tilted = 0.0, outward = 0.0;
    double cx = (w - 1) / 2.0, cy = (ht - 1) / 2.0;
    int far = 0;
    for (int p = 0; p < np; p++) {
        const float *v = nm.data + 3 * p;
        assert_true(fabs(hypot(hypot(v[0], v[1]), v[2]) - 1.0) < 1e-3);
        for (int c = 0; c < 3; c++)
            mean[c] += v[c];
        if (v[2] < cos(20.0 * M_PI / 180.0))
            tilted++;
        /* the normal's tilt along the way out of the middle (y up: rows down) */
        double dx = p % w - cx, dy = cy - p / w, r = hypot(dx, dy);
        if (r > 4.0) {
            outward += (v[0] * dx + v[1] * dy) / r;
            far++;
        }
    }
    double ml = hypot(hypot(mean[0], mean[1]), mean[2]);
    double mz = mean[2] / ml;
    tilted /= np;
    outward /= far;
    /* the range map: the middle third against a frame 3 pixels wide */
    double mid = 0.0, edge = 0.0;
    int nmid = 0, nedge = 0;
    for (int y = 0; y < ht; y++)
        for (int x = 0; x < w; x++) {
            float v = h.data[y * w + x];
            if (x >= w / 3 && x < 2 * w / 3 && y >= ht / 3 && y < 2 * ht / 3)
                mid += v, nmid++;
            if (x < 3 || y < 3 || x >= w - 3 || y >= ht - 3)
                edge += v, nedge++;
        }
    mid /= nmid;
    edge /= nedge;
    print_message("lion: mean normal z %.4f, %.0f %% tilted > 20 deg, outward tilt %.3f, "
                  "height middle %.2f edge %.2f px\n", mz, 100.0 * tilted, outward, mid, edge);
    assert_true(mz > 0.95);      /* the mean normal near +z */
    assert_true(tilted > 0.15);  /* a relief, not flat */
    assert_true(outward > 0.1); /* normals lean away from the middle: raised (x or y
                                 * of the lights mirrored: about 0.01 or -0.01) */
    assert_true(mid > edge + 3.0); /* mirrored: +-1.3 */
    btf_image_free(&nm);
    btf_image_free(&h);
    /* the previews decode, at the image's size */
    static const char *png[3] = {"normals.png", "albedo.png", "height.png"};
    for (int i = 0; i < 3; i++) {
        btf_image img;
        btf_error e = {0};
        TU_OK(btf_image_read(tu_fmt("%s/%s", dir, png[i]), NULL, &img, &e), &e);
        assert_int_equal(img.width, 64);
        assert_int_equal(img.height, 43);
        btf_image_free(&img);
    }
}

/* `btfcar analyse` of the lion makes a model that `btfcar info` reads and
 * `btfcar synthesise` turns into a finite, non-constant image. (Its renders
 * are looked at in docs/examples/rti-lion/; the report of the pixel-wise
 * family renders the capture in lion_rf_held_out.) */
static void lion_analyse_synthesise(void **state)
{
    (void)state;
    const char *mp = tu_fmt("%s/lion.btfcar", tu_dir);
    char model[4096];
    snprintf(model, sizeof model, "%s", mp);
    char *err = NULL;
    int rc = tu_run(tu_fmt("%s analyse %s -o %s --quiet", tu_cli(), lion_lp(), model), &err);
    if (rc)
        print_error("%s", err);
    free(err);
    assert_int_equal(rc, 0);
    int st;
    char *out = tu_capture(tu_fmt("%s info %s", tu_cli(), model), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "1 views x 240 lights"));
    assert_non_null(strstr(out, "range map   64 x 43"));
    free(out);
    const char *sp = tu_fmt("%s/lion-synth", tu_dir);
    char synth[4096];
    snprintf(synth, sizeof synth, "%s", sp);
    rc = tu_run(tu_fmt("%s synthesise %s --size 96x64 --subspace 0 --backend cpu -o %s --quiet",
                       tu_cli(), model, synth),
                &err);
    if (rc)
        print_error("%s", err);
    free(err);
    assert_int_equal(rc, 0);
    btf_image img;
    read_exr(tu_fmt("%s/subspace_00.exr", synth), 3, &img);
    assert_int_equal(img.width, 96);
    assert_int_equal(img.height, 64);
    float lo = img.data[0], hi = img.data[0];
    for (int i = 0; i < 96 * 64 * 3; i++)
        lo = fminf(lo, img.data[i]), hi = fmaxf(hi, img.data[i]);
    assert_true(hi > lo + 0.01f);
    btf_image_free(&img);
}

/* A copy of the lion's light file in dir without the lights on lines
 * i % 10 == 5 (i from 0, after the count): 24 of the 240 held out; image
 * paths made absolute so that the copy reads the capture's JPEGs. */
static const char *write_held_out_lp(const char *dir)
{
    size_t n;
    unsigned char *raw = tu_slurp(lion_lp(), &n);
    assert_non_null(raw);
    char *text = malloc(n + 1); /* the bytes as a string */
    assert_non_null(text);
    memcpy(text, raw, n);
    text[n] = '\0';
    free(raw);
    char base[4096];
    assert_non_null(realpath(lion_lp(), base));
    *strrchr(base, '/') = '\0';
    const char *path = tu_fmt("%s/held-out.lp", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "216\n");
    int i = -1; /* the count's line is -1 */
    for (char *line = strtok(text, "\r\n"); line; line = strtok(NULL, "\r\n"), i++)
        if (i >= 0 && i % 10 != 5)
            fprintf(f, "%s/%s\n", base, line);
    fclose(f);
    free(text);
    return path;
}

static double json_number(const cJSON *o, const char *name)
{
    const cJSON *v = cJSON_GetObjectItem(o, name);
    assert_non_null(v);
    return v->valuedouble;
}

/* Runs cmd; on failure prints its standard error and fails the test. */
static void run_ok(const char *cmd)
{
    char *err = NULL;
    int rc = tu_run(cmd, &err);
    if (rc)
        print_error("%s", err);
    free(err);
    assert_int_equal(rc, 0);
}

/* Analyses lp (with the extra options) into dir/name.btfcar, reports the
 * whole capture against it with every pair into dir/name-report, and
 * returns the parsed report.json (cJSON_Delete it). */
static cJSON *lion_analyse_report(const char *dir, const char *lp, const char *name,
                                  const char *opts)
{
    char model[4096], rep[4096];
    snprintf(model, sizeof model, "%s/%s.btfcar", dir, name);
    snprintf(rep, sizeof rep, "%s/%s-report", dir, name);
    run_ok(tu_fmt("%s analyse %s %s -o %s --quiet", tu_cli(), lp, opts, model));
    run_ok(tu_fmt("%s report %s %s --all -o %s --quiet", tu_cli(), lion_lp(), model, rep));
    size_t n;
    unsigned char *text = tu_slurp(tu_fmt("%s/report.json", rep), &n);
    assert_non_null(text);
    cJSON *j = cJSON_ParseWithLength((const char *)text, n);
    free(text);
    assert_non_null(j);
    return j;
}

/* The pixel-wise family on the lion with 24 of its lights held out of the
 * fit: the report of the whole capture measures those pairs apart (the RF
 * model renders them at their exact lights), its Table 1 error over the
 * fitted images only; a light of the model that the dataset lacks is an
 * error naming it. Measured (2026-12-05): mean |dY| 0.0127 over the fitted
 * images, 0.0124 over the held-out pairs; the bound leaves room. */
static void lion_rf_held_out(void **state)
{
    (void)state;
    char dir[4096], lp[4096];
    snprintf(dir, sizeof dir, "%s/lion-rf", tu_dir);
    assert_int_equal(mkdir(dir, 0755), 0);
    snprintf(lp, sizeof lp, "%s", write_held_out_lp(dir));
    cJSON *j = lion_analyse_report(dir, lp, "lion-rf", "--family rf");
    const cJSON *q = cJSON_GetObjectItem(j, "quality");
    const cJSON *pw = cJSON_GetObjectItem(j, "pixelwise");
    assert_non_null(q);
    assert_non_null(pw);
    assert_int_equal((int)json_number(q, "held_out"), 24);
    const cJSON *pairs = cJSON_GetObjectItem(q, "pairs_measured");
    assert_int_equal(cJSON_GetArraySize(pairs), 240);
    int held = 0;
    double held_dy = 0.0;
    const cJSON *p;
    cJSON_ArrayForEach(p, pairs) {
        double dy = json_number(p, "mean_abs_dy");
        assert_true(isfinite(dy) && dy >= 0.0 && isfinite(json_number(p, "combined")));
        if (cJSON_IsTrue(cJSON_GetObjectItem(p, "held_out"))) {
            /* the held-out lines: light indices are sorted by theta, so
             * check the count and the mean rather than which ones */
            held++;
            held_dy += dy;
        }
    }
    assert_int_equal(held, 24);
    double fitted = json_number(pw, "mean_abs_dy");
    double luminance = json_number(pw, "mean_luminance");
    print_message("lion, rf: mean |dY| %.5f over the fitted images, %.5f over the 24 held-out "
                  "pairs (mean luminance %.4f); combined %.3f fitted, %.3f held out\n", fitted,
                  held_dy / held, luminance, json_number(q, "mean_combined"),
                  json_number(q, "mean_held_out"));
    assert_true(fabs(held_dy / held - json_number(q, "mean_held_out_abs_dy")) < 1e-12);
    /* interpolating to an unseen light costs little for a relief under a
     * dense dome: within 1.5x the fitted images' error */
    assert_true(fitted > 0.0 && held_dy / held < 1.5 * fitted);
    cJSON_Delete(j);

    /* the other way round: the whole capture's model against the held-out
     * set, which lacks 24 of the model's lights */
    const char *full = tu_fmt("%s/lion-all.btfcar", dir);
    char fullp[4096];
    snprintf(fullp, sizeof fullp, "%s", full);
    run_ok(tu_fmt("%s analyse %s --family rf -o %s --quiet", tu_cli(), lion_lp(), fullp));
    int st;
    char *out = tu_capture(tu_fmt("%s report %s %s -o %s/report-2 --quiet 2>&1", tu_cli(), lp,
                                  fullp, dir), &st);
    assert_int_not_equal(st, 0);
    assert_non_null(strstr(out, "reflectance-field model's light"));
    assert_non_null(strstr(out, "is not one of dataset"));
    free(out);
    struct stat sb;
    assert_int_equal(stat(tu_fmt("%s/report-2", dir), &sb), -1);
}

/* The report's pixel-wise |dY| of one model of the lion (analysed from the
 * held-out light file with the extra options), over the measured and the
 * held-out pairs; its mean combined distance too. */
static void lion_report_dy(const char *dir, const char *lp, const char *name, const char *opts,
                           double *dy, double *held_dy, double *combined)
{
    cJSON *j = lion_analyse_report(dir, lp, name, opts);
    const cJSON *q = cJSON_GetObjectItem(j, "quality");
    const cJSON *pw = cJSON_GetObjectItem(j, "pixelwise"); /* the RF family's */
    assert_non_null(q);
    *dy = pw ? json_number(pw, "mean_abs_dy") : json_number(q, "mean_abs_dy");
    *held_dy = json_number(q, "mean_held_out_abs_dy");
    *combined = json_number(q, "mean_combined");
    const cJSON *p;
    cJSON_ArrayForEach(p, cJSON_GetObjectItem(q, "pairs_measured")) {
        double v = json_number(p, "mean_abs_dy");
        assert_true(isfinite(v) && v >= 0.0);
    }
    assert_true(isfinite(*dy) && *dy > 0.0 && isfinite(*held_dy) && *held_dy > 0.0);
    cJSON_Delete(j);
}

/* On an object the layout is the appearance: the report's pixel-wise |dY|
 * ranks the lion's models as the eye does (docs/examples/rti-lion/): the
 * reflectance field, then the CAR model with its registered structure
 * layer, then the CAR model without it, at the fitted and at the held-out
 * lights; the texture distances, which need no pixel correspondence, rank
 * the last two the other way, which is why the figure is there. Measured
 * (2026-12-05): |dY| 0.0127 / 0.0337 / 0.0473 fitted, 0.0124 / 0.0306 /
 * 0.0418 held out; combined 0.88 / 1.34 / 1.29. */
static void lion_pixelwise_ranks_as_the_eye(void **state)
{
    (void)state;
    char dir[4096], lp[4096];
    snprintf(dir, sizeof dir, "%s/lion-dy", tu_dir);
    assert_int_equal(mkdir(dir, 0755), 0);
    snprintf(lp, sizeof lp, "%s", write_held_out_lp(dir));
    double rf[3], car[3], flat[3];
    lion_report_dy(dir, lp, "rf", "--family rf", &rf[0], &rf[1], &rf[2]);
    lion_report_dy(dir, lp, "car", "", &car[0], &car[1], &car[2]);
    lion_report_dy(dir, lp, "flat", "--no-structure", &flat[0], &flat[1], &flat[2]);
    print_message("lion |dY| fitted / held out: rf %.4f / %.4f, car %.4f / %.4f, car without "
                  "structure %.4f / %.4f; combined %.2f, %.2f, %.2f\n", rf[0], rf[1], car[0],
                  car[1], flat[0], flat[1], rf[2], car[2], flat[2]);
    for (int k = 0; k < 2; k++) {
        assert_true(rf[k] < car[k]);
        assert_true(car[k] < flat[k]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lp_directions),
        cmocka_unit_test(lp_errors),
        cmocka_unit_test(lp_error_through_cli),
        cmocka_unit_test(lp_frame_matches_truth),
        cmocka_unit_test(lion_info),
        cmocka_unit_test(lion_photostereo),
        cmocka_unit_test(lion_analyse_synthesise),
        cmocka_unit_test(lion_rf_held_out),
        cmocka_unit_test(lion_pixelwise_ranks_as_the_eye),
    };
    return cmocka_run_group_tests_name("real_rti", tests, tu_setup_dir, tu_teardown_dir);
}
