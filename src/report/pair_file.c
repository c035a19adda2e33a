/*
 * pair_file.c — a measured pair's picture in a report folder: its name,
 * shared by the orchestration (which writes it) and the page and JSON
 * writers (which name it), so that the three agree; and the picture itself
 * (measured | model), the same for the CAR and the reflectance-field
 * reports.
 */
#include "core/core.h"
#include "report/report.h"
#include "report/report_data.h"

#include <stdio.h>
#include <string.h>

void btf_report_pair_file(const btf_report_data *d, int pair, char *buf, size_t n)
{
    const btf_pair_quality *p = &d->q.pairs[pair];
    snprintf(buf, n, "pair-v%02d-l%02d.png", p->view, p->light);
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

btf_status btf_report_write_pair(const char *dir, const char *name, const btf_image *meas,
                                 const btf_image *model, btf_error *err)
{
    char path[4096];
    btf_image both = {0};
    btf_status rc = btf_path_join(path, sizeof path, dir, name, err);
    if (rc == BTF_OK)
        rc = side_by_side(meas, model, &both, err);
    if (rc == BTF_OK)
        rc = btf_image_write_png(path, &both, err);
    btf_image_free(&both);
    return rc;
}
