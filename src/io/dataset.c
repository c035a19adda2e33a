/*
 * dataset.c — BTF datasets on disk (the measured (view, light) images that
 * the analysis of paper section II starts from) behind one streaming
 * interface.
 *
 * Three layouts are recognised automatically:
 *  - Bonn UBO2003: "NNNNN tlAAA plBBB tvCCC pvDDD.jpg" (3-digit whole degrees,
 *    5-digit running index), in per-view folders "tvCCC_pvDDD/" or one folder;
 *  - UTIA: "tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.png" (8-bit sRGB) or ".exr";
 *  - a manifest: a TSV file with the columns path, theta_l, phi_l, theta_v,
 *    phi_v (degrees; paths relative to the manifest's folder).
 * Opening collects every (light, view) pair from the names only, checks that
 * the set is complete and unique, and (unless asked not to) probes every file's
 * header and structure. Pixels are decoded one image at a time, on demand.
 */
#include <stdio.h>
#include "core/core.h"
#include "io/io.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PATH_MAX_LEN 4096

typedef struct entry {
    char *path;
    btf_dir light, view;
} entry;

typedef struct entry_list {
    entry *items;
    int count, cap;
    btf_layout layout;
    int flat;        /* UBO2003 files in one folder (no tvCCC_pvDDD/) */
    char ext[8];     /* the first file's extension, for messages */
} entry_list;

struct btf_dataset {
    btf_dataset_info info;
    btf_dirset views, lights;
    char root[PATH_MAX_LEN];
    entry_list files; /* owns the path strings */
    char **paths;     /* [view * n_lights + light], pointers into files */
    uint64_t max_pixels; /* btf_dataset_opts.max_pixels */
};


const char *btf_layout_name(btf_layout layout)
{
    switch (layout) {
    case BTF_LAYOUT_UBO2003: return "UBO2003";
    case BTF_LAYOUT_UTIA: return "UTIA";
    case BTF_LAYOUT_MANIFEST: return "manifest";
    default: return "unknown";
    }
}

static void entries_free(entry_list *l)
{
    for (int i = 0; i < l->count; i++)
        free(l->items[i].path);
    free(l->items);
    memset(l, 0, sizeof *l);
}

static btf_status entries_add(entry_list *l, const char *path, btf_dir light, btf_dir view,
                              btf_error *err)
{
    if (l->count == l->cap) {
        int ncap = l->cap ? l->cap * 2 : 256;
        entry *n = realloc(l->items, (size_t)ncap * sizeof *n);
        if (!n)
            return btf_fail(err, BTF_E_NOMEM, "out of memory listing the dataset");
        l->items = n;
        l->cap = ncap;
    }
    char *p = strdup(path);
    if (!p)
        return btf_fail(err, BTF_E_NOMEM, "out of memory listing the dataset");
    l->items[l->count++] = (entry){p, light, view};
    return BTF_OK;
}

/* Matches name against a pattern where '#' is one decimal digit and any other
 * character must be equal (letters case-insensitively). The digit groups are
 * stored in nums (up to 8). Returns the number of groups, or -1. */
static int match_name(const char *name, const char *pat, int *nums)
{
    int groups = 0, in_group = 0;
    for (; *pat; pat++, name++) {
        if (*pat == '#') {
            if (!isdigit((unsigned char)*name))
                return -1;
            if (!in_group) {
                if (groups == 8)
                    return -1;
                nums[groups++] = 0;
            }
            nums[groups - 1] = nums[groups - 1] * 10 + (*name - '0');
            in_group = 1;
        } else {
            if (tolower((unsigned char)*name) != tolower((unsigned char)*pat))
                return -1;
            in_group = 0;
        }
    }
    return *name == '\0' ? groups : -1;
}

static const char UBO_JPG[] = "##### tl### pl### tv### pv###.jpg";
static const char UTIA_PNG[] = "tl###_pl###_tv###_pv###.png";
static const char UTIA_EXR[] = "tl###_pl###_tv###_pv###.exr";
static const char VIEW_DIR[] = "tv###_pv###";

