/*
 * dataset.c — BTF datasets on disk (the measured (view, light) images that
 * the analysis of paper section II starts from) behind one streaming
 * interface.
 *
 * Opening lists the files of a UBO2003, UTIA or manifest layout
 * (dataset/dataset_scan.c), makes every (view, light) pair's table from the
 * entries, checks that the set is complete and unique, and (unless asked
 * not to) probes every file's header and structure. Pixels are decoded one
 * image at a time, on demand: read by pair, iterate, or verify them all.
 * A Bonn .btf file (layout UBO2014, recognised by its signature) is opened
 * by dataset/ubo_open.c instead, and each image is reconstructed from it by
 * dataset/ubo_decode.c.
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/dataset.h"
#include "dataset/ubo2014.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

struct btf_dataset {
    btf_dataset_info info;
    btf_dirset views, lights;
    char root[BTF_DATASET_PATH_MAX];
    btf_dataset_entries files; /* owns the path strings */
    char **paths;     /* [view * n_lights + light], pointers into files; NULL
                         where a sparse set has no image of the pair */
    const btf_near_field **near; /* [pair]: a near-field image's geometry, or NULL */
    uint64_t max_pixels; /* btf_dataset_opts.max_pixels */
    ubo_open_file *ubo;  /* layout UBO2014: the mapped file */
};

/* The distinct light (or view) directions of the entries as a set. */
static btf_status collect_dirs(const btf_dataset_entries *l, int lights, btf_dirset *set,
                               btf_error *err)
{
    btf_dir *d = btf__alloc((size_t)l->count, sizeof *d, err);
    if (!d)
        return BTF_E_NOMEM;
    for (int i = 0; i < l->count; i++)
        d[i] = lights ? l->items[i].light : l->items[i].view;
    btf_status rc = btf_dirset_from_list(set, d, l->count, err);
    free(d);
    return rc;
}

static void describe_pair(char *buf, size_t n, btf_dir light, btf_dir view)
{
    snprintf(buf, n, "light (theta %g, phi %g), view (theta %g, phi %g)", light.theta, light.phi,
             view.theta, view.phi);
}

/* Where the file of a missing pair was expected, for the error message. */
static void expected_name(const btf_dataset *ds, int vi, int li, char *buf, size_t n)
{
    btf_dir v = ds->views.dirs[vi], L = ds->lights.dirs[li];
    int tl = (int)(L.theta + 0.5), pl = (int)(L.phi + 0.5), tv = (int)(v.theta + 0.5),
        pv = (int)(v.phi + 0.5);
    char folder[32] = "";
    if (!ds->files.flat)
        snprintf(folder, sizeof folder, "tv%03d_pv%03d/", tv, pv);
    if (ds->info.layout == BTF_LAYOUT_UBO2003)
        snprintf(buf, n, "%s/%s%05d tl%03d pl%03d tv%03d pv%03d%s", ds->root, folder,
                 li * ds->info.n_views + vi, tl, pl, tv, pv, ds->files.ext);
    else if (ds->info.layout == BTF_LAYOUT_UTIA)
        snprintf(buf, n, "%s/%stl%03d_pl%03d_tv%03d_pv%03d%s", ds->root, folder, tl, pl, tv, pv,
                 ds->files.ext);
    else
        snprintf(buf, n, "%s", ds->root);
}

