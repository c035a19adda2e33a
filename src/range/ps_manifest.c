/*
 * ps_manifest.c — photometric stereo (Haindl & Filip 2007, section II.B)
 * on ordinary captures listed in a manifest: a TSV file (read by io/tsv.c)
 * with a header line naming its columns: path (relative to the manifest's
 * folder, or absolute), the light as theta_l, phi_l (degrees) or as lx,
 * ly, lz (a vector), optionally r, g, b (the light's intensity), and
 * optionally theta_v, phi_v (the view: a BTF manifest of several views gives
 * the images of one view, never a mix; each file once). The
 * table is turned into lights, intensities and paths here; the run itself
 * is photostereo.c's. Every message names the manifest, and a bad value its
 * line and column, since a person wrote the file.
 */
#include "range/range.h"
#include "io/io.h"
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The manifest's columns; -1 when absent. */
typedef struct manifest_columns {
    int path, theta, phi, lx, ly, lz, r, g, b, theta_v, phi_v;
} manifest_columns;

/* What a manifest describes: count images, their lights and intensities. */
typedef struct manifest {
    int count;
    double *lights;       /* count x 3 */
    double *intensity;    /* count x 3, or NULL without r g b columns */
    char **paths;         /* count, resolved against the manifest's folder */
    btf_dir *views;       /* count, or NULL without theta_v phi_v columns */
} manifest;

static btf_status find_columns(const btf_tsv *t, const char *path, manifest_columns *c,
                               btf_error *err)
{
    c->path = btf__tsv_column(t, "path");
    c->theta = btf__tsv_column(t, "theta_l");
    c->phi = btf__tsv_column(t, "phi_l");
    c->lx = btf__tsv_column(t, "lx");
    c->ly = btf__tsv_column(t, "ly");
    c->lz = btf__tsv_column(t, "lz");
    c->r = btf__tsv_column(t, "r");
    c->g = btf__tsv_column(t, "g");
    c->b = btf__tsv_column(t, "b");
    c->theta_v = btf__tsv_column(t, "theta_v");
    c->phi_v = btf__tsv_column(t, "phi_v");
    if ((c->theta_v >= 0) != (c->phi_v >= 0))
        return btf__fail(err, BTF_E_FORMAT, "%s: incomplete columns: give theta_v and phi_v "
                         "together or not at all", path);
    if (c->path < 0)
        return btf__fail(err, BTF_E_FORMAT, "%s: no 'path' column in the header line", path);
    int angles = (c->theta >= 0) + (c->phi >= 0), vec = (c->lx >= 0) + (c->ly >= 0) + (c->lz >= 0);
    int rgb = (c->r >= 0) + (c->g >= 0) + (c->b >= 0);
    if (angles == 1 || (vec != 0 && vec != 3) || (rgb != 0 && rgb != 3))
        return btf__fail(err, BTF_E_FORMAT, "%s: incomplete columns: give theta_l and phi_l, or "
                         "lx, ly and lz, and r, g, b together or not at all", path);
    if (angles == 2 && vec == 3)
        return btf__fail(err, BTF_E_FORMAT, "%s: both theta_l/phi_l and lx/ly/lz columns: give "
                         "the light one way only", path);
    if (angles == 0 && vec == 0)
        return btf__fail(err, BTF_E_FORMAT, "%s: no light columns (theta_l, phi_l or lx, ly, lz)",
                         path);
    return BTF_OK;
}

/* Row `row`'s light into light[3] and, with r g b columns, its intensity
 * into intensity[3] (NULL otherwise). */
static btf_status read_row(const btf_tsv *t, const char *path, int row, const manifest_columns *c,
                           double *light, double *intensity, btf_error *err)
{
    btf_status rc;
    if (c->theta >= 0) {
        btf_dir d;
        if ((rc = btf__tsv_number(t, path, row, c->theta, &d.theta, err)) ||
            (rc = btf__tsv_number(t, path, row, c->phi, &d.phi, err)))
            return rc;
        if (d.theta < 0.0 || d.theta > 90.0)
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: theta_l %g out of range 0..90 degrees",
                             path, t->line_no[row], d.theta);
        btf_dir_to_vec(d, light);
    } else {
        int cols[3] = {c->lx, c->ly, c->lz};
        for (int k = 0; k < 3; k++)
            if ((rc = btf__tsv_number(t, path, row, cols[k], &light[k], err)))
                return rc;
        double len = sqrt(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
        if (!(len > 1e-12) || !isfinite(len))
            return btf__fail(err, BTF_E_FORMAT, "%s:%d: light (%g, %g, %g) is not a non-zero "
                             "finite vector", path, t->line_no[row], light[0], light[1], light[2]);
    }
    if (intensity) {
        int cols[3] = {c->r, c->g, c->b};
        for (int k = 0; k < 3; k++) {
            if ((rc = btf__tsv_number(t, path, row, cols[k], &intensity[k], err)))
                return rc;
            if (!(intensity[k] > 0.0))
                return btf__fail(err, BTF_E_FORMAT, "%s:%d: intensity %s = %g must be positive",
                                 path, t->line_no[row], t->names[cols[k]], intensity[k]);
        }
    }
    return BTF_OK;
}