static btf_dir dir_of(int theta, int phi)
{
    return (btf_dir){(double)theta, (double)phi};
}

/* Classifies one file name; adds it if it follows a layout. folder_view is
 * the view named by the enclosing "tvCCC_pvDDD" folder, or NULL. */
static btf_status add_file(entry_list *l, const char *dir, const char *name,
                           const int *folder_view, btf_error *err)
{
    int n[8];
    btf_layout kind;
    if (match_name(name, UBO_JPG, n) == 5) {
        kind = BTF_LAYOUT_UBO2003;
        n[0] = n[1], n[1] = n[2], n[2] = n[3], n[3] = n[4]; /* drop the running index */
    } else if (folder_view && (match_name(name, UTIA_PNG, n) == 4 || match_name(name, UTIA_EXR, n) == 4)) {
        kind = BTF_LAYOUT_UTIA;
    } else {
        return BTF_OK; /* not an image of the dataset (a README, truth/, ...) */
    }
    char path[PATH_MAX_LEN];
    btf_status rc = btf_path_join(path, sizeof path, dir, name, err);
    if (rc)
        return rc;
    if (l->layout != BTF_LAYOUT_UNKNOWN && l->layout != kind)
        return btf_fail(err, BTF_E_DATA, "%s: %s file in a %s dataset (mixed layouts)", path,
                        btf_layout_name(kind), btf_layout_name(l->layout));
    if (l->count == 0) {
        l->flat = folder_view == NULL;
        const char *dot = strrchr(name, '.');
        snprintf(l->ext, sizeof l->ext, "%s", dot ? dot : "");
    }
    l->layout = kind;
    if (n[0] > 90 || n[2] > 90 || n[1] >= 360 || n[3] >= 360)
        return btf_fail(err, BTF_E_DATA, "%s: direction out of range in the name", path);
    if (folder_view && (folder_view[0] != n[2] || folder_view[1] != n[3]))
        return btf_fail(err, BTF_E_DATA, "%s: view tv%03d pv%03d differs from its folder's", path,
                        n[2], n[3]);
    return entries_add(l, path, dir_of(n[0], n[1]), dir_of(n[2], n[3]), err);
}

static btf_status scan_folder(entry_list *l, const char *dir, const int *folder_view,
                              btf_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return btf_fail(err, BTF_E_IO, "%s: cannot open folder: %s", dir, strerror(errno));
    btf_status rc = BTF_OK;
    struct dirent *e;
    while (rc == BTF_OK && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        int view[8];
        char sub[PATH_MAX_LEN];
        if (!folder_view && match_name(e->d_name, VIEW_DIR, view) == 2) {
            rc = btf_path_join(sub, sizeof sub, dir, e->d_name, err);
            struct stat st;
            if (rc == BTF_OK && stat(sub, &st) == 0 && S_ISDIR(st.st_mode))
                rc = scan_folder(l, sub, view, err);
        } else {
            rc = add_file(l, dir, e->d_name, folder_view, err);
        }
    }
    closedir(d);
    return rc;
}

