/* test_cli.c — the btfcar command end to end: generate, info, errors. */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>


static void help_and_version(void **state)
{
    (void)state;
    int st;
    char *out = tu_capture(tu_fmt("%s --help", tu_cli()), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "generate"));
    free(out);
    out = tu_capture(tu_fmt("%s --version", tu_cli()), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, BTF_VERSION_STRING));
    free(out);
    const char *cmds[] = {"generate", "info"};
    for (int i = 0; i < 2; i++) {
        out = tu_capture(tu_fmt("%s %s --help", tu_cli(), cmds[i]), &st);
        assert_int_equal(st, 0);
        assert_non_null(strstr(out, "usage: btfcar"));
        free(out);
    }
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s frobnicate", tu_cli()), &err), 2);
    assert_non_null(strstr(err, "unknown command"));
    free(err);
}

static void generate_then_info(void **state)
{
    (void)state;
    char out[4096];
    snprintf(out, sizeof out, "%s/leather", tu_dir);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s generate --quiet --material leather --size 16 --seed 7 %s",
                                   tu_cli(), out), &err), 0);
    free(err);
    assert_int_equal(tu_count_files(out), 6561 + 3);
    struct stat st;
    assert_int_equal(stat(tu_fmt("%s/truth/height.exr", out), &st), 0);
    assert_int_equal(stat(tu_fmt("%s/truth/normals.exr", out), &st), 0);
    assert_int_equal(stat(tu_fmt("%s/truth/albedo.exr", out), &st), 0);
    /* The UBO2003 naming with the running index light * 81 + view. */
    assert_int_equal(stat(tu_fmt("%s/tv075_pv345/06560 tl075 pl345 tv075 pv345.jpg", out), &st), 0);
    assert_int_equal(stat(tu_fmt("%s/tv015_pv000/00001 tl000 pl000 tv015 pv000.jpg", out), &st), 0);
    int status;
    char *text = tu_capture(tu_fmt("%s info %s", tu_cli(), out), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(text, "UBO2003"));
    assert_non_null(strstr(text, "6561 (81 views x 81 lights)"));
    assert_non_null(strstr(text, "16 x 16"));
    assert_non_null(strstr(text, "ubo81"));
    free(text);
    /* --verify decodes every image. */
    text = tu_capture(tu_fmt("%s info --verify %s", tu_cli(), out), &status);
    assert_int_equal(status, 0);
    free(text);
}

static int files_equal(const char *a, const char *b)
{
    unsigned char *x, *y;
    size_t nx, ny;
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    if (!fa || !fb)
        return 0;
    x = malloc(1 << 20);
    y = malloc(1 << 20);
    nx = fread(x, 1, 1 << 20, fa);
    ny = fread(y, 1, 1 << 20, fb);
    fclose(fa);
    fclose(fb);
    int eq = nx == ny && memcmp(x, y, nx) == 0;
    free(x);
    free(y);
    return eq;
}

static void generate_is_deterministic(void **state)
{
    (void)state;
    char a[4096], b[4096], c[4096];
    snprintf(a, sizeof a, "%s/a", tu_dir);
    snprintf(b, sizeof b, "%s/b", tu_dir);
    snprintf(c, sizeof c, "%s/c", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 8 --seed 3 --threads 1 %s",
                                   tu_cli(), a), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 8 --seed 3 --threads 2 %s",
                                   tu_cli(), b), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material fabric --size 8 --seed 4 %s",
                                   tu_cli(), c), NULL), 0);
    const char *names[] = {"tv045_pv020/03260 tl060 pl054 tv045 pv020.jpg", "truth/height.exr",
                           "truth/albedo.exr"};
    for (int i = 0; i < 3; i++) {
        assert_true(files_equal(tu_fmt("%s/%s", a, names[i]), tu_fmt("%s/%s", b, names[i])));
    }
    /* Another seed gives another sample of the material. */
    assert_false(files_equal(tu_fmt("%s/%s", a, names[0]), tu_fmt("%s/%s", c, names[0])));
    assert_false(files_equal(tu_fmt("%s/%s", a, names[2]), tu_fmt("%s/%s", c, names[2])));
}

