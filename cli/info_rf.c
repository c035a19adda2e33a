/*
 * info_rf.c — btfcar info on a reflectance-field model (Meseth, Müller &
 * Klein 2003; docs/rf.md): the fit, its size, the direction sets, the bytes
 * per texel, and the quantisation ranges of each parameter slot over the
 * fields, as text or (--json) one JSON document ("format":
 * "btfcar-rf-model"); of a sampled model (the paper's section 6) also the
 * sample, the surface its coordinate map covers and what each costs.
 * cmd_info.c recognises the file by its signature.
 */
#include "info.h"

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

int cli_info_rf(cli_ctx *c, const model_file *mf, int json)
{
    btf_error err = {0};
    btf_rf_model m;
    if (btf_rf_read(mf->path, &m, &err) != 0)
        return cli_lib_error(c, &err);
    double texels = (double)m.width * m.height;
    double code_bytes = (double)m.fields * m.slots * 2.0;
    btf_rf_bytes b;
    if (btf_rf_model_bytes(&m, &b, &err) != 0) {
        btf_rf_model_free(&m);
        return cli_lib_error(c, &err);
    }
    int sw, sh;
    btf_rf_surface_size(&m, &sw, &sh);
    if (json) {
        printf("{\"format\": \"btfcar-rf-model\", \"version\": [%u, %u], \"file\": ", mf->major,
               mf->minor);
        cli_json_string(stdout, mf->path);
        printf(", \"file_bytes\": %lld, \"fit\": \"%s\", \"lobes\": %d, \"width\": %d, "
               "\"height\": %d,\n \"params\": %d, \"slots\": %d, \"fields\": %d, "
               "\"bytes_per_texel\": %.6g, \"code_bytes_per_texel\": %.6g,\n \"views\": ",
               mf->bytes, btf_rf_fit_name(m.fit), m.lobes, m.width, m.height, m.params,
               m.slots, m.fields, mf->bytes / texels, code_bytes);
        cli_json_dirset(stdout, &m.views);
        printf(",\n \"lights\": ");
        cli_json_dirset(stdout, &m.lights);
        printf(",\n \"surface_width\": %d, \"surface_height\": %d, \"coefficient_bytes\": "
               "%llu, \"map_bytes\": %llu, \"file_map_bytes\": %llu, \"sample\": ", sw, sh,
               (unsigned long long)b.coefficients, (unsigned long long)b.map,
               (unsigned long long)b.file_map);
        if (m.map)
            printf("{\"x\": %d, \"y\": %d, \"width\": %d, \"height\": %d}", m.sample_x,
                   m.sample_y, m.width, m.height);
        else
            printf("null");
        printf(",\n \"slot_ranges\": [");
        for (int s = 0; s < m.slots; s++) {
            char name[32];
            float lo = m.lo[s], hi = m.hi[s];
            for (int f = 1; f < m.fields; f++) {
                lo = m.lo[f * m.slots + s] < lo ? m.lo[f * m.slots + s] : lo;
                hi = m.hi[f * m.slots + s] > hi ? m.hi[f * m.slots + s] : hi;
            }
            printf("%s\n  {\"slot\": ", s ? "," : "");
            cli_json_string(stdout, slot_name(&m, s, name, sizeof name));
            printf(", \"min\": ");
            cli_json_f32(stdout, lo);
            printf(", \"max\": ");
            cli_json_f32(stdout, hi);
            printf("}");
        }
        printf("]}\n");
    } else {
        char vs[256], ls[256];
        cli_describe_set(&m.views, vs, sizeof vs);
        cli_describe_set(&m.lights, ls, sizeof ls);
        printf("reflectance-field model %s (format %u.%u, %lld bytes)\n", mf->path, mf->major,
               mf->minor, mf->bytes);
        if (m.fit == BTF_RF_PTM)
            printf("fit         ptm: a biquadratic polynomial in the light's (lu, lv) per view "
                   "and texel\n");
        else if (m.fit == BTF_RF_LOBES)
            printf("fit         lobes: %d non-linear lobe%s rho <d, l>^n per view and texel\n",
                   m.lobes, m.lobes == 1 ? "" : "s");
        else
            printf("fit         lafortune: rho_d l_z + %d Lafortune lobe%s per texel over all "
                   "views\n", m.lobes, m.lobes == 1 ? "" : "s");
        printf("texels      %d x %d\n", m.width, m.height);
        if (m.map) {
            printf("sample      the texels above are a sample at (%d, %d) of the data; a %d x %d "
                   "coordinate map into it (image quilting, paper section 6) is the surface\n",
                   m.sample_x, m.sample_y, sw, sh);
            printf("memory      %llu bytes of coefficients + %llu bytes of coordinate map "
                   "(%llu in all; in the file %lld, of which the map %llu)\n",
                   (unsigned long long)b.coefficients, (unsigned long long)b.map,
                   (unsigned long long)(b.coefficients + b.map), mf->bytes,
                   (unsigned long long)b.file_map);
        }
        printf("views       %s\n", vs);
        printf("lights      %s\n", ls);
        printf("fields      %d, each %d luminance parameters + 3 chromaticity factors per texel, "
               "16-bit codes\n", m.fields, m.params);
        printf("per texel   %.1f bytes of codes, %.1f bytes in the file\n", code_bytes,
               mf->bytes / texels);
        printf("slot ranges (over every field):\n");
        for (int s = 0; s < m.slots; s++) {
            char name[32];
            float lo = m.lo[s], hi = m.hi[s];
            for (int f = 1; f < m.fields; f++) {
                lo = m.lo[f * m.slots + s] < lo ? m.lo[f * m.slots + s] : lo;
                hi = m.hi[f * m.slots + s] > hi ? m.hi[f * m.slots + s] : hi;
            }
            printf("  %-16s %12.6g .. %-12.6g\n", slot_name(&m, s, name, sizeof name), lo, hi);
        }
    }
    btf_rf_model_free(&m);
    if (fflush(stdout) != 0)
        return cli_error(c, "cannot write the output");
    return 0;
}
