/*
 * jpeg_contrast.c — the subspace-image contrast of the report's compression
 * accounting (docs/report-compression.md): what plain image coding of the model's own
 * reduction would store. The model keeps one representative measured image
 * per subspace (m->subspaces[k].view, .light) and the index table that maps
 * every (view, light) pair to a subspace; here those images are read from
 * the dataset and encoded as JPEG in memory (io/png_jpeg_encode.c, 8-bit
 * sRGB, 4:2:0 as libjpeg's defaults), and the index table is counted at one
 * byte per pair. The JPEGs are decoded again to state their error in 8-bit
 * sRGB levels. docs/report-compression.md.
 */
#include "io/io.h"
#include "report/report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_QUALITY 90

/* One subspace image: encoded size and squared error summed. */
static btf_status one_image(const btf_dataset *ds, int view, int light, int quality,
                            const btf_srgb_levels_table *t, uint64_t *bytes, double *sq,
                            btf_error *err)
{
    btf_image img = {0};
    btf_status rc = btf_dataset_read(ds, view, light, &img, err);
    if (rc)
        return rc;
    const char *name = btf_dataset_path(ds, view, light);
    size_t n = (size_t)img.width * img.height * 3;
    float *lv = btf__alloc(n, sizeof *lv, NULL);
    unsigned char *px = btf__alloc(n, 1, NULL);
    unsigned char *enc = NULL;
    size_t len = 0;
    btf_decoded dec = {0};
    if (!lv || !px) {
        rc = btf__fail(err, BTF_E_NOMEM, "%s: out of memory", name);
        goto done;
    }
    if (img.channels != 3) {
        rc = btf__fail(err, BTF_E_DATA, "%s: %d channels (expected RGB)", name, img.channels);
        goto done;
    }
    btf__srgb_levels(t, img.data, n, lv);
    for (size_t i = 0; i < n; i++) /* as btf_image_write_jpeg rounds */
        px[i] = (unsigned char)lrintf(btf__linear_to_srgb(img.data[i]) * 255.0f);
    char msg[256];
    if (btf__png_jpeg_encode(BTF_FILE_JPEG, img.width, img.height, 3, px, quality, &enc, &len,
                             msg, sizeof msg) != 0) {
        rc = btf__fail(err, BTF_E_DATA, "%s: cannot encode as JPEG: %s", name, msg);
        goto done;
    }
    if ((rc = btf__png_jpeg_decode(enc, len, BTF_FILE_JPEG, name, &dec, err)))
        goto done;
    if (dec.width != img.width || dec.height != img.height || dec.channels != 3 || dec.depth16) {
        rc = btf__fail(err, BTF_E_DATA, "%s: the JPEG decoded to %dx%d of %d channels", name,
                       dec.width, dec.height, dec.channels);
        goto done;
    }
    const unsigned char *back = dec.pixels;
    double s = 0;
    for (size_t i = 0; i < n; i++) {
        double e = (double)back[i] - lv[i];
        s += e * e;
    }
    *bytes += len;
    *sq += s;
done:
    btf_image_free(&img);
    BTF_FREE_ALL(lv, px, enc, dec.pixels);
    return rc;
}

btf_status btf__jpeg_subspace_contrast(const btf_dataset *ds, const btf_model *m, int quality,
                                       btf_jpeg_contrast *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "dataset: no JPEG contrast to fill");
    memset(out, 0, sizeof *out);
    if (!ds || !m)
        return btf__fail(err, BTF_E_ARG, "dataset: the JPEG contrast needs a dataset and a model");
    const btf_dataset_info *info = btf_dataset_get_info(ds);
    if (quality == 0)
        quality = DEFAULT_QUALITY;
    if (quality < 1 || quality > 100)
        return btf__fail(err, BTF_E_ARG, "%s: JPEG quality %d (expected 1..100)", info->root,
                         quality);
    if (!m->index)
        return btf__fail(err, BTF_E_DATA, "%s: the model has no index table", info->root);
    if (m->n_subspaces < 1 || !m->subspaces)
        return btf__fail(err, BTF_E_DATA, "%s: the model has no subspaces", info->root);
    /* Each representative pair in the dataset's own indices: the same sets,
     * or (a model of some of its pairs) the same directions. */
    int *at = btf__alloc((size_t)m->n_subspaces, 2 * sizeof(int), err);
    if (!at)
        return BTF_E_NOMEM;
    for (int k = 0; k < m->n_subspaces; k++) {
        const btf_subspace_model *s = &m->subspaces[k];
        int v = -1, l = -1;
        if (s->view >= 0 && s->view < m->views.count && s->light >= 0 &&
            s->light < m->lights.count) {
            v = btf_dirset_find(info->views, m->views.dirs[s->view], BTF_DIR_NAME_TOLERANCE);
            l = btf_dirset_find(info->lights, m->lights.dirs[s->light], BTF_DIR_NAME_TOLERANCE);
        }
        if (v < 0 || l < 0 || !btf_dataset_has(ds, v, l)) {
            free(at);
            return btf__fail(err, BTF_E_DATA,
                             "%s: subspace %d's representative pair (view %d, light %d of the "
                             "model) is not in the dataset", info->root, k, s->view, s->light);
        }
        at[2 * k] = v, at[2 * k + 1] = l;
    }
    btf_srgb_levels_table t;
    btf__srgb_levels_init(&t);
    uint64_t bytes = 0;
    double sq = 0;
    for (int k = 0; k < m->n_subspaces; k++) {
        btf_status rc = one_image(ds, at[2 * k], at[2 * k + 1], quality, &t, &bytes, &sq, err);
        if (rc) {
            free(at);
            memset(out, 0, sizeof *out);
            return rc;
        }
    }
    free(at);
    btf__raw_bytes_of(info, &out->raw);
    out->images = m->n_subspaces;
    out->quality = quality;
    out->jpeg_bytes = bytes;
    out->index_bytes = (uint64_t)m->views.count * m->lights.count;
    out->bytes = out->jpeg_bytes + out->index_bytes;
    out->rms = sqrt(sq / ((double)m->n_subspaces * info->width * info->height * 3));
    out->ratio = (double)out->raw.raw / (double)out->bytes;
    return BTF_OK;
}
