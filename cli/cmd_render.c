/* cmd_render.c — btfcar render: the material on geometry (Haindl & Filip
 * 2007, section III): a JSON scene (--scene), or a flat patch seen from one
 * (view, light) pair (--view/--light), the model's counterpart of one
 * measured image. The library does the work (src/render/, src/scene/). */
#include "cli.h"

#include <stdlib.h>
#include <string.h>

static const char ABOUT[] =
    "Renders the material. With --scene, the objects of a JSON scene file\n"
    "(docs/scene.md) under its lights; with --view and --light, a flat patch\n"
    "seen and lit from those directions (orthographic, one texel per pixel), to\n"
    "lay beside the measured image of that pair. Per pixel, the 3 nearest\n"
    "measured views x 3 nearest lights select subspace images, blended with\n"
    "barycentric weights at parallax-shifted texture coordinates and relit by\n"
    "the range map's normals (docs/render.md). Only the subspaces the frame\n"
    "needs are synthesised, tileable, in memory. IMAGE: .png (8-bit sRGB) or\n"
    ".exr (linear float).\n"
    "A reflectance-field model (analyse --family rf, docs/rf.md) renders flat or\n"
    "a scene, on the CPU or the GPU as --backend chooses: per pixel the four\n"
    "closest measured views' fields at the exact light, bilinear in theta and\n"
    "phi; its texels repeat across the surface (--texture-size, --all-subspaces,\n"
    "--seed and --relief do not apply; the first two are errors).\n";

/* The frame's side without --size (and without --beside). */
#define DEFAULT_SIDE 512

/* --beside DATASET: the measured image of the (view, light) pair, read at
 * the measured directions nearest those asked for (within 0.5 degree). */
static btf_status read_measured(const char *dataset, btf_dir view, btf_dir light,
                                btf_image *out, btf_error *err)
{
    btf_dataset *ds;
    btf_status rc = btf_dataset_open(dataset, NULL, &ds, err);
    if (rc)
        return rc;
    const btf_dataset_info *in = btf_dataset_get_info(ds);
    int v = btf_dirset_find(in->views, view, 0.5), l = btf_dirset_find(in->lights, light, 0.5);
    if (v < 0 || l < 0)
        rc = cli_set_error(err, BTF_E_ARG, "%s: no measured %s at theta %g, phi %g (within "
                           "0.5 degree) to lay beside the render", dataset,
                           v < 0 ? "view" : "light", v < 0 ? view.theta : light.theta,
                           v < 0 ? view.phi : light.phi);
    else
        rc = btf_dataset_read(ds, v, l, out, err);
    btf_dataset_close(ds);
    return rc;
}

/* [measured | model] side by side, the measured image at its own size and
 * the render's height the larger of the two (the rest black). */
static btf_status side_by_side(const btf_image *a, const btf_image *b, btf_image *out,
                               btf_error *err)
{
    int h = a->height > b->height ? a->height : b->height;
    btf_status rc = btf_image_alloc(out, a->width + b->width, h, 3, err);
    if (rc)
        return rc;
    memset(out->data, 0, (size_t)out->width * h * 3 * sizeof(float));
    for (int y = 0; y < h; y++) {
        float *row = out->data + (size_t)y * out->width * 3;
        if (y < a->height)
            memcpy(row, a->data + (size_t)y * a->width * 3, (size_t)a->width * 3 * sizeof(float));
        if (y < b->height)
            memcpy(row + (size_t)a->width * 3, b->data + (size_t)y * b->width * 3,
                   (size_t)b->width * 3 * sizeof(float));
    }
    return BTF_OK;
}

/* The backend --backend and --device ask for (auto: a real GPU if there is
 * one, else the CPU, NULL); NULL with *rc set when the GPU asked for is not
 * there. */
static btf_gpu *open_backend(const char *backend, int device, btf_status *rc, btf_error *err)
{
    btf_gpu *gpu = cli_open_gpu(backend, device, err);
    if (!gpu && (!strcmp(backend, "gpu") || device >= 0))
        *rc = err->code ? err->code : BTF_E_UNSUPPORTED;
    else if (!gpu)
        *err = (btf_error){0}; /* auto: the CPU runs, the GPU's reason is spent */
    return gpu;
}

/* What the render did and how long each step took. A material that
 * synthesises its textures times that step; one that does not (a
 * reflectance field) has only an upload on the GPU, and traces only for a
 * scene. */
static void print_times(const btf_material *m, int flat, const char *gpu_name,
                        const btf_render_info *info, double t_read, double t_write,
                        double t_start)
{
    btf_material_info mi;
    btf_material_get_info(m, &mi);
    int synthesises = (mi.caps & BTF_MATERIAL_SYNTHESISES) != 0;
    printf("backend %s (%s): model read %.3f s, ", gpu_name ? "gpu" : "cpu",
           gpu_name ? gpu_name : "cpu", t_read);
    if (synthesises || !flat)
        printf("trace %.3f s, ", info->trace_s);
    if (synthesises || gpu_name)
        printf("%s %.3f s, ", !synthesises ? "upload" : gpu_name ? "synthesis pass" : "synthesis",
               info->synth_s);
    printf("%s %.3f s, write %.3f s; total %.3f s\n", gpu_name ? "render pass" : "shade",
           info->shade_s, t_write, cli_now() - t_start);
}