static btf_status build_table(btf_dataset *ds, const btf_dataset_entries *l, btf_error *err)
{
    int nv = ds->views.count, nl = ds->lights.count;
    ds->paths = btf__calloc((size_t)nv * nl, sizeof(char *), err);
    if (!ds->paths)
        return BTF_E_NOMEM;
    for (int i = 0; i < l->count; i++) {
        const btf_dataset_entry *e = &l->items[i];
        int vi = btf_dirset_find(&ds->views, e->view, BTF_DIR_NAME_TOLERANCE);
        int li = btf_dirset_find(&ds->lights, e->light, BTF_DIR_NAME_TOLERANCE);
        if (vi < 0 || li < 0) /* the sets were made from these very entries */
            return btf__fail(err, BTF_E_DATA, "%s: direction not in the dataset's set", e->path);
        char **slot = &ds->paths[(size_t)vi * nl + li];
        if (*slot) {
            char pair[160];
            describe_pair(pair, sizeof pair, e->light, e->view);
            return btf__fail(err, BTF_E_DATA, "%s: second file for %s (the first is %s)", e->path,
                             pair, *slot);
        }
        *slot = e->path;
        if (e->near.on) {
            if (!ds->near && !(ds->near = btf__calloc((size_t)nv * nl, sizeof *ds->near, err)))
                return BTF_E_NOMEM;
            ds->near[(size_t)vi * nl + li] = &e->near;
            ds->info.near_field = 1;
        }
    }
    ds->info.n_pairs = l->count;
    if (l->count == nv * nl)
        return BTF_OK;
    /* A manifest may list any set of pairs (docs/datasets.md, "Sparse pair
     * sets"); the folder layouts name a full grid, where a missing file is
     * a broken copy. */
    if (ds->files.layout == BTF_LAYOUT_MANIFEST)
        return BTF_OK;
    for (int vi = 0; vi < nv; vi++)
        for (int li = 0; li < nl; li++)
            if (!ds->paths[(size_t)vi * nl + li]) {
                char name[BTF_DATASET_PATH_MAX], pair[160];
                expected_name(ds, vi, li, name, sizeof name);
                describe_pair(pair, sizeof pair, ds->lights.dirs[li], ds->views.dirs[vi]);
                return btf__fail(err, BTF_E_DATA, "%s: missing image for %s (%d of %d pairs present; "
                                 "a manifest may list any set of pairs)",
                                 name, pair, l->count, nv * nl);
            }
    return BTF_OK;
}

/* Probes every file (or only the first): same size everywhere, sound structure. */
static btf_status probe_files(btf_dataset *ds, const btf_dataset_opts *o, btf_error *err)
{
    int n = ds->info.n_views * ds->info.n_lights;
    btf_image_header first = {0};
    const char *first_path = NULL;
    for (int i = 0; i < n; i++) {
        btf_image_header h;
        const char *p = ds->paths[i];
        if (!p)
            continue; /* a pair a sparse set does not hold */
        if (!first_path || !o->skip_verify) {
            btf_status rc = btf_image_probe(p, &h, err);
            if (!rc)
                rc = btf__check_pixels(p, h.width, h.height, o->max_pixels, err);
            if (rc)
                return rc;
            if (!first_path) {
                first = h;
                first_path = p;
            } else if (h.width != first.width || h.height != first.height) {
                return btf__fail(err, BTF_E_DATA, "%s: size %dx%d differs from %dx%d of %s", p,
                                 h.width, h.height, first.width, first.height, first_path);
            }
            ds->info.bytes_on_disk += h.file_bytes;
        } else {
            struct stat st;
            if (stat(p, &st) != 0)
                return btf__fail(err, BTF_E_IO, "%s: %s", p, strerror(errno));
            ds->info.bytes_on_disk += (uint64_t)st.st_size;
        }
        if (o->progress && (i % 256 == 0 || i == n - 1))
            o->progress(o->progress_user, (double)(i + 1) / n, "checking images");
    }
    ds->info.width = first.width;
    ds->info.height = first.height;
    ds->info.channels = first.channels;
    ds->info.format = first.format;
    return BTF_OK;
}

void btf_dataset_close(btf_dataset *ds)
{
    if (!ds)
        return;
    btf__dataset_entries_free(&ds->files);
    btf_dirset_free(&ds->views);
    btf_dirset_free(&ds->lights);
    free(ds->paths);
    free(ds->near);
    ubo_close(ds->ubo);
    free(ds);
}

/* A .btf file: the mapped file's sets and sizes become the dataset's. */
static btf_status open_ubo(btf_dataset *ds, const btf_dataset_opts *o, btf_error *err)
{
    btf_status rc = ubo_open(ds->root, &ds->ubo, err);
    if (rc == BTF_OK)
        rc = btf__dirset_copy(&ds->views, &ds->ubo->views, err);
    if (rc == BTF_OK)
        rc = btf__dirset_copy(&ds->lights, &ds->ubo->lights, err);
    if (rc == BTF_OK)
        rc = btf__check_pixels(ds->root, (int)ds->ubo->f.width, (int)ds->ubo->f.height,
                               o->max_pixels, err);
    if (rc)
        return rc;
    ds->info.layout = BTF_LAYOUT_UBO2014;
    ds->info.root = ds->root;
    ds->info.n_views = ds->views.count;
    ds->info.n_lights = ds->lights.count;
    ds->info.views = &ds->views;
    ds->info.lights = &ds->lights;
    ds->info.width = (int)ds->ubo->f.width;
    ds->info.height = (int)ds->ubo->f.height;
    ds->info.channels = 3;
    ds->info.format = BTF_FILE_UNKNOWN;
    ds->info.bytes_on_disk = ds->ubo->f.size;
    ds->info.n_pairs = ds->views.count * ds->lights.count;
    return BTF_OK;
}

