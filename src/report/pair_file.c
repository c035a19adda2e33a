/*
 * pair_file.c — a measured pair's picture in a report folder: its name,
 * shared by the measurement (which writes it) and the page and JSON
 * writers (which name it), so that the three agree; and the picture itself
 * (measured | model), the same for every family's report.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/report_base.h"

#include <stdio.h>
#include <string.h>

void btf__report_pair_file(int view, int light, char *buf, size_t n)
{
    snprintf(buf, n, "pair-v%02d-l%02d.png", view, light);
}

/* measured | model, side by side with a 4-pixel dark gap. */
static btf_status side_by_side(const btf_image *a, const btf_image *b, btf_image *out,
                               btf_error *err)
{
    int gap = 4, w = a->width + gap + b->width, h = a->height > b->height ? a->height : b->height;
    btf_status rc = btf_image_alloc(out, w, h, 3, err);
    if (rc)
        return rc;
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        out->data[i] = 0.02f;
    for (int y = 0; y < h; y++) {
        if (y < a->height)
            memcpy(out->data + (size_t)y * w * 3, a->data + (size_t)y * a->width * 3,
                   (size_t)a->width * 3 * sizeof(float));
        if (y < b->height)
            memcpy(out->data + ((size_t)y * w + a->width + gap) * 3,
                   b->data + (size_t)y * b->width * 3, (size_t)b->width * 3 * sizeof(float));
    }
    return BTF_OK;
}

static btf_status write_pair(const char *dir, const char *name, const btf_image *meas,
                             const btf_image *model, btf_error *err)
{
    char path[4096];
    btf_image both = {0};
    btf_status rc = btf__path_join(path, sizeof path, dir, name, err);
    if (rc == BTF_OK)
        rc = side_by_side(meas, model, &both, err);
    if (rc == BTF_OK)
        rc = btf_image_write_png(path, &both, err);
    btf_image_free(&both);
    return rc;
}

btf_status btf__report_picture(btf_report_base *r, const char *dir, int pair, int view, int light,
                               const btf_image *measured, const btf_image *model, btf_error *err)
{
    char name[64];
    btf__report_pair_file(view, light, name, sizeof name);
    btf_status rc = write_pair(dir, name, measured, model, err);
    r->pictured[pair] = rc == BTF_OK;
    return rc;
}