/* --beside: [measured | model] into *img; the measured image is freed. */
static btf_status lay_beside(btf_image *measured, btf_image *img, btf_error *err)
{
    btf_image both = {0};
    btf_status rc = side_by_side(measured, img, &both, err);
    btf_image_free(img);
    btf_image_free(measured);
    *img = both;
    return rc;
}

/* The material's own options: a model that does not synthesise its textures
 * (a reflectance field keeps its texels, which repeat across the surface)
 * has nothing for --texture-size and --all-subspaces to act on. */
static int check_material_options(cli_ctx *c, const char *path, const btf_material *m,
                                  const btf_render_opts *ro)
{
    btf_material_info mi;
    btf_material_get_info(m, &mi);
    if (!(mi.caps & BTF_MATERIAL_SYNTHESISES) && (ro->texture_size || ro->all_subspaces))
        return cli_usage_error(c, "%s is a reflectance-field model: %s applies to the CAR "
                               "model's synthesised textures only", path,
                               ro->texture_size ? "--texture-size" : "--all-subspaces");
    return -1;
}

/* Reads the model and the scene, renders on the chosen backend, lays the
 * measured image beside, writes: one sequence for every model family
 * (btfcar/material.h). */
static int render_material(cli_ctx *c, const char *model, const char *scene_path,
                           btf_dir view, btf_dir light, const char *beside, const char *out_path,
                           btf_render_opts *ro, const char *backend, int device, double t_start)
{
    btf_error err = {0};
    btf_scene scene;
    memset(&scene, 0, sizeof scene);
    if (scene_path && btf_scene_load(scene_path, &scene, &err) != 0)
        return cli_lib_error(c, &err);
    btf_material *m;
    double t_read = cli_now();
    if (btf_material_read(model, &m, &err) != 0) {
        btf_scene_free(&scene);
        return cli_lib_error(c, &err);
    }
    t_read = cli_now() - t_read;
    int urc = check_material_options(c, model, m, ro);
    if (urc >= 0) {
        btf_material_free(m);
        btf_scene_free(&scene);
        return urc;
    }
    btf_image img = {0}, measured = {0};
    btf_status rc = beside ? read_measured(beside, view, light, &measured, &err) : BTF_OK;
    if (rc == BTF_OK && ro->width == 0) { /* no --size: the measured image's, else the default */
        ro->width = beside ? measured.width : DEFAULT_SIDE;
        ro->height = beside ? measured.height : DEFAULT_SIDE;
    }
    btf_gpu *gpu = rc == BTF_OK ? open_backend(backend, device, &rc, &err) : NULL;
    char devname[300];
    snprintf(devname, sizeof devname, "%s", gpu ? btf_gpu_device_name(gpu) : "cpu");
    int used_gpu = gpu != NULL;
    btf_render_info info;
    memset(&info, 0, sizeof info);
    if (rc == BTF_OK)
        rc = scene_path ? btf_material_render_scene(m, gpu, &scene, ro, &img, &info, &err)
                        : btf_material_render_flat(m, gpu, view, light, ro, &img, &info, &err);
    if (rc == BTF_OK && gpu && btf_gpu_validation_errors(gpu))
        rc = cli_set_error(&err, BTF_E_UNSUPPORTED, "Vulkan validation: %s",
                           btf_gpu_first_validation_message(gpu));
    btf_gpu_close(gpu);
    if (rc == BTF_OK && beside)
        rc = lay_beside(&measured, &img, &err);
    btf_image_free(&measured);
    double t_write = cli_now();
    if (rc == BTF_OK)
        rc = cli_write_image(out_path, &img, &err);
    t_write = cli_now() - t_write;
    if (rc == BTF_OK && !c->quiet) {
        char note[512];
        btf_material_render_note(m, scene_path ? &scene : NULL, view, &info, note, sizeof note);
        printf("%s\n", note);
        print_times(m, !scene_path, used_gpu ? devname : NULL, &info, t_read, t_write, t_start);
        printf("rendered %dx%d into %s\n", img.width, img.height, out_path);
    }
    btf_image_free(&img);
    btf_material_free(m);
    btf_scene_free(&scene);
    if (rc) {
        if (!strchr(err.msg, ':')) { /* name the model when the library could not */
            char why[sizeof err.msg];
            snprintf(why, sizeof why, "%s", err.msg);
            cli_set_error(&err, rc, "%s: %s", model, why);
        }
        return cli_lib_error(c, &err);
    }
    return 0;
}

