/*
 * rf_describe.c — btfcar info on a reflectance-field model (Meseth, Müller &
 * Klein 2003; docs/rf.md): the fit, its size, the direction sets, the bytes
 * per texel, and the quantisation ranges of each parameter slot over the
 * fields, as text or (--json) one JSON document ("format":
 * "btfcar-rf-model"); of a sampled model (the paper's section 6) also the
 * sample, the surface its coordinate map covers and what each costs.
 * The family's describe (src/material/: btf_material_describe).
 */
#include "material/family.h"
#include "rf/rf.h"

#include <stdlib.h>

static const char *slot_name(const btf_rf_model *m, int s, char *buf, size_t n)
{
    static const char *const ptm[6] = {"a0 (lu^2)", "a1 (lv^2)", "a2 (lu lv)", "a3 (lu)",
                                       "a4 (lv)", "a5 (1)"};
    static const char *const lobe[4] = {"rho", "x", "y", "log2 n"};
    static const char *const laf[5] = {"rho", "cx", "cy", "cz", "log2 n"};
    static const char *const chroma[3] = {"chroma r", "chroma g", "chroma b"};
    if (s >= m->params)
        snprintf(buf, n, "%s", chroma[s - m->params]);
    else if (m->fit == BTF_RF_PTM)
        snprintf(buf, n, "%s", ptm[s]);
    else if (m->fit == BTF_RF_LOBES)
        snprintf(buf, n, "lobe %d %s", s / 4 + 1, lobe[s % 4]);
    else if (s == 0)
        snprintf(buf, n, "rho_d");
    else
        snprintf(buf, n, "lobe %d %s", (s - 1) / 5 + 1, laf[(s - 1) % 5]);
    return buf;
}

/* A parameter slot's quantisation range over every field. */
static void slot_range(const btf_rf_model *m, int s, float *lo, float *hi)
{
    *lo = m->lo[s], *hi = m->hi[s];
    for (int k = 1; k < m->fields; k++) {
        *lo = m->lo[k * m->slots + s] < *lo ? m->lo[k * m->slots + s] : *lo;
        *hi = m->hi[k * m->slots + s] > *hi ? m->hi[k * m->slots + s] : *hi;
    }
}

btf_status rf_describe(const btf_rf_model *m, const describe_file *mf, FILE *f, int json,
                       btf_error *err)
{
    double texels = (double)m->width * m->height;
    double code_bytes = (double)m->fields * m->slots * 2.0;
    btf_rf_bytes b;
    btf_status rc = btf_rf_model_bytes(m, &b, err);
    if (rc)
        return rc;
    int sw, sh;
    btf_rf_surface_size(m, &sw, &sh);
    if (json) {
        fprintf(f, "{\"format\": \"btfcar-rf-model\", \"version\": [%u, %u], \"file\": ", mf->major,
                mf->minor);
        txt_json_string(f, mf->path);
        fprintf(f, ", \"file_bytes\": %lld, \"fit\": \"%s\", \"lobes\": %d, \"width\": %d, "
                "\"height\": %d,\n \"params\": %d, \"slots\": %d, \"fields\": %d, "
                "\"bytes_per_texel\": %.6g, \"code_bytes_per_texel\": %.6g,\n \"views\": ",
                mf->bytes, btf_rf_fit_name(m->fit), m->lobes, m->width, m->height, m->params,
                m->slots, m->fields, mf->bytes / texels, code_bytes);
        txt_json_dirset(f, &m->views);
        fprintf(f, ",\n \"lights\": ");
        txt_json_dirset(f, &m->lights);
        fprintf(f, ",\n \"surface_width\": %d, \"surface_height\": %d, \"coefficient_bytes\": "
                "%llu, \"map_bytes\": %llu, \"file_map_bytes\": %llu, \"sample\": ", sw, sh,
                (unsigned long long)b.coefficients, (unsigned long long)b.map,
                (unsigned long long)b.file_map);
        if (m->map)
            fprintf(f, "{\"x\": %d, \"y\": %d, \"width\": %d, \"height\": %d}", m->sample_x,
                    m->sample_y, m->width, m->height);
        else
            fprintf(f, "null");
        fprintf(f, ",\n \"slot_ranges\": [");
        for (int s = 0; s < m->slots; s++) {
            char name[32];
            float lo, hi;
            slot_range(m, s, &lo, &hi);
            fprintf(f, "%s\n  {\"slot\": ", s ? "," : "");
            txt_json_string(f, slot_name(m, s, name, sizeof name));
            fprintf(f, ", \"min\": ");
            txt_json_f32(f, lo);
            fprintf(f, ", \"max\": ");
            txt_json_f32(f, hi);
            fprintf(f, "}");
        }
        fprintf(f, "]}\n");
    } else {
        char vs[256], ls[256];
        txt_describe_set(&m->views, vs, sizeof vs);
        txt_describe_set(&m->lights, ls, sizeof ls);
        fprintf(f, "reflectance-field model %s (format %u.%u, %lld bytes)\n", mf->path, mf->major,
                mf->minor, mf->bytes);
        if (m->fit == BTF_RF_PTM)
            fprintf(f, "fit         ptm: a biquadratic polynomial in the light's (lu, lv) per view "
                    "and texel\n");
        else if (m->fit == BTF_RF_LOBES)
            fprintf(f, "fit         lobes: %d non-linear lobe%s rho <d, l>^n per view and texel\n",
                    m->lobes, m->lobes == 1 ? "" : "s");
        else
            fprintf(f, "fit         lafortune: rho_d l_z + %d Lafortune lobe%s per texel over all "
                    "views\n", m->lobes, m->lobes == 1 ? "" : "s");
        fprintf(f, "texels      %d x %d\n", m->width, m->height);
        if (m->map) {
            fprintf(f, "sample      the texels above are a sample at (%d, %d) of the data; "
                       "a %d x %d "
                    "coordinate map into it (image quilting, paper section 6) is the surface\n",
                    m->sample_x, m->sample_y, sw, sh);
            fprintf(f, "memory      %llu bytes of coefficients + %llu bytes of coordinate map "
                    "(%llu in all; in the file %lld, of which the map %llu)\n",
                    (unsigned long long)b.coefficients, (unsigned long long)b.map,
                    (unsigned long long)(b.coefficients + b.map), mf->bytes,
                    (unsigned long long)b.file_map);
        }
        fprintf(f, "views       %s\n", vs);
        fprintf(f, "lights      %s\n", ls);
        fprintf(f, "fields      %d, each %d luminance parameters + 3 chromaticity factors "
                   "per texel, "
                "16-bit codes\n", m->fields, m->params);
        fprintf(f, "per texel   %.1f bytes of codes, %.1f bytes in the file\n", code_bytes,
                mf->bytes / texels);
        fprintf(f, "slot ranges (over every field):\n");
        for (int s = 0; s < m->slots; s++) {
            char name[32];
            float lo, hi;
            slot_range(m, s, &lo, &hi);
            fprintf(f, "  %-16s %12.6g .. %-12.6g\n", slot_name(m, s, name, sizeof name), lo, hi);
        }
    }
    return BTF_OK;
}
