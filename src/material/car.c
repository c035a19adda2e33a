/*
 * car.c — the CAR model (Haindl & Filip 2007) as a family of the
 * material interface (src/material/family.h): its file, its description
 * (car_describe.c), its renders on the CPU (src/render/) or the GPU
 * (gpu/render_gpu.c) and its report (src/report/).
 */
#include "material/family.h"
#include "model/model.h"

static btf_status car_read(const char *path, void *model, btf_error *err)
{
    return btf_model_read(path, model, err);
}

static void car_free(void *model)
{
    btf_model_free(model);
}

static void car_dirsets(const void *model, const btf_dirset **views, const btf_dirset **lights)
{
    const btf_model *m = model;
    *views = &m->views;
    *lights = &m->lights;
}

static btf_status car_describe_ops(const void *model, const describe_file *file, FILE *out,
                                   int json, btf_error *err)
{
    (void)err;
    car_describe(model, file, out, json);
    return BTF_OK;
}

/* Whether the model has what the renderer interpolates over: view and
 * light direction sets it can triangulate (at most BTF_HEMISPHERE_MAX_POINTS,
 * no two the same, not all on one line; a set of 1 or 2 directions, one
 * camera over a dome, is made a triangle by the renderer's ghost
 * directions, docs/render.md "Sparse pair sets"). Checked here, with the
 * file's name, rather than left to the renderer, whose messages cannot name
 * a file they have not seen. */
static btf_status car_renders(const void *model, const char *path, btf_error *err)
{
    const btf_model *m = model;
    if (!m->index || m->views.count < 1 || m->lights.count < 1)
        return btf__fail(err, BTF_E_ARG, "%s: the model is a single texture: it has no view and "
                         "light directions to render with (analyse a BTF dataset)", path);
    const btf_dirset *sets[2] = {&m->views, &m->lights};
    for (int i = 0; i < 2; i++) {
        btf_hemisphere *h = NULL;
        btf_error why = {0};
        if (sets[i]->count < 3)
            continue;
        if (btf_hemisphere_build(sets[i], &h, &why) != BTF_OK)
            return btf__fail(err, why.code, "%s: its %s cannot be rendered: %s", path,
                             i ? "lights" : "views", why.msg);
        btf_hemisphere_free(h);
    }
    return BTF_OK;
}

static btf_status car_render_flat(const void *model, btf_gpu *g, btf_dir view, btf_dir light,
                                  const btf_render_opts *opts, btf_image *out,
                                  btf_render_info *info, btf_error *err)
{
    return g ? btf_gpu_render_flat(g, model, view, light, opts, out, info, err)
             : btf_render_flat(model, view, light, opts, out, info, err);
}

static btf_status car_render_scene(const void *model, btf_gpu *g, const btf_scene *s,
                                   const btf_render_opts *opts, btf_image *out,
                                   btf_render_info *info, btf_error *err)
{
    return g ? btf_gpu_render_scene(g, model, s, opts, out, info, err)
             : btf_render_scene(model, s, opts, out, info, err);
}

static void car_render_note(const void *model, const btf_scene *s, btf_dir view,
                            const btf_render_info *info, char *buf, size_t n)
{
    (void)model, (void)s, (void)view;
    snprintf(buf, n, "subspaces: %d needed of %d (tileable, %dx%d texels)", info->needed,
             info->total, info->texture_size, info->texture_size);
}

static btf_status car_report(const btf_dataset *ds, const void *model, const char *dir,
                             const btf_report_opts *opts, btf_report_summary *summary,
                             btf_error *err)
{
    return btf_report_write(ds, model, dir, opts, summary, err);
}

const btf_family_ops btf__car_family = {
    .family = BTF_FAMILY_CAR,
    .name = "car",
    .caps = BTF_MATERIAL_SYNTHESISES,
    .model_size = sizeof(btf_model),
    .sniff = btf__model_sniff,
    .read = car_read,
    .free = car_free,
    .dirsets = car_dirsets,
    .describe = car_describe_ops,
    .renders = car_renders,
    .render_flat = car_render_flat,
    .render_scene = car_render_scene,
    .render_note = car_render_note,
    .report = car_report,
};
