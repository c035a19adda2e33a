/*
 * rf_bytes.c — what a reflectance-field model costs, the figure the memory
 * reduction of Meseth, Müller & Klein 2003, section 6, is about ("reduces
 * the memory requirements per material to about 25 MB (24 MB for a 64^2
 * BTF base texture [...]; less than 1 MB for a 256^2 index texture)"): the
 * sample's coefficients plus the coordinate map, in memory as the renderer
 * holds them, and in the file, where the map's share is the file less the
 * same model without its map.
 */
#include "rf/rf.h"

#include <stdlib.h>
#include <string.h>

btf_status btf_rf_model_bytes(const btf_rf_model *m, btf_rf_bytes *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_model_bytes: no output");
    memset(out, 0, sizeof *out);
    if (!m)
        return btf__fail(err, BTF_E_ARG, "btf_rf_model_bytes: no model");
    uint64_t planes = (uint64_t)m->fields * (uint64_t)m->slots;
    out->coefficients = planes * (2 * (uint64_t)m->width * (uint64_t)m->height + 8);
    if (m->map)
        out->map = 4 * (uint64_t)m->surface_width * (uint64_t)m->surface_height;
    unsigned char *data = NULL;
    size_t n = 0, n_bare = 0;
    btf_status rc = btf_rf_encode(m, &data, &n, err);
    free(data);
    if (rc)
        return rc;
    out->file = n;
    if (m->map) {
        btf_rf_model bare = *m;
        bare.map = NULL;
        data = NULL;
        rc = btf_rf_encode(&bare, &data, &n_bare, err);
        free(data);
        if (rc)
            return rc;
        out->file_map = n > n_bare ? n - n_bare : 0;
    }
    return BTF_OK;
}