const btf_ubo2014_info *btf_dataset_ubo2014(const btf_dataset *ds)
{
    return ds && ds->ubo ? &ds->ubo->f.info : NULL;
}

btf_dataset_opts btf_dataset_defaults(void)
{
    return (btf_dataset_opts){.struct_size = sizeof(btf_dataset_opts),
                              .skip_verify = 0, .progress = NULL, .progress_user = NULL,
                              .max_pixels = BTF_DEFAULT_MAX_PIXELS};
}

btf_status btf_dataset_open(const char *path, const btf_dataset_opts *opts, btf_dataset **out,
                            btf_error *err)
{
    *out = NULL;
    btf_dataset_opts d = btf_dataset_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_dataset_open", err))
        return BTF_E_ARG;
    btf_dataset *ds = btf__calloc(1, sizeof *ds, err);
    if (!ds)
        return BTF_E_NOMEM;
    ds->max_pixels = o.max_pixels;
    snprintf(ds->root, sizeof ds->root, "%s", path);
    size_t rl = strlen(ds->root);
    while (rl > 1 && ds->root[rl - 1] == '/')
        ds->root[--rl] = '\0';
    if (ubo_sniff(ds->root)) {
        btf_status urc = open_ubo(ds, &o, err);
        if (urc) {
            btf_dataset_close(ds);
            return urc;
        }
        *out = ds;
        return BTF_OK;
    }
    btf_status rc = btf__dataset_list_entries(ds->root, &ds->files, err);
    if (rc == BTF_OK)
        rc = collect_dirs(&ds->files, 0, &ds->views, err);
    if (rc == BTF_OK)
        rc = collect_dirs(&ds->files, 1, &ds->lights, err);
    if (rc == BTF_OK) {
        ds->info.layout = ds->files.layout;
        ds->info.root = ds->root;
        ds->info.n_views = ds->views.count;
        ds->info.n_lights = ds->lights.count;
        ds->info.views = &ds->views;
        ds->info.lights = &ds->lights;
        rc = build_table(ds, &ds->files, err);
    }
    if (rc == BTF_OK)
        rc = probe_files(ds, &o, err);
    if (rc) {
        btf_dataset_close(ds);
        return rc;
    }
    *out = ds;
    return BTF_OK;
}

const btf_dataset_info *btf_dataset_get_info(const btf_dataset *ds)
{
    return &ds->info;
}

btf_status btf__dataset_present(const btf_dataset *ds, unsigned char **present, btf_error *err)
{
    int nv = ds->info.n_views, nl = ds->info.n_lights;
    *present = btf__alloc((size_t)(nv * nl > 0 ? nv * nl : 1), 1, err);
    if (!*present)
        return BTF_E_NOMEM;
    for (int v = 0; v < nv; v++)
        for (int l = 0; l < nl; l++)
            (*present)[(size_t)v * nl + l] = (unsigned char)btf_dataset_has(ds, v, l);
    return BTF_OK;
}

int btf_dataset_has(const btf_dataset *ds, int view, int light)
{
    return btf_dataset_path(ds, view, light) != NULL;
}

const char *btf_dataset_path(const btf_dataset *ds, int view, int light)
{
    if (view < 0 || light < 0 || view >= ds->info.n_views || light >= ds->info.n_lights)
        return NULL;
    if (ds->ubo)
        return ds->root; /* every image is in the one file */
    return ds->paths[(size_t)view * ds->info.n_lights + light];
}

