/*
 * dataset_scan.c — the image files of a BTF dataset on disk (the measured
 * (view, light) images that the analysis of paper section II starts from)
 * as a list of (path, light, view) entries, from the names alone (io/io.h;
 * dataset/dataset.c makes the dataset of them).
 *
 * Three layouts are recognised automatically:
 *  - Bonn UBO2003: "NNNNN tlAAA plBBB tvCCC pvDDD.jpg" (3-digit whole degrees,
 *    5-digit running index), in per-view folders "tvCCC_pvDDD/" or one folder;
 *  - UTIA: "tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.png" (8-bit sRGB) or ".exr";
 *  - a manifest: a TSV file with the columns path, theta_l, phi_l, theta_v,
 *    phi_v (degrees; paths relative to the manifest's folder).
 * A folder is scanned by name patterns (one level of view folders); a file
 * is read as a manifest, or, named *.lp, as an RTI light file (dataset/rti_lp.c).
 * Names in one dataset must follow one layout.
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/dataset.h"
#include "io/io.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const char *btf_layout_name(btf_layout layout)
{
    switch (layout) {
    case BTF_LAYOUT_UBO2003: return "UBO2003";
    case BTF_LAYOUT_UTIA: return "UTIA";
    case BTF_LAYOUT_MANIFEST: return "manifest";
    case BTF_LAYOUT_UBO2014: return "UBO2014";
    case BTF_LAYOUT_RTI: return "RTI";
    default: return "unknown";
    }
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
static btf_status add_file(btf_dataset_entries *l, const char *dir, const char *name,
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
    char path[BTF_DATASET_PATH_MAX];
    btf_status rc = btf__path_join(path, sizeof path, dir, name, err);
    if (rc)
        return rc;
    if (l->layout != BTF_LAYOUT_UNKNOWN && l->layout != kind)
        return btf__fail(err, BTF_E_DATA, "%s: %s file in a %s dataset (mixed layouts)", path,
                         btf_layout_name(kind), btf_layout_name(l->layout));
    if (l->count == 0) {
        l->flat = folder_view == NULL;
        const char *dot = strrchr(name, '.');
        snprintf(l->ext, sizeof l->ext, "%s", dot ? dot : "");
    }
    l->layout = kind;
    if (n[0] > 90 || n[2] > 90 || n[1] >= 360 || n[3] >= 360)
        return btf__fail(err, BTF_E_DATA, "%s: direction out of range in the name", path);
    if (folder_view && (folder_view[0] != n[2] || folder_view[1] != n[3]))
        return btf__fail(err, BTF_E_DATA, "%s: view tv%03d pv%03d differs from its folder's", path,
                         n[2], n[3]);
    return btf__dataset_entries_add(l, path, dir_of(n[0], n[1]), dir_of(n[2], n[3]), err);
}

static btf_status scan_folder(btf_dataset_entries *l, const char *dir, const int *folder_view,
                              btf_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return btf__fail(err, BTF_E_IO, "%s: cannot open folder: %s", dir, strerror(errno));
    btf_status rc = BTF_OK;
    struct dirent *e;
    while (rc == BTF_OK && (e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        int view[8];
        char sub[BTF_DATASET_PATH_MAX];
        if (!folder_view && match_name(e->d_name, VIEW_DIR, view) == 2) {
            rc = btf__path_join(sub, sizeof sub, dir, e->d_name, err);
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

/* The same file under two directions would stand for two images: an error
 * naming both lines (entries 0.. are the manifest's rows in order). */
static btf_status no_duplicate_paths(const btf_dataset_entries *l, const btf_tsv *t,
                                     const char *path, btf_error *err)
{
    int first, again;
    btf_status rc = btf__dataset_entries_repeat(l, &first, &again, err);
    if (rc == BTF_OK && first >= 0)
        rc = btf__fail(err, BTF_E_DATA, "%s:%d: %s is listed again (first on line %d); each "
                       "image under one (light, view) pair", path, t->line_no[again],
                       l->items[again].path, t->line_no[first]);
    return rc;
}

/* The columns of a near-field manifest (docs/datasets.md). */
static const char *const NEAR_COLS[9] = {"path",    "cam_x",   "cam_y",  "cam_z", "light_x",
                                         "light_y", "light_z", "size_x", "size_y"};

/* Row r of a near-field manifest: positions and size, checked, into *nf. */
static btf_status near_row(const btf_tsv *t, const char *path, int r, const int *c,
                           btf_near_field *nf, btf_error *err)
{
    double v[8];
    for (int i = 0; i < 8; i++) {
        btf_status rc = btf__tsv_number(t, path, r, c[i + 1], &v[i], err);
        if (rc)
            return rc;
    }
    int line = t->line_no[r];
    if (!(v[2] > 0.0))
        return btf__fail(err, BTF_E_DATA, "%s:%d: camera below the surface (cam_z %g; expected > 0, "
                         "z along the surface normal towards the camera)", path, line, v[2]);
    if (!(v[5] > 0.0))
        return btf__fail(err, BTF_E_DATA, "%s:%d: light below the surface (light_z %g; expected > 0)",
                         path, line, v[5]);
    if (!(v[6] > 0.0) || !(v[7] > 0.0))
        return btf__fail(err, BTF_E_DATA, "%s:%d: image size %g x %g (expected both > 0: the "
                         "sample's width and height the image covers, in the positions' unit)",
                         path, line, v[6], v[7]);
    *nf = (btf_near_field){.on = 1, .camera = {v[0], v[1], v[2]}, .light = {v[3], v[4], v[5]},
                           .size_x = v[6], .size_y = v[7]};
    double spread = btf__near_field_spread(nf);
    if (!(spread <= BTF_NEAR_FIELD_MAX_SPREAD))
        return btf__fail(err, BTF_E_DATA, "%s:%d: the directions change by %.1f degrees across the "
                         "image (at most %g: one image is one (view, light) pair after the "
                         "fall-off correction); crop it to a smaller patch", path, line, spread,
                         BTF_NEAR_FIELD_MAX_SPREAD);
    return BTF_OK;
}

