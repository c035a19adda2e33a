/*
 * model_cells.c — the CELL section (format 1.7, docs/model-format.md,
 * "CELL"): the remainders' periodic cells (model/structure_cells.c). The
 * cell's geometry, then per subspace whether it keeps a cell, then each
 * kept cell's factors as the albedo pattern's one-byte codes, each minus
 * the previous texel's code of its channel (raster order), modulo 256:
 * a cell is smooth along its rows, so the residuals deflate well.
 */
#include "model/model_file.h"

#include <stdlib.h>
#include <string.h>

btf_status btf__model_put_cells(btf_box_writer *w, const btf_model *m, const char *name,
                                btf_error *err)
{
    (void)name, (void)err;
    const btf_cells *c = btf__model_cells(m);
    size_t texels = (size_t)c->w * c->h;
    size_t body = btf__box_section_begin(w, btf__model_tags[S_CELL]);
    btf__box_part(w, BTF_MODEL_PART_CELLS);
    btf__box_put_u16(w, (unsigned)c->w);
    btf__box_put_u16(w, (unsigned)c->h);
    btf__box_put_u16(w, (unsigned)c->shift);
    btf__box_put_u16(w, (unsigned)c->n_subspaces);
    for (int k = 0; k < c->n_subspaces; k++)
        btf__box_put_u8(w, c->kept[k] ? 1u : 0u);
    for (int k = 0; k < c->n_subspaces; k++) {
        if (!c->kept[k])
            continue;
        const float *v = btf__cells_of(c, k);
        unsigned prev[3] = {0, 0, 0};
        for (size_t i = 0; i < texels * 3; i++) {
            unsigned q = btf__albedo_code(v[i]);
            btf__box_put_u8(w, (q - prev[i % 3]) & 0xffu);
            prev[i % 3] = q;
        }
    }
    btf__box_section_end(w, body);
    return BTF_OK;
}

/* The geometry and the kept flags, checked before anything is allocated. */
static btf_status read_cells_head(btf_box_reader *r, const btf_model *m, int *geo,
                                  const unsigned char **kept, const char *name, btf_error *err)
{
    for (int i = 0; i < 4; i++)
        geo[i] = (int)btf__box_read_u16(r);
    *kept = btf__box_take(r, (size_t)(geo[3] > 0 ? geo[3] : 0));
    if (r->short_read || !*kept)
        return btf__model_short(S_CELL, name, err);
    if (!m->albedo)
        return failf(err, BTF_E_FORMAT, name, "section CELL without a structure layer "
                     "(expected STRC)");
    if (geo[0] < 1 || geo[1] < 1 || (long)geo[0] * geo[1] > BTF_CELLS_MAX_TEXELS ||
        geo[2] >= geo[0])
        return failf(err, BTF_E_FORMAT, name, "section CELL: a cell of %d x %d texels, shift "
                     "%d (expected 1..%d texels, a shift below the width)", geo[0], geo[1],
                     geo[2], BTF_CELLS_MAX_TEXELS);
    if (geo[3] != m->n_subspaces)
        return failf(err, BTF_E_FORMAT, name, "section CELL: %d subspaces (expected SUBS's %d)",
                     geo[3], m->n_subspaces);
    size_t n_kept = 0, texels = (size_t)geo[0] * geo[1];
    for (int k = 0; k < geo[3]; k++) {
        if ((*kept)[k] > 1)
            return failf(err, BTF_E_FORMAT, name, "section CELL: subspace %d's flag is %u "
                         "(expected 0 or 1)", k, (*kept)[k]);
        n_kept += (*kept)[k];
    }
    if (n_kept == 0 || r->n - r->pos != n_kept * texels * 3)
        return failf(err, BTF_E_FORMAT, name, "section CELL: %zu cells in %zu bytes (expected "
                     "at least 1 cell, %zu bytes each)", n_kept, r->n - r->pos, texels * 3);
    return BTF_OK;
}

btf_status btf__model_read_cells(const btf_box_span *sp, btf_model *m, const char *name,
                                 btf_error *err)
{
    btf_box_reader r = {sp->p, sp->n, 0, 0};
    int geo[4];
    const unsigned char *kept;
    btf_status rc = read_cells_head(&r, m, geo, &kept, name, err);
    if (rc)
        return rc;
    btf_error e = {0};
    btf_cells *c = btf__cells_new(geo[0], geo[1], geo[2], geo[3], &e);
    if (!c)
        return failf(err, BTF_E_NOMEM, name, "out of memory reading section CELL");
    size_t texels = (size_t)c->w * c->h;
    for (int k = 0; k < c->n_subspaces; k++) {
        if (!(c->kept[k] = kept[k]))
            continue;
        const unsigned char *res = btf__box_take(&r, texels * 3);
        float *v = c->value + (size_t)k * texels * 3;
        unsigned prev[3] = {0, 0, 0};
        for (size_t i = 0; i < texels * 3; i++) {
            unsigned q = (res[i] + prev[i % 3]) & 0xffu;
            v[i] = btf__albedo_value(q);
            prev[i % 3] = q;
        }
    }
    return btf__model_set_cells(m, c, err);
}
