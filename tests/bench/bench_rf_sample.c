/*
 * bench_rf_sample.c — the memory reduction of Meseth, Müller & Klein 2003,
 * section 6 (docs/rf.md, "Memory reduction"): on each
 * generated material, the whole reflectance-field fit against the fit of
 * an N x N sample with a quilted coordinate map: bytes (in memory and in
 * the file), fitting time, the pixel-wise error (mean |dY| over every image,
 * as the report computes it, btf__rf_error) and the texture distance
 * (btf_texture_distance's combined figure, as `btfcar compare` prints it)
 * of the flat render against the measured image over 3 x 3 (view, light)
 * pairs; then (PTM) what the map costs on larger surfaces. Figures only;
 * never fails on time.
 *
 * Usage: bench_rf_sample [SIZE [SAMPLE [FIT [MATERIAL]]]]
 *        (default 64 32 ptm, every material; FIT ptm|lobes|lafortune)
 */
#include "testutil.h"
#include "rf/rf_render.h"
#include "rf/rf_error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct figures {
    double seconds, fit_s, mae, combined;
    btf_rf_bytes bytes;
} figures;

/* The mean combined texture distance of the flat render against the
 * measured image over views {0, 30, 60 deg} x lights {0, 45, 75 deg}. */
static int texture_distance(const btf_dataset *ds, const btf_rf_model *m, double *out,
                            btf_error *e)
{
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    const int views[3] = {0, 7, 37}, lights[3] = {0, 19, 57};
    double sum = 0.0;
    int n = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            int v = views[i] < in->n_views ? views[i] : 0;
            int l = lights[j] < in->n_lights ? lights[j] : 0;
            btf_image meas, img;
            if (btf_dataset_read(ds, v, l, &meas, e))
                return 1;
            if (btf__rf_render_flat(m, in->views->dirs[v], in->lights->dirs[l], in->width,
                                    in->height, 2, &img, e)) {
                btf_image_free(&meas);
                return 1;
            }
            btf_texture_distance_opts o = btf_texture_distance_defaults();
            btf_texture_distances d;
            int rc = btf_texture_distance(&meas, &img, &o, &d, e);
            btf_image_free(&meas);
            btf_image_free(&img);
            if (rc)
                return 1;
            sum += d.combined, n++;
        }
    *out = sum / n;
    return 0;
}

static int measure(const btf_dataset *ds, int fit, int sample, figures *f, btf_rf_model *keep,
                   btf_error *e)
{
    btf_rf_opts o = btf_rf_defaults();
    o.fit = fit, o.threads = 2;
    btf_rf_fit_info info;
    o.info = &info;
    btf_rf_model m;
    double t0 = tu_now();
    int rc;
    if (sample) {
        btf_rf_sample_opts so = btf_rf_sample_defaults();
        so.width = so.height = sample, so.seed = 1;
        rc = btf_rf_fit_sampled(ds, &o, &so, &m, e);
    } else {
        rc = btf_rf_fit(ds, &o, &m, e);
    }
    f->seconds = tu_now() - t0;
    if (rc)
        return 1;
    f->fit_s = info.fit_s;
    if (btf__rf_error(ds, &m, 2, &f->mae, NULL, e) || btf_rf_model_bytes(&m, &f->bytes, e) ||
        texture_distance(ds, &m, &f->combined, e)) {
        btf_rf_model_free(&m);
        return 1;
    }
    if (keep)
        *keep = m;
    else
        btf_rf_model_free(&m);
    return 0;
}

static void row(const char *what, const figures *f)
{
    printf("  %-22s %10.0f %10.0f %10.0f %8.1f %8.1f %9.5f %9.3f\n", what,
           (double)f->bytes.coefficients, (double)f->bytes.map, (double)f->bytes.file,
           f->seconds, f->fit_s, f->mae, f->combined);
}

/* The sampled model's map on larger surfaces: memory, file, time. */
static void surfaces(const btf_dataset *ds, int fit, int sample)
{
    const int sides[3] = {256, 1024, 4096};
    printf("  larger surfaces (the same %dx%d sample; a whole fit of the surface would hold "
           "its coefficients for every texel):\n", sample, sample);
    for (int k = 0; k < 3; k++) {
        btf_error e = {0};
        btf_rf_opts o = btf_rf_defaults();
        o.fit = fit, o.threads = 2;
        btf_rf_fit_info info;
        o.info = &info;
        btf_rf_sample_opts so = btf_rf_sample_defaults();
        so.width = so.height = sample, so.seed = 1;
        so.surface_width = so.surface_height = sides[k];
        btf_rf_model m;
        btf_rf_bytes b;
        if (btf_rf_fit_sampled(ds, &o, &so, &m, &e) || btf_rf_model_bytes(&m, &b, &e)) {
            fprintf(stderr, "bench_rf_sample: %s\n", e.msg);
            return;
        }
        double per_texel = (double)b.coefficients / ((double)sample * sample);
        printf("  %5d^2 surface: coefficients %.2f MB + map %.2f MB in memory (file %.2f MB, "
               "map %.3f MB of it), quilting %.2f s; a whole fit: %.0f MB\n", sides[k],
               b.coefficients / 1e6, b.map / 1e6, b.file / 1e6, b.file_map / 1e6, info.quilt_s,
               per_texel * sides[k] * sides[k] / 1e6);
        btf_rf_model_free(&m);
    }
}

static int material(const char *name, int size, int sample, int fit, int big)
{
    char *dir = tu_tmpdir();
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    btf_error e = {0};
    btf_generate_opts g = btf_generate_defaults();
    g.size = size, g.threads = 2;
    btf_dataset *ds = NULL;
    figures whole, part;
    if (btf_generate(name, path, &g, &e) || btf_dataset_open(path, NULL, &ds, &e) ||
        measure(ds, fit, 0, &whole, NULL, &e) || measure(ds, fit, sample, &part, NULL, &e)) {
        fprintf(stderr, "bench_rf_sample: %s: %s\n", name, e.msg);
        return 1;
    }
    printf("%s %dx%d, %s:\n", name, size, size, btf_rf_fit_name(fit));
    row("whole fit", &whole);
    char what[64];
    snprintf(what, sizeof what, "%dx%d sample + map", sample, sample);
    row(what, &part);
    if (big)
        surfaces(ds, fit, sample);
    btf_dataset_close(ds);
    tu_rmtree(dir);
    free(dir);
    return 0;
}

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 64;
    int sample = argc > 2 ? atoi(argv[2]) : 32;
    const char *fitname = argc > 3 ? argv[3] : "ptm";
    const char *only = argc > 4 ? argv[4] : NULL;
    int fit = !strcmp(fitname, "lobes") ? BTF_RF_LOBES
              : !strcmp(fitname, "lafortune") ? BTF_RF_LAFORTUNE : BTF_RF_PTM;
    printf("== reflectance fields on a sample (paper section 6, docs/rf.md): 81 x 81 images, "
           "2 threads\n");
    printf("  %-22s %10s %10s %10s %8s %8s %9s %9s\n", "model", "coeff. B", "map B", "file B",
           "time s", "fit s", "mean|dY|", "texture");
    const char *materials[3] = {"leather", "fabric", "wood"};
    int rc = 0;
    for (int k = 0; k < 3; k++)
        if (!only || !strcmp(only, materials[k]))
            rc |= material(materials[k], size, sample, fit,
                           (k == 0 || only != NULL) && fit == BTF_RF_PTM);
    printf("  (texture: btf_texture_distance's combined figure, flat render against the "
           "measured image, mean over 3 x 3 pairs; 1.0 is as close as the material is to "
           "itself)\n");
    return rc;
}