static void generate_errors(void **state)
{
    (void)state;
    char *err = NULL;
    assert_int_not_equal(tu_run(tu_fmt("%s generate --material velvet %s/v", tu_cli(), tu_dir), &err), 0);
    assert_non_null(strstr(err, "velvet"));
    free(err);
    /* A non-empty OUTDIR is refused and left as it was. */
    char full[4096];
    snprintf(full, sizeof full, "%s/full", tu_dir);
    mkdir(full, 0777);
    tu_write_file(tu_fmt("%s/keep.txt", full), "mine", 4);
    assert_int_not_equal(tu_run(tu_fmt("%s generate --material wood --size 4 %s", tu_cli(), full),
                                &err), 0);
    assert_non_null(strstr(err, "not empty"));
    free(err);
    assert_int_equal(tu_count_files(full), 1);
    assert_int_equal(tu_run(tu_fmt("%s generate --material wood --size 0 %s/z", tu_cli(), tu_dir), &err), 2);
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s generate --size 4 %s/z", tu_cli(), tu_dir), &err), 2);
    assert_non_null(strstr(err, "--material"));
    free(err);
}

static void info_names_truncated_jpeg(void **state)
{
    (void)state;
    char out[4096], victim[4096];
    snprintf(out, sizeof out, "%s/trunc", tu_dir);
    assert_int_equal(tu_run(tu_fmt("%s generate -q --material wood --size 8 %s", tu_cli(), out),
                            NULL), 0);
    snprintf(victim, sizeof victim, "%s/tv060_pv018/02387 tl045 pl200 tv060 pv018.jpg", out);
    struct stat st;
    assert_int_equal(stat(victim, &st), 0);
    assert_int_equal(truncate(victim, st.st_size - 30), 0);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s info %s", tu_cli(), out), &err), 1);
    assert_non_null(strstr(err, "02387 tl045 pl200 tv060 pv018.jpg"));
    assert_non_null(strstr(err, "truncated"));
    /* One line: the only newline is the last character. */
    assert_true(strchr(err, '\n') == err + strlen(err) - 1);
    free(err);
    /* A missing file is named too. */
    remove(victim);
    assert_int_equal(tu_run(tu_fmt("%s info %s", tu_cli(), out), &err), 1);
    assert_non_null(strstr(err, "02387 tl045 pl200 tv060 pv018.jpg"));
    assert_non_null(strstr(err, "missing"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s info %s/does-not-exist", tu_cli(), tu_dir), &err), 1);
    assert_non_null(strstr(err, "does-not-exist"));
    free(err);
}

static void bad_model_files(void **state)
{
    (void)state;
    char bad[4096];
    snprintf(bad, sizeof bad, "%s/bad.btfcar", tu_dir);
    tu_write_file(bad, "path\tjunk\nnot a model\n", 22);
    const char *cmds[] = {"info %s", "synthesise %s --size 4x4 -o %s.out"};
    for (int i = 0; i < 2; i++) {
        char *err = NULL;
        assert_int_equal(tu_run(tu_fmt(tu_fmt("%%s %s", cmds[i]), tu_cli(), bad, bad), &err), 1);
        assert_non_null(strstr(err, bad));
        assert_non_null(strstr(err, "not a btfcar model"));
        assert_true(strchr(err, '\n') == err + strlen(err) - 1);
        free(err);
    }
    struct stat st;
    assert_int_not_equal(stat(tu_fmt("%s.out/subspace_00.exr", bad), &st), 0);
}

/* texture-fit's model options reach the model (--levels, --neighbourhood,
 * --max-neighbours), and synthesise regenerates it. */
static void texture_fit_options(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("leather", 48, 2, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    char png[4096], model[4096];
    snprintf(png, sizeof png, "%s/tex.png", tu_dir);
    snprintf(model, sizeof model, "%s/tex.btfcar", tu_dir);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    const char *opts[] = {"--levels 2 --max-neighbours 3", "--levels 1 --neighbourhood 0:-1,-1:0"};
    const int want_levels[] = {2, 1};
    for (int i = 0; i < 2; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s texture-fit -q %s -o %s %s", tu_cli(), png, model, opts[i]), &err);
        if (rc)
            print_error("%s\n", err);
        assert_int_equal(rc, 0);
        free(err);
        btf_model m;
        TU_OK(btf_model_read(model, &m, &e), &e);
        assert_int_equal(m.subspaces[0].levels, want_levels[i]);
        for (int b = 0; b < 3; b++)
            for (int l = 0; l < m.subspaces[0].levels; l++)
                assert_true(i == 0 ? m.subspaces[0].bands[b][l].n <= 3
                                   : m.subspaces[0].bands[b][l].n == 2);
        btf_model_free(&m);
        assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 20x10 --backend cpu -o %s.syn",
                                       tu_cli(), model, model), NULL), 0);
    }
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s texture-fit %s -o %s --max-neighbours 0", tu_cli(), png,
                                   model), &err), 2);
    free(err);
}