int cmd_render(int argc, char **argv)
{
    cli_ctx c = {"render", 0};
    static const char *const backends[] = {"cpu", "gpu", "auto", NULL};
    const char *model = NULL, *scene_path = NULL, *out_path = NULL, *beside = NULL;
    cli_dir_arg view = {{0, 0}, 0}, light = {{0, 0}, 0};
    btf_render_opts ro = btf_render_defaults();
    int size[2] = {0, 0}, backend = 2, all = 0, device = -1; /* size 0: not given */
    double t_start = cli_now();
    cli_opt opts[] = {
        {.name = "--scene", .kind = CLI_STRING, .dest = &scene_path, .meta = "FILE",
         .help = "the JSON scene to render (docs/scene.md, examples/)"},
        {.name = "--view", .kind = CLI_CUSTOM, .dest = &view, .meta = "THETA,PHI",
         .help = "flat render: the view direction (degrees)", .parse = cli_parse_dir_arg},
        {.name = "--light", .kind = CLI_CUSTOM, .dest = &light, .meta = "THETA,PHI",
         .help = "flat render: the light direction (degrees)", .parse = cli_parse_dir_arg},
        {.name = "--beside", .kind = CLI_STRING, .dest = &beside, .meta = "DATASET",
         .help = "flat render: write the measured image of the pair (from DATASET) on\n"
                 "the left and the render on the right"},
        {.name = "--size", .kind = CLI_SIZE, .dest = size, .meta = "WxH",
         .help = "frame size in pixels (default: 512x512; with --beside, the measured\n"
                 "image's size)", .lo = 1, .hi = BTF_RENDER_MAX_SIDE},
        {.name = "--output", .short_name = "-o", .kind = CLI_STRING, .dest = &out_path,
         .meta = "IMAGE", .help = "the image to write: .png (8-bit sRGB) or .exr (linear)",
         .required = 1},
        {.name = "--seed", .kind = CLI_U64, .dest = &ro.seed, .meta = "S",
         .help = "synthesis seed of the subspace images; the same seed gives the same\n"
                 "pixels"},
        {.name = "--relief", .kind = CLI_DOUBLE, .dest = &ro.relief, .meta = "R",
         .help = "range map height scale for parallax and bump mapping; 0 turns\n"
                 "both off", .lo = 0, .hi = 1e6},
        {.name = "--texture-size", .kind = CLI_INT, .dest = &ro.texture_size, .meta = "N|auto",
         .help = "side of the tileable subspace images in texels; auto: what the\n"
                 "visible surface spans (at most 1024). A CAR model only",
         .lo = 8, .hi = BTF_RENDER_MAX_SIDE, .word = "auto", .word_value = 0},
        {.name = "--threads", .kind = CLI_INT, .dest = &ro.threads, .meta = "N",
         .help = "threads for tracing, synthesis and shading; 0: all CPUs", .lo = 0,
         .hi = 1024},
        {.name = "--all-subspaces", .kind = CLI_FLAG, .dest = &all,
         .help = "synthesise every subspace, not only those the frame needs (a CAR\n"
                 "model only)"},
        {.name = "--backend", .kind = CLI_CHOICE, .dest = &backend, .meta = "cpu|gpu|auto",
         .help = "cpu: the CPU renderer; gpu: the two Vulkan compute passes (synthesis,\n"
                 "render) on any device, lavapipe included; auto: a real GPU if present,\n"
                 "else the CPU", .choices = backends},
        {.name = "--device", .kind = CLI_INT, .dest = &device, .meta = "N",
         .help = "Vulkan device index (btfcar info --devices)", .lo = 0, .hi = 255},
        {0}};
    cli_spec spec = {.cmd = "render", .args = "MODEL", .about = ABOUT, .min_args = 1,
                     .max_args = 1, .opts = opts};
    int nargs, prc = cli_parse(&c, &spec, argc, argv, &model, &nargs);
    if (prc >= 0)
        return prc;
    int flat = view.given || light.given;
    if (flat && scene_path)
        return cli_usage_error(&c, "--scene and --view/--light exclude each other");
    if (!flat && !scene_path)
        return cli_usage_error(&c, "give --scene FILE, or --view THETA,PHI and --light THETA,PHI");
    if (flat && !(view.given && light.given))
        return cli_usage_error(&c, "a flat render needs both --view and --light");
    if (beside && !flat)
        return cli_usage_error(&c, "--beside goes with a flat render (--view, --light)");
    if (!cli_has_suffix(out_path, ".png") && !cli_has_suffix(out_path, ".exr"))
        return cli_usage_error(&c, "%s: expected a .png or .exr output", out_path);
    if (device >= 0 && backend == 0)
        return cli_usage_error(&c, "--device names a Vulkan device; it does not go with --backend cpu");
    if (cli_check_output(&c, out_path, BTF_OUTPUT_FILE))
        return 1;
    ro.width = size[0];
    ro.height = size[1];
    ro.all_subspaces = all;
    return render_material(&c, model, scene_path, view.dir, light.dir, beside, out_path, &ro,
                           backends[backend], device, t_start);
}