btf_status btf_dataset_read(const btf_dataset *ds, int view, int light, btf_image *out,
                            btf_error *err)
{
    const char *p = btf_dataset_path(ds, view, light);
    if (!p && view >= 0 && light >= 0 && view < ds->info.n_views && light < ds->info.n_lights)
        return btf__fail(err, BTF_E_ARG, "%s: no image of (view %d, light %d): the set holds %d "
                         "of its %d x %d pairs", ds->root, view, light, ds->info.n_pairs,
                         ds->info.n_views, ds->info.n_lights);
    if (!p)
        return btf__fail(err, BTF_E_ARG, "%s: no (view %d, light %d) in a %d x %d dataset", ds->root,
                         view, light, ds->info.n_views, ds->info.n_lights);
    if (ds->ubo) {
        btf_status rc = btf_image_alloc(out, ds->info.width, ds->info.height, 3, err);
        if (rc == BTF_OK)
            rc = ubo_decode(&ds->ubo->f, ds->ubo->view_index[view], ds->ubo->light_index[light],
                            out->data, err);
        if (rc)
            btf_image_free(out);
        return rc;
    }
    btf_read_opts ro = {.channels = 3, .max_pixels = ds->max_pixels};
    btf_status rc = btf_image_read(p, &ro, out, err);
    if (rc == BTF_OK && (out->width != ds->info.width || out->height != ds->info.height)) {
        rc = btf__fail(err, BTF_E_DATA, "%s: size %dx%d differs from the dataset's %dx%d", p,
                       out->width, out->height, ds->info.width, ds->info.height);
        btf_image_free(out);
    }
    if (rc == BTF_OK && ds->near && ds->near[(size_t)view * ds->info.n_lights + light])
        btf__near_field_correct(ds->near[(size_t)view * ds->info.n_lights + light], out);
    return rc;
}

btf_status btf__dataset_read_into(const btf_dataset *ds, int view, int light, btf_image *img,
                                  btf_error *err)
{
    int reuse = ds->ubo && img->data && img->width == ds->info.width &&
                img->height == ds->info.height && img->channels == 3;
    if (!reuse) {
        btf_image_free(img);
        return btf_dataset_read(ds, view, light, img, err);
    }
    if (!btf_dataset_path(ds, view, light)) {
        btf_image_free(img);
        return btf_dataset_read(ds, view, light, img, err); /* the message */
    }
    btf_status rc = ubo_decode(&ds->ubo->f, ds->ubo->view_index[view],
                               ds->ubo->light_index[light], img->data, err);
    if (rc)
        btf_image_free(img);
    return rc;
}

void btf_dataset_iter_begin(btf_dataset_iter *it, const btf_dataset *ds)
{
    memset(it, 0, sizeof *it);
    it->ds = ds;
}

int btf_dataset_iter_next(btf_dataset_iter *it, btf_error *err)
{
    const btf_dataset *ds = it->ds;
    int n = ds->info.n_views * ds->info.n_lights;
    while (it->next < n && !btf_dataset_has(ds, it->next / ds->info.n_lights,
                                            it->next % ds->info.n_lights))
        it->next++; /* a pair a sparse set does not hold */
    if (it->next >= n) {
        btf_image_free(&it->sample.image);
        return 0;
    }
    int k = it->next++;
    btf_sample *s = &it->sample;
    s->view = k / ds->info.n_lights;
    s->light = k % ds->info.n_lights;
    s->view_dir = ds->views.dirs[s->view];
    s->light_dir = ds->lights.dirs[s->light];
    s->path = btf_dataset_path(ds, s->view, s->light);
    /* The sample's buffer is the iterator's: a .btf file's next image is
     * decoded into it (btf__dataset_read_into). */
    int rc = btf__dataset_read_into(ds, s->view, s->light, &s->image, err);
    return rc ? rc : 1;
}

void btf_dataset_iter_end(btf_dataset_iter *it)
{
    btf_image_free(&it->sample.image);
}

btf_status btf_dataset_verify_pixels(const btf_dataset *ds, btf_progress_fn progress,
                                     void *user, btf_error *err)
{
    btf_dataset_iter it;
    btf_dataset_iter_begin(&it, ds);
    int n = ds->info.n_pairs, rc, done = 0;
    while ((rc = btf_dataset_iter_next(&it, err)) == 1) {
        done++;
        if (progress && (done % 64 == 0 || done == n))
            progress(user, (double)done / n, "decoding images");
    }
    btf_dataset_iter_end(&it);
    return rc < 0 ? (btf_status)rc : BTF_OK;
}