/* synthesise's request checks: --subspace takes distinct plain numbers,
 * --size at most 65536 per side, --device goes with a Vulkan backend, and
 * the GPU backend refuses images beyond its memory budget (auto streams
 * them on the CPU instead). Usage errors exit 2 before any output. */
static void synthesise_request_checks(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_image img;
    tu_material_image("wood", 32, 3, (btf_dir){0, 0}, (btf_dir){30, 0}, &img);
    char png[4096], model[4096], out[4096];
    snprintf(png, sizeof png, "%s/req.png", tu_dir);
    snprintf(model, sizeof model, "%s/req.btfcar", tu_dir);
    snprintf(out, sizeof out, "%s/req.out", tu_dir);
    TU_OK(btf_image_write_png(png, &img, &e), &e);
    btf_image_free(&img);
    assert_int_equal(tu_run(tu_fmt("%s texture-fit -q %s -o %s --levels 1", tu_cli(), png, model),
                            NULL), 0);
    const char *bad[] = {"--subspace ''", "--subspace ' 0'", "--subspace +0", "--subspace -0",
                         "--subspace 0,0", "--subspace 0,", "--subspace 1",
                         "--size 70000x1", "--size 1x65537", "--backend cpu --device 0",
                         "--match-colours --no-match-colours"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char *err = NULL;
        int rc = tu_run(tu_fmt("%s synthesise %s --size 8x8 %s -o %s", tu_cli(), model, bad[i],
                               out), &err);
        if (rc != 2)
            print_error("%s: exit %d, %s\n", bad[i], rc, err ? err : "");
        assert_int_equal(rc, 2);
        assert_true(strchr(err, '\n') == err + strlen(err) - 1); /* one line */
        free(err);
    }
    struct stat st;
    assert_int_not_equal(stat(out, &st), 0); /* nothing written */
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 4x3 --subspace 0 --backend cpu "
                                   "-o %s", tu_cli(), model, out), NULL), 0);
    /* 20000 x 20000 floats are 4.5 GiB: more than the GPU backend holds. The
     * refusal comes before any device or pixel work. */
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s synthesise %s --size 20000x20000 --backend gpu -o %s.big",
                                   tu_cli(), model, out), &err), 1);
    assert_non_null(strstr(err, "GiB"));
    assert_non_null(strstr(err, "--backend cpu"));
    free(err);
    assert_int_not_equal(stat(tu_fmt("%s.big", out), &st), 0); /* no folder left */
    /* colour matching, the default, needs the model's Lab histogram (format
     * 1.3): an older model synthesises without it, and asking for it then
     * is an error naming the subspace, before anything is written */
    const char *old = "tests/data/model-v1.0.btfcar";
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 8x8 --backend cpu -o %s.old",
                                   tu_cli(), old, out), NULL), 0);
    assert_int_equal(tu_run(tu_fmt("%s synthesise -q %s --size 8x8 --backend cpu --match-colours "
                                   "-o %s.old2", tu_cli(), old, out), &err), 1);
    assert_non_null(strstr(err, "Lab histogram"));
    assert_non_null(strstr(err, "subspace 0"));
    free(err);
    assert_int_not_equal(stat(tu_fmt("%s.old2", out), &st), 0);
}