static btf_status read_manifest(btf_dataset_entries *l, const char *path, btf_error *err)
{
    btf_tsv t;
    btf_status rc = btf__tsv_read(path, &t, err);
    if (rc)
        return rc;
    static const char *cols[5] = {"path", "theta_l", "phi_l", "theta_v", "phi_v"};
    /* Positions (a near-field capture) when the header names cam_x. */
    int near = btf__tsv_column(&t, "cam_x") >= 0;
    int c[9];
    for (int i = 0; i < (near ? 9 : 5); i++)
        if ((c[i] = btf__tsv_column(&t, near ? NEAR_COLS[i] : cols[i])) < 0) {
            btf__tsv_free(&t);
            if (near)
                return btf__fail(err, BTF_E_FORMAT,
                                 "%s: near-field manifest header lacks the column '%s' (expected: "
                                 "path cam_x cam_y cam_z light_x light_y light_z size_x size_y, "
                                 "tab-separated)", path, NEAR_COLS[i]);
            return btf__fail(err, BTF_E_FORMAT,
                             "%s: manifest header lacks the column '%s' (expected: path theta_l "
                             "phi_l theta_v phi_v, tab-separated; or, for a near-field capture, "
                             "path cam_x cam_y cam_z light_x light_y light_z size_x size_y)",
                             path, cols[i]);
        }
    if (near && btf__tsv_column(&t, "theta_l") >= 0) {
        btf__tsv_free(&t);
        return btf__fail(err, BTF_E_FORMAT, "%s: manifest gives both directions (theta_l ...) and "
                         "positions (cam_x ...); give one of the two", path);
    }
    char base[BTF_DATASET_PATH_MAX];
    snprintf(base, sizeof base, "%s", path);
    char *slash = strrchr(base, '/');
    if (slash)
        slash[1] = '\0';
    else
        snprintf(base, sizeof base, ".");
    l->layout = BTF_LAYOUT_MANIFEST;
    for (int r = 0; rc == BTF_OK && r < t.nrows; r++) {
        double v[4];
        btf_near_field nf = {0};
        if (near) {
            rc = near_row(&t, path, r, c, &nf, err);
            if (rc == BTF_OK) {
                btf_dir L = btf__near_field_dir(nf.light), V = btf__near_field_dir(nf.camera);
                v[0] = L.theta, v[1] = L.phi, v[2] = V.theta, v[3] = V.phi;
            }
        }
        for (int i = 0; !near && rc == BTF_OK && i < 4; i++)
            rc = btf__tsv_number(&t, path, r, c[i + 1], &v[i], err);
        if (rc)
            break;
        const char *p = btf__tsv_cell(&t, r, c[0]);
        char full[BTF_DATASET_PATH_MAX];
        if (p[0] == '/')
            snprintf(full, sizeof full, "%s", p);
        else
            rc = btf__path_join(full, sizeof full, base, p, err);
        if (rc == BTF_OK && (v[0] < 0 || v[0] > 90 || v[2] < 0 || v[2] > 90))
            rc = btf__fail(err, BTF_E_DATA, "%s:%d: theta outside [0, 90]", path, t.line_no[r]);
        if (rc == BTF_OK)
            rc = btf__dataset_entries_add(l, full, (btf_dir){v[0], v[1]}, (btf_dir){v[2], v[3]},
                                          err);
        if (rc == BTF_OK)
            l->items[l->count - 1].near = nf;
    }
    if (rc == BTF_OK && t.nrows == 0)
        rc = btf__fail(err, BTF_E_DATA, "%s: manifest lists no images", path);
    if (rc == BTF_OK && l->count == t.nrows)
        rc = no_duplicate_paths(l, &t, path, err);
    btf__tsv_free(&t);
    return rc;
}

btf_status btf__dataset_list_entries(const char *path, btf_dataset_entries *l, btf_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return btf__fail(err, BTF_E_IO, "%s: %s", path, strerror(errno));
    if (S_ISREG(st.st_mode) && btf__rti_lp_name(path))
        return btf__rti_lp_read(path, l, err); /* an RTI light file (dataset/rti_lp.c) */
    if (!S_ISDIR(st.st_mode))
        return read_manifest(l, path, err);
    btf_status rc = scan_folder(l, path, NULL, err);
    if (rc == BTF_OK && l->count == 0)
        rc = btf__fail(err, BTF_E_FORMAT,
                       "%s: unknown layout: no UBO2003 ('NNNNN tlAAA plBBB tvCCC pvDDD.jpg') or "
                       "UTIA ('tvCCC_pvDDD/tlAAA_plBBB_tvCCC_pvDDD.png|exr') images; for other "
                       "layouts pass a manifest .tsv", path);
    return rc;
}