/* Row `row`'s view (theta_v, phi_v columns) into *d. */
static btf_status read_view(const btf_tsv *t, const char *path, int row, const manifest_columns *c,
                            btf_dir *d, btf_error *err)
{
    btf_status rc;
    if ((rc = btf__tsv_number(t, path, row, c->theta_v, &d->theta, err)) ||
        (rc = btf__tsv_number(t, path, row, c->phi_v, &d->phi, err)))
        return rc;
    if (!(d->theta >= 0.0 && d->theta <= 90.0) || !(d->phi >= 0.0 && d->phi < 360.0))
        return btf__fail(err, BTF_E_FORMAT, "%s:%d: view theta_v %g phi_v %g out of range "
                         "(theta 0..90, phi 0..360 degrees)", path, t->line_no[row], d->theta,
                         d->phi);
    return BTF_OK;
}

/* The same file under two rows (two lights, or two views) would weigh one
 * image twice or mix views: an error naming both lines. */
static btf_status no_duplicate_paths(const btf_tsv *t, const char *path, const manifest *m,
                                     btf_error *err)
{
    int first, again;
    btf_status rc = btf__first_repeat((const char *const *)m->paths, m->count, &first, &again,
                                      err);
    if (rc == BTF_OK && first >= 0)
        rc = btf__fail(err, BTF_E_FORMAT, "%s:%d: %s is listed again (first on line %d); "
                       "each image once", path, t->line_no[again], m->paths[again],
                       t->line_no[first]);
    return rc;
}

/* A manifest's relative path, from the manifest's folder. */
static btf_status resolve_path(const char *manifest_path, const char *rel, char **out,
                               btf_error *err)
{
    if (!*rel)
        return btf__fail(err, BTF_E_FORMAT, "%s: empty path", manifest_path);
    const char *slash = strrchr(manifest_path, '/');
    size_t dl = rel[0] == '/' || !slash ? 0 : (size_t)(slash - manifest_path) + 1;
    size_t rl = strlen(rel);
    char *p = btf__alloc(dl + rl + 1, 1, err);
    if (!p)
        return BTF_E_NOMEM;
    memcpy(p, manifest_path, dl);
    memcpy(p + dl, rel, rl + 1);
    *out = p;
    return BTF_OK;
}

static void manifest_free(manifest *m)
{
    for (int i = 0; m->paths && i < m->count; i++)
        free(m->paths[i]);
    BTF_FREE_ALL(m->paths, m->lights, m->intensity, m->views);
    memset(m, 0, sizeof *m);
}

/* The table t read from the manifest at path into m (freed on failure). */
static btf_status manifest_parse(const btf_tsv *t, const char *path, manifest *m, btf_error *err)
{
    memset(m, 0, sizeof *m);
    manifest_columns c;
    btf_status rc = find_columns(t, path, &c, err);
    if (rc)
        return rc;
    int n = t->nrows;
    if (n < 3)
        return btf__fail(err, BTF_E_FORMAT, "%s: %d images; photometric stereo needs at least 3",
                         path, n);
    m->count = n;
    m->lights = btf__alloc((size_t)n * 3, sizeof(double), err);
    m->intensity = c.r >= 0 ? btf__alloc((size_t)n * 3, sizeof(double), err) : NULL;
    m->paths = btf__calloc((size_t)n, sizeof(char *), err);
    if (!m->lights || !m->paths || (c.r >= 0 && !m->intensity))
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK && c.theta_v >= 0 && !(m->views = btf__alloc((size_t)n, sizeof(btf_dir), err)))
        rc = BTF_E_NOMEM;
    for (int i = 0; i < n && rc == BTF_OK; i++) {
        rc = read_row(t, path, i, &c, m->lights + 3 * i,
                      m->intensity ? m->intensity + 3 * i : NULL, err);
        if (rc == BTF_OK && m->views)
            rc = read_view(t, path, i, &c, &m->views[i], err);
        if (rc == BTF_OK)
            rc = resolve_path(path, btf__tsv_cell(t, i, c.path), &m->paths[i], err);
    }
    if (rc == BTF_OK)
        rc = no_duplicate_paths(t, path, m, err);
    if (rc)
        manifest_free(m);
    return rc;
}