/* What every command takes from the one option table: --name=value, "--",
 * -V, unknown choices as usage errors, usage lines that name every option
 * the parser knows, and --help defaults that are the library's. */
static void option_conventions(void **state)
{
    (void)state;
    int st;
    char *out = tu_capture(tu_fmt("%s -V", tu_cli()), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, BTF_VERSION_STRING));
    free(out);
    char *err = NULL;
    /* An unknown value of an enumerated option: exit 2, the choices named. */
    assert_int_equal(tu_run(tu_fmt("%s generate --material stone %s/x", tu_cli(), tu_dir), &err), 2);
    assert_non_null(strstr(err, "leather"));
    free(err);
    assert_int_equal(tu_run(tu_fmt("%s synthesise m --size 4x4 -o x --backend=tpu", tu_cli()),
                            &err), 2);
    assert_non_null(strstr(err, "cpu, gpu or auto"));
    free(err);
    /* --name=value is --name value; a flag with a value is an error. */
    const char *ds = tu_fmt("%s/conv", tu_dir);
    char dsdir[4096];
    snprintf(dsdir, sizeof dsdir, "%s", ds);
    assert_int_equal(tu_run(tu_fmt("%s generate --material=fabric --size=8 --seed=3 -q %s",
                                   tu_cli(), dsdir), NULL), 0);
    assert_int_equal(tu_count_files(dsdir), 6561 + 3);
    assert_int_equal(tu_run(tu_fmt("%s info --json=yes %s", tu_cli(), dsdir), &err), 2);
    assert_non_null(strstr(err, "takes no value"));
    free(err);
    /* "--" ends the options: a folder named like an option is an argument. */
    char *cwd = getcwd(NULL, 0);
    assert_int_equal(chdir(tu_dir), 0);
    assert_int_equal(tu_run(tu_fmt("%s generate --material wood --size 4 -q -- --odd", tu_cli()),
                            NULL), 0);
    struct stat sb;
    assert_int_equal(stat("--odd/truth/height.exr", &sb), 0);
    assert_int_equal(chdir(cwd), 0);
    free(cwd);
    /* The usage line names what the parser accepts. */
    out = tu_capture(tu_fmt("%s synthesise --help", tu_cli()), &st);
    assert_int_equal(st, 0);
    assert_non_null(strstr(out, "[--backend cpu|gpu|auto]"));
    assert_non_null(strstr(out, "[--half]"));
    assert_non_null(strstr(out, "[--device N]"));
    free(out);
    /* --help prints the library's defaults (btf_*_defaults). */
    btf_generate_opts g = btf_generate_defaults();
    out = tu_capture(tu_fmt("%s generate --help", tu_cli()), &st);
    assert_non_null(strstr(out, tu_fmt("(default: %d)", g.size)));
    assert_non_null(strstr(out, tu_fmt("(default: %d)", g.jpeg_quality)));
    free(out);
    btf_segment_opts so = btf_segment_defaults();
    out = tu_capture(tu_fmt("%s analyse --help", tu_cli()), &st);
    assert_non_null(strstr(out, tu_fmt("(default: %d)", so.features.bins)));
    assert_non_null(strstr(out, tu_fmt("(default: %d)", so.kmeans.restarts)));
    free(out);
}