static btf_status read_manifest(entry_list *l, const char *path, btf_error *err)
{
    btf_tsv t;
    btf_status rc = btf_tsv_read(path, &t, err);
    if (rc)
        return rc;
    static const char *cols[5] = {"path", "theta_l", "phi_l", "theta_v", "phi_v"};
    int c[5];
    for (int i = 0; i < 5; i++)
        if ((c[i] = btf_tsv_column(&t, cols[i])) < 0) {
            btf_tsv_free(&t);
            return btf_fail(err, BTF_E_FORMAT,
                            "%s: manifest header lacks the column '%s' (expected: path theta_l "
                            "phi_l theta_v phi_v, tab-separated)", path, cols[i]);
        }
    char base[PATH_MAX_LEN];
    snprintf(base, sizeof base, "%s", path);
    char *slash = strrchr(base, '/');
    if (slash)
        slash[1] = '\0';
    else
        snprintf(base, sizeof base, ".");
    l->layout = BTF_LAYOUT_MANIFEST;
    for (int r = 0; rc == BTF_OK && r < t.nrows; r++) {
        double v[4];
        for (int i = 0; rc == BTF_OK && i < 4; i++)
            rc = btf_tsv_number(&t, path, r, c[i + 1], &v[i], err);
        if (rc)
            break;
        const char *p = btf_tsv_cell(&t, r, c[0]);
        char full[PATH_MAX_LEN];
        if (p[0] == '/')
            snprintf(full, sizeof full, "%s", p);
        else
            rc = btf_path_join(full, sizeof full, base, p, err);
        if (rc == BTF_OK && (v[0] < 0 || v[0] > 90 || v[2] < 0 || v[2] > 90))
            rc = btf_fail(err, BTF_E_DATA, "%s:%d: theta outside [0, 90]", path, t.line_no[r]);
        if (rc == BTF_OK)
            rc = entries_add(l, full, (btf_dir){v[0], v[1]}, (btf_dir){v[2], v[3]}, err);
    }
    if (rc == BTF_OK && t.nrows == 0)
        rc = btf_fail(err, BTF_E_DATA, "%s: manifest lists no images", path);
    btf_tsv_free(&t);
    return rc;
}