/* Keeps only the rows of one view: the one nearest want, or nearest the
 * normal (the first of equals); *view its index among the distinct views in
 * the order of first appearance. A manifest without view columns is one
 * view (-1). */
static btf_status manifest_keep_view(manifest *m, const char *path, const btf_dir *want,
                                     int *view, btf_dir *view_dir, btf_error *err)
{
    *view = -1;
    if (!m->views) {
        if (want)
            return btf__fail(err, BTF_E_ARG, "%s: a view was asked for but the manifest has no "
                             "theta_v and phi_v columns (one view)", path);
        return BTF_OK;
    }
    btf_dir *distinct = btf__alloc((size_t)m->count, sizeof(btf_dir), err);
    if (!distinct)
        return BTF_E_NOMEM;
    int nd = 0;
    for (int i = 0; i < m->count; i++) {
        int k = 0;
        while (k < nd && !(distinct[k].theta == m->views[i].theta &&
                           distinct[k].phi == m->views[i].phi))
            k++;
        if (k == nd)
            distinct[nd++] = m->views[i];
    }
    int v = -1; /* left unset when no view is near want */
    btf_status rc = btf__ps_pick_view(distinct, nd, want, path, &v, err);
    btf_dir d = distinct[rc || v < 0 ? 0 : v];
    free(distinct);
    if (rc)
        return rc;
    int kept = 0;
    for (int i = 0; i < m->count; i++) {
        if (m->views[i].theta == d.theta && m->views[i].phi == d.phi) {
            m->paths[kept] = m->paths[i];
            memmove(m->lights + 3 * kept, m->lights + 3 * i, 3 * sizeof(double));
            if (m->intensity)
                memmove(m->intensity + 3 * kept, m->intensity + 3 * i, 3 * sizeof(double));
            m->views[kept] = m->views[i];
            kept++;
        } else {
            free(m->paths[i]);
        }
    }
    m->count = kept;
    if (kept < 3)
        return btf__fail(err, BTF_E_FORMAT, "%s: %d images of view theta_v %g phi_v %g; "
                         "photometric stereo needs at least 3", path, kept, d.theta, d.phi);
    *view = v;
    *view_dir = d;
    return BTF_OK;
}

btf_status btf__photostereo_manifest(const char *path, const btf_photostereo_opts *opts,
                                     btf_ps_result *out, btf_error *err)
{
    return btf_photostereo_manifest_view(path, NULL, opts, out, err);
}

btf_status btf_photostereo_manifest_view(const char *path, const btf_dir *want,
                                         const btf_photostereo_opts *opts, btf_ps_result *out,
                                         btf_error *err)
{
    btf_status rc = btf__ps_result_start(out, err);
    if (rc)
        return rc;
    if (!path)
        return btf__fail(err, BTF_E_ARG, "photostereo: no manifest given");
    btf_photostereo_opts zero = {0}, o;
    if (btf__opts_take(&o, sizeof o, opts, &zero, "btf_photostereo_manifest", err))
        return BTF_E_ARG;
    btf_tsv t;
    if ((rc = btf__tsv_read(path, &t, err)))
        return rc;
    manifest m;
    rc = manifest_parse(&t, path, &m, err);
    btf__tsv_free(&t);
    if (rc)
        return rc;
    int view;
    btf_dir view_dir = {0, 0};
    if ((rc = manifest_keep_view(&m, path, want, &view, &view_dir, err))) {
        manifest_free(&m);
        return rc;
    }
    /* The size comes from the first image (btf__ps_run probes it). */
    btf_ps_source src = {.name = path, .count = m.count, .paths = (const char *const *)m.paths,
                         .read = o.read, .channels = 3};
    rc = btf__ps_run(&src, m.lights, m.intensity, &o, out, err);
    out->view = view;
    out->view_dir = view_dir;
    manifest_free(&m);
    if (rc)
        btf_ps_result_free(out);
    return rc;
}
