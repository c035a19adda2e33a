/*
 * rf.c — the reflectance-field model (Meseth, Müller & Klein 2003;
 * docs/rf.md) as a family of the material interface
 * (src/material/family.h): its file, its description (rf_describe.c), its
 * renders on the CPU (rf_render.c) or the GPU (gpu/rf_render_gpu.c) and its
 * report (src/report/rf_report.c). Its texels repeat across the surface:
 * nothing is synthesised, so only the frame's size and the threads of
 * btf_render_opts apply.
 */
#include "material/family.h"
#include "rf/rf.h"
#include "report/report.h"
#include "synth_gpu.h"

/* The material interface's frame without a size (btfcar/material.h). */
#define DEFAULT_SIDE 512

static btf_status rf_read(const char *path, void *model, btf_error *err)
{
    return btf__rf_read(path, model, err);
}

static void rf_free(void *model)
{
    btf_rf_model_free(model);
}

static void rf_dirsets(const void *model, const btf_dirset **views, const btf_dirset **lights)
{
    const btf_rf_model *m = model;
    *views = &m->views;
    *lights = &m->lights;
}

static btf_status rf_describe_ops(const void *model, const describe_file *file, FILE *out,
                                  int json, btf_error *err)
{
    return rf_describe(model, file, out, json, err);
}

/* Every reflectance-field model the reader accepts renders. */
static btf_status rf_renders(const void *model, const char *path, btf_error *err)
{
    (void)model, (void)path, (void)err;
    return BTF_OK;
}

static void frame_size(const btf_render_opts *opts, int *width, int *height)
{
    *width = opts->width > 0 ? opts->width : DEFAULT_SIDE;
    *height = opts->height > 0 ? opts->height : DEFAULT_SIDE;
}

static btf_status rf_render_flat_ops(const void *model, btf_gpu *g, btf_dir view,
                                     btf_dir light, const btf_render_opts *opts, btf_image *out,
                                     btf_render_info *info, btf_error *err)
{
    int w, h;
    frame_size(opts, &w, &h);
    memset(info, 0, sizeof *info);
    if (g)
        return btf__gpu_rf_render_flat(g, model, view, light, w, h, out, info, err);
    double t = btf__now();
    btf_status rc = btf__rf_render_flat(model, view, light, w, h, opts->threads, out, err);
    info->shade_s = btf__now() - t;
    return rc;
}

static btf_status rf_render_scene_ops(const void *model, btf_gpu *g, const btf_scene *s,
                                      const btf_render_opts *opts, btf_image *out,
                                      btf_render_info *info, btf_error *err)
{
    int w, h;
    frame_size(opts, &w, &h);
    memset(info, 0, sizeof *info);
    return g ? btf__gpu_rf_render_scene(g, model, s, w, h, opts->threads, out, info, err)
             : btf__rf_render_scene(model, s, w, h, opts->threads, out, info, err);
}

/* The views a render blends: at a flat render's view, the four closest
 * measured ones and their weights (section 5.4); lafortune evaluates its
 * one field at the view itself. */
static void rf_render_note(const void *model, const btf_scene *s, btf_dir view,
                           const btf_render_info *info, char *buf, size_t n)
{
    const btf_rf_model *m = model;
    (void)info;
    if (s) {
        snprintf(buf, n, "reflectance-field model (%s): per pixel the four closest measured "
                 "views at the exact light", btf_rf_fit_name(m->fit));
        return;
    }
    if (m->fit == BTF_RF_LAFORTUNE) {
        snprintf(buf, n, "reflectance-field model (lafortune): evaluated at the view itself");
        return;
    }
    int idx[4];
    double w[4];
    btf__rf_view_weights(&m->views, view, idx, w);
    size_t used = (size_t)snprintf(buf, n, "reflectance-field model (%s): views",
                                   btf_rf_fit_name(m->fit));
    for (int i = 0; i < 4 && used < n; i++)
        if (w[i] != 0.0)
            used += (size_t)snprintf(buf + used, n - used, " %d (%g, %g) x %.4f", idx[i],
                                     m->views.dirs[idx[i]].theta, m->views.dirs[idx[i]].phi,
                                     w[i]);
}

static btf_status rf_report(const btf_dataset *ds, const void *model, const char *dir,
                            const btf_report_opts *opts, btf_report_summary *summary,
                            btf_error *err)
{
    return btf__rf_report_write(ds, model, dir, opts, summary, err);
}

const btf_family_ops btf__rf_family = {
    .family = BTF_FAMILY_RF,
    .name = "rf",
    .caps = 0,
    .model_size = sizeof(btf_rf_model),
    .sniff = btf__rf_sniff,
    .read = rf_read,
    .free = rf_free,
    .dirsets = rf_dirsets,
    .describe = rf_describe_ops,
    .renders = rf_renders,
    .render_flat = rf_render_flat_ops,
    .render_scene = rf_render_scene_ops,
    .render_note = rf_render_note,
    .report = rf_report,
};
