/*
 * ps_write.c — the range-map stage's results on disk (Haindl & Filip 2007,
 * section II.B): normals, albedo and height as float EXR for programs, each
 * with a PNG preview for people (ps_preview.c). The six files are written
 * into a temporary sibling folder and moved into place as a set
 * (btf_output_dir_begin/commit): a failure or an interrupt leaves none.
 */
#include "range/range.h"
#include "core/core.h"

#include <stdio.h>

/* name.exr from exr and name.png from png, in outdir. */
static btf_status write_pair(const char *outdir, const char *name, const btf_image *exr,
                             const btf_image *png, btf_error *err)
{
    char path[4096], file[64];
    btf_status rc;
    snprintf(file, sizeof file, "%s.exr", name);
    if ((rc = btf__path_join(path, sizeof path, outdir, file, err)) ||
        (rc = btf_image_write_exr_opts(path, exr, NULL, NULL, err)))
        return rc;
    snprintf(file, sizeof file, "%s.png", name);
    if ((rc = btf__path_join(path, sizeof path, outdir, file, err)) ||
        (rc = btf_image_write_png(path, png, err)))
        return rc;
    return BTF_OK;
}

btf_status btf_ps_write(const btf_ps_result *r, const btf_image *mask, const char *outdir,
                        btf_error *err)
{
    if (!r || !outdir || !r->normal.data || !r->albedo.data || !r->height.data)
        return btf__fail(err, BTF_E_ARG,
                         "photostereo: nothing to write (empty result or no folder)");
    btf_output_dir *od;
    btf_status rc = btf_output_dir_begin(outdir, &od, err);
    if (rc)
        return rc;
    const char *dir = btf_output_dir_path(od);
    btf_image prev = {0};
    if ((rc = btf__normals_preview(&r->normal, &prev, err)) == BTF_OK)
        rc = write_pair(dir, "normals", &r->normal, &prev, err);
    btf_image_free(&prev);
    if (rc == BTF_OK)
        rc = write_pair(dir, "albedo", &r->albedo, &r->albedo, err);
    if (rc == BTF_OK && (rc = btf__height_relief(&r->height, mask, &prev, err)) == BTF_OK)
        rc = write_pair(dir, "height", &r->height, &prev, err);
    btf_image_free(&prev);
    if (rc) {
        btf_output_dir_fail(od, err);
        return rc;
    }
    return btf_output_dir_commit(od, err);
}
