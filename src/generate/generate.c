/*
 * generate.c — writes a procedural BTF (a stand-in for the measured BTFs of
 * the paper's section II) to disk in the Bonn UBO2003 layout:
 * for each of the 81 views a folder "tvCCC_pvDDD/" with the 81 images
 * "NNNNN tlAAA plBBB tvCCC pvDDD.jpg" (NNNNN = light_index * 81 + view_index),
 * plus the ground truth in truth/{height,normals,albedo}.exr.
 *
 * Visibility from a view depends only on the view, and shadowing only on the
 * light, so the 81 view maps and 81 light maps are computed once and each of
 * the 6,561 images only combines one of each (generate/render.c). Maps,
 * then images, are made by the thread pool (core/pool.c); each is
 * independent, so the output does not depend on the thread count.
 *
 * The whole dataset is built in a temporary folder beside OUTDIR and renamed
 * into place at the end: a failure leaves nothing behind.
 */
#include <stdio.h>
#include "core/core.h"
#include "generate/material.h"

#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The batch both phases share: the material, its directions and the maps
 * phase 1 makes for phase 2. */
typedef struct gen_job {
    const btf_procedural *m;
    const btf_dirset *dirs;
    btf_view_map **views;
    btf_light_map **lights;
    const char *dir;       /* the temporary output folder */
    int quality;
} gen_job;

static void view_folder(char *buf, size_t n, btf_dir v)
{
    snprintf(buf, n, "tv%03d_pv%03d", (int)(v.theta + 0.5), (int)(v.phi + 0.5));
}

static int render_one(const gen_job *j, int vi, int li, btf_error *err)
{
    btf_dir v = j->dirs->dirs[vi], l = j->dirs->dirs[li];
    btf_image img = {0};
    int rc = btf__material_render_maps(j->m, j->views[vi], j->lights[li], v, l, &img, err);
    if (rc)
        return rc;
    char folder[32], name[64], path[4096];
    view_folder(folder, sizeof folder, v);
    snprintf(name, sizeof name, "%s/%05d tl%03d pl%03d tv%03d pv%03d.jpg", folder,
             li * j->dirs->count + vi, (int)(l.theta + 0.5), (int)(l.phi + 0.5),
             (int)(v.theta + 0.5), (int)(v.phi + 0.5));
    rc = btf__path_join(path, sizeof path, j->dir, name, err);
    if (rc == 0)
        rc = btf_image_write_jpeg(path, &img, j->quality, err);
    btf_image_free(&img);
    return rc;
}

/* Phase 1 jobs: 0..n-1 the view maps, n..2n-1 the light maps. */
static btf_status map_job(void *user, int t, int worker, btf_error *err)
{
    (void)worker;
    gen_job *j = user;
    int n = j->dirs->count;
    if (t < n)
        return btf__view_map_make(j->m, j->dirs->dirs[t], &j->views[t], err);
    return btf__light_map_make(j->m, j->dirs->dirs[t - n], &j->lights[t - n], err);
}

/* Phase 2 jobs walk view-major so that one view's folder fills at a time. */
static btf_status image_job(void *user, int t, int worker, btf_error *err)
{
    (void)worker;
    gen_job *j = user;
    int n = j->dirs->count;
    return render_one(j, t / n, t % n, err);
}

static btf_status write_truth(const btf_procedural *m, const char *dir, btf_error *err)
{
    char tdir[4096], path[4096];
    btf_status rc = btf__path_join(tdir, sizeof tdir, dir, "truth", err);
    if (rc == 0)
        rc = btf_mkdirs(tdir, err);
    struct { const char *name; float *data; int channels; } maps[3] = {
        {"height.exr", m->height, 1}, {"normals.exr", m->normal, 3}, {"albedo.exr", m->albedo, 3}};
    for (int i = 0; rc == 0 && i < 3; i++) {
        btf_image img = {m->size, m->size, maps[i].channels, maps[i].data};
        rc = btf__path_join(path, sizeof path, tdir, maps[i].name, err);
        if (rc == 0)
            rc = btf_image_write_exr_opts(path, &img, NULL, NULL, err);
    }
    return rc;
}