/* The distinct light (or view) directions of the entries as a set. */
static btf_status collect_dirs(const entry_list *l, int lights, btf_dirset *set, btf_error *err)
{
    btf_dir *d = btf_alloc((size_t)l->count, sizeof *d, err);
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

static btf_status build_table(btf_dataset *ds, const entry_list *l, btf_error *err)
{
    int nv = ds->views.count, nl = ds->lights.count;
    ds->paths = btf_calloc((size_t)nv * nl, sizeof(char *), err);
    if (!ds->paths)
        return BTF_E_NOMEM;
    for (int i = 0; i < l->count; i++) {
        const entry *e = &l->items[i];
        int vi = btf_dirset_find(&ds->views, e->view, BTF_DIR_NAME_TOLERANCE);
        int li = btf_dirset_find(&ds->lights, e->light, BTF_DIR_NAME_TOLERANCE);
        if (vi < 0 || li < 0) /* the sets were made from these very entries */
            return btf_fail(err, BTF_E_DATA, "%s: direction not in the dataset's set", e->path);
        char **slot = &ds->paths[(size_t)vi * nl + li];
        if (*slot) {
            char pair[160];
            describe_pair(pair, sizeof pair, e->light, e->view);
            return btf_fail(err, BTF_E_DATA, "%s: second file for %s (the first is %s)", e->path,
                            pair, *slot);
        }
        *slot = e->path;
    }
    for (int vi = 0; vi < nv; vi++)
        for (int li = 0; li < nl; li++)
            if (!ds->paths[(size_t)vi * nl + li]) {
                char name[PATH_MAX_LEN], pair[160];
                expected_name(ds, vi, li, name, sizeof name);
                describe_pair(pair, sizeof pair, ds->lights.dirs[li], ds->views.dirs[vi]);
                return btf_fail(err, BTF_E_DATA, "%s: missing image for %s (%d of %d pairs present)",
                                name, pair, l->count, nv * nl);
            }
    return BTF_OK;
}

/* Probes every file (or only the first): same size everywhere, sound structure. */
static btf_status probe_files(btf_dataset *ds, const btf_dataset_opts *o, btf_error *err)
{
    int n = ds->info.n_views * ds->info.n_lights;
    btf_image_header first = {0};
    for (int i = 0; i < n; i++) {
        btf_image_header h;
        const char *p = ds->paths[i];
        if (i == 0 || !o->skip_verify) {
            btf_status rc = btf_image_probe(p, &h, err);
            if (!rc)
                rc = btf_check_pixels(p, h.width, h.height, o->max_pixels, err);
            if (rc)
                return rc;
            if (i == 0) {
                first = h;
            } else if (h.width != first.width || h.height != first.height) {
                return btf_fail(err, BTF_E_DATA, "%s: size %dx%d differs from %dx%d of %s", p,
                                h.width, h.height, first.width, first.height, ds->paths[0]);
            }
            ds->info.bytes_on_disk += h.file_bytes;
        } else {
            struct stat st;
            if (stat(p, &st) != 0)
                return btf_fail(err, BTF_E_IO, "%s: %s", p, strerror(errno));
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

static btf_status list_entries(const char *path, entry_list *l, btf_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return btf_fail(err, BTF_E_IO, "%s: %s", path, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return read_manifest(l, path, err);
    btf_status rc = scan_folder(l, path, NULL, err);
    if (rc == BTF_OK && l->count == 0)
        rc = btf_fail(err, BTF_E_FORMAT,
                      "%s: unknown layout: no UBO2003 ('NNNNN tlAAA plBBB tvCCC pvDDD.jpg') or "
                      "UTIA ('tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.png|exr') images; for other "
                      "layouts pass a manifest .tsv", path);
    return rc;
}

void btf_dataset_close(btf_dataset *ds)
{
    if (!ds)
        return;
    entries_free(&ds->files);
    btf_dirset_free(&ds->views);
    btf_dirset_free(&ds->lights);
    free(ds->paths);
    free(ds);
}

btf_dataset_opts btf_dataset_defaults(void)
{
    return (btf_dataset_opts){.skip_verify = 0, .progress = NULL, .progress_user = NULL,
                              .max_pixels = BTF_DEFAULT_MAX_PIXELS};
}

btf_status btf_dataset_open(const char *path, const btf_dataset_opts *opts, btf_dataset **out,
                            btf_error *err)
{
    *out = NULL;
    btf_dataset_opts o = opts ? *opts : btf_dataset_defaults();
    btf_dataset *ds = btf_calloc(1, sizeof *ds, err);
    if (!ds)
        return BTF_E_NOMEM;
    ds->max_pixels = o.max_pixels;
    snprintf(ds->root, sizeof ds->root, "%s", path);
    size_t rl = strlen(ds->root);
    while (rl > 1 && ds->root[rl - 1] == '/')
        ds->root[--rl] = '\0';
    btf_status rc = list_entries(ds->root, &ds->files, err);
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

const char *btf_dataset_path(const btf_dataset *ds, int view, int light)
{
    if (view < 0 || light < 0 || view >= ds->info.n_views || light >= ds->info.n_lights)
        return NULL;
    return ds->paths[(size_t)view * ds->info.n_lights + light];
}

btf_status btf_dataset_read(const btf_dataset *ds, int view, int light, btf_image *out,
                            btf_error *err)
{
    const char *p = btf_dataset_path(ds, view, light);
    if (!p)
        return btf_fail(err, BTF_E_ARG, "%s: no (view %d, light %d) in a %d x %d dataset", ds->root,
                        view, light, ds->info.n_views, ds->info.n_lights);
    btf_read_opts ro = {.channels = 3, .max_pixels = ds->max_pixels};
    btf_status rc = btf_image_read(p, &ro, out, err);
    if (rc == BTF_OK && (out->width != ds->info.width || out->height != ds->info.height)) {
        rc = btf_fail(err, BTF_E_DATA, "%s: size %dx%d differs from the dataset's %dx%d", p,
                      out->width, out->height, ds->info.width, ds->info.height);
        btf_image_free(out);
    }
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
    btf_image_free(&it->sample.image);
    int n = ds->info.n_views * ds->info.n_lights;
    if (it->next >= n)
        return 0;
    int k = it->next++;
    btf_sample *s = &it->sample;
    s->view = k / ds->info.n_lights;
    s->light = k % ds->info.n_lights;
    s->view_dir = ds->views.dirs[s->view];
    s->light_dir = ds->lights.dirs[s->light];
    s->path = btf_dataset_path(ds, s->view, s->light);
    int rc = btf_dataset_read(ds, s->view, s->light, &s->image, err);
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
    int n = ds->info.n_views * ds->info.n_lights, rc;
    while ((rc = btf_dataset_iter_next(&it, err)) == 1) {
        if (progress && (it.next % 64 == 0 || it.next == n))
            progress(user, (double)it.next / n, "decoding images");
    }
    btf_dataset_iter_end(&it);
    return rc < 0 ? (btf_status)rc : BTF_OK;
}