/* info --devices --json is one JSON document whatever the devices. */
static void devices_json(void **state)
{
    (void)state;
    int st;
    char *out = tu_capture(tu_fmt("%s info --devices --json", tu_cli()), &st);
    assert_int_equal(st, 0);
    assert_true(strncmp(out, "{\"devices\": [", 13) == 0);
    assert_non_null(strstr(out, "]}"));
    if (strstr(out, "\"index\"")) { /* a device: its limits are stated */
        assert_non_null(strstr(out, "\"max_storage_buffer_bytes\": "));
        assert_non_null(strstr(out, "\"device_local_bytes\": "));
        assert_true(strstr(out, "\"storage_16bit\": true") ||
                    strstr(out, "\"storage_16bit\": false"));
    }
    free(out);
}

/* docs/cli.md is the commands' own --help (tools/cli-doc.sh): it must not
 * drift from the option tables. Run from the source tree (make test). */
static void cli_doc_is_current(void **state)
{
    (void)state;
    if (access("tools/cli-doc.sh", R_OK) != 0 || access("docs/cli.md", R_OK) != 0) {
        print_message("not in the source tree: docs/cli.md not compared\n");
        return;
    }
    int st = tu_run(tu_fmt("sh tools/cli-doc.sh %s | cmp -s - docs/cli.md", tu_cli()), NULL);
    if (st != 0)
        print_error("docs/cli.md is stale: sh tools/cli-doc.sh build/btfcar > docs/cli.md\n");
    assert_int_equal(st, 0);
}

/* tools/gpu-check.sh --dry-run: the parity test programs and the four timed
 * workloads, each on both backends, without running any (the real run needs
 * minutes: docs/gpu.md, "Checking on a real GPU"). Run from the source tree. */
static void gpu_check_dry_run(void **state)
{
    (void)state;
    if (access("tools/gpu-check.sh", R_OK) != 0) {
        print_message("not in the source tree: tools/gpu-check.sh not run\n");
        return;
    }
    int st;
    char *out = tu_capture(tu_fmt("BTF_CLI=%s sh tools/gpu-check.sh --dry-run", tu_cli()), &st);
    assert_int_equal(st, 0);
    /* the test programs as built: <the command's folder>/tests/test_gpu etc. */
    const char *want[] = {"tests/test_gpu\n", "tests/test_gpu_render\n", "tests/test_gpu_tileable\n",
                          "tests/test_gpu_rf\n", "tests/test_gpu_match\n", "--family rf",
                          "synthesise -q WORK/car.btfcar --size 512x512 -o WORK/gpu-synth --backend gpu",
                          "--scene tools/../examples/sphere-one-light.json --size 1024x1024 -o "
                          "WORK/cpu-sphere.png --backend cpu",
                          "--size 4096x4096 --texture-size 256 -o WORK/gpu-flat.png --backend gpu",
                          "render -q WORK/rf.btfcar --scene", NULL};
    for (int i = 0; want[i]; i++) {
        if (!strstr(out, want[i]))
            print_error("gpu-check.sh --dry-run lacks '%s':\n%s\n", want[i], out);
        assert_non_null(strstr(out, want[i]));
    }
    free(out);
    assert_int_equal(tu_run("sh tools/gpu-check.sh --no-such-option 2>/dev/null", NULL), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(help_and_version),
        cmocka_unit_test(option_conventions),
        cmocka_unit_test(devices_json),
        cmocka_unit_test(cli_doc_is_current),
        cmocka_unit_test(gpu_check_dry_run),
        cmocka_unit_test(generate_then_info),
        cmocka_unit_test(generate_is_deterministic),
        cmocka_unit_test(generate_errors),
        cmocka_unit_test(info_names_truncated_jpeg),
        cmocka_unit_test(bad_model_files),
        cmocka_unit_test(texture_fit_options),
        cmocka_unit_test(synthesise_request_checks),
    };
    return cmocka_run_group_tests_name("cli", tests, tu_setup_dir, tu_teardown_dir);
}