static btf_status make_view_folders(const btf_dirset *dirs, const char *dir, btf_error *err)
{
    for (int i = 0; i < dirs->count; i++) {
        char folder[32], path[4096];
        view_folder(folder, sizeof folder, dirs->dirs[i]);
        btf_status rc = btf__path_join(path, sizeof path, dir, folder, err);
        if (rc == 0)
            rc = btf_mkdirs(path, err);
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* OUTDIR may not exist yet, or be an empty folder; anything else is refused
 * so that a generator run never overwrites somebody's data. */
static btf_status check_outdir(const char *outdir, btf_error *err)
{
    struct stat st;
    if (stat(outdir, &st) != 0)
        return errno == ENOENT ? BTF_OK
                               : btf__fail(err, BTF_E_IO, "%s: %s", outdir, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return btf__fail(err, BTF_E_ARG, "%s: exists and is not a folder", outdir);
    DIR *d = opendir(outdir);
    if (!d)
        return btf__fail(err, BTF_E_IO, "%s: %s", outdir, strerror(errno));
    int empty = 1;
    struct dirent *e;
    while (empty && (e = readdir(d)))
        empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
    closedir(d);
    if (!empty)
        return btf__fail(err, BTF_E_ARG, "%s: folder exists and is not empty; give a new or empty "
                         "folder", outdir);
    return BTF_OK;
}

static int generate_into(const btf_procedural *m, const btf_dirset *dirs, const char *tmp,
                         const btf_generate_opts *o, btf_error *err)
{
    int n = dirs->count;
    gen_job j = {.m = m, .dirs = dirs, .dir = tmp, .quality = o->jpeg_quality};
    j.views = btf__calloc((size_t)n, sizeof *j.views, err);
    j.lights = btf__calloc((size_t)n, sizeof *j.lights, err);
    int rc = (j.views && j.lights) ? BTF_OK : BTF_E_NOMEM;
    btf_pool_progress progress = {o->progress, o->progress_user, "rendering images", 0.0, 1.0,
                                  n};
    if (rc == 0)
        rc = make_view_folders(dirs, tmp, err);
    if (rc == 0)
        rc = btf__pool_run(2 * n, o->threads, map_job, &j, NULL, err);
    if (rc == 0)
        rc = btf__pool_run(n * n, o->threads, image_job, &j, &progress, err);
    if (rc == 0)
        rc = write_truth(m, tmp, err);
    for (int i = 0; i < n; i++) {
        if (j.views)
            btf__view_map_free(j.views[i]);
        if (j.lights)
            btf__light_map_free(j.lights[i]);
    }
    free(j.views);
    free(j.lights);
    return rc;
}

btf_generate_opts btf_generate_defaults(void)
{
    return (btf_generate_opts){.struct_size = sizeof(btf_generate_opts),
                               .size = 128, .seed = 0, .jpeg_quality = 95, .threads = 0};
}

btf_status btf_generate(const char *material, const char *outdir, const btf_generate_opts *opts,
                        btf_error *err)
{
    btf_generate_opts d = btf_generate_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_generate", err))
        return BTF_E_ARG;
    if (o.jpeg_quality < 0 || o.jpeg_quality > 100)
        return btf__fail(err, BTF_E_ARG, "JPEG quality %d: expected 1..100", o.jpeg_quality);
    /* Zero means the default; seed 0 and threads 0 (all CPUs) are taken as
     * they are. A negative size is refused by btf_procedural_make. */
    if (o.size == 0)
        o.size = d.size;
    if (o.jpeg_quality == 0)
        o.jpeg_quality = d.jpeg_quality;
    int size = o.size;
    btf_status rc = check_outdir(outdir, err);
    if (rc)
        return rc;
    btf_procedural m;
    rc = btf_procedural_make(material, size, o.seed, &m, err);
    if (rc)
        return rc;
    btf_dirset dirs;
    rc = btf_dirset_ubo81(&dirs, err);
    if (rc) {
        btf_procedural_free(&m);
        return rc;
    }
    /* Into a temporary sibling folder, renamed into place as a whole. */
    btf_output_dir *od = NULL;
    rc = btf_output_dir_begin(outdir, &od, err);
    if (rc == 0)
        rc = generate_into(&m, &dirs, btf_output_dir_path(od), &o, err);
    if (rc == 0)
        rc = btf_output_dir_commit(od, err);
    else
        btf_output_dir_fail(od, err);
    btf_dirset_free(&dirs);
    btf_procedural_free(&m);
    return rc;
}
