/*
 * rf_model.c — the reflectance-field model's lifetime and vocabulary
 * (Meseth, Müller & Klein 2003, section 4.2): the fits' names, how many
 * parameters each keeps per texel and field, the options' defaults (the
 * fit's and the section 6 sample's), the surface a model describes, and
 * freeing a model.
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdlib.h>
#include <string.h>

const char *btf_rf_fit_name(int fit)
{
    static const char *const names[] = {"ptm", "lobes", "lafortune"};
    return fit >= 0 && fit < 3 ? names[fit] : NULL;
}

int btf__rf_param_count(int fit, int lobes)
{
    switch (fit) {
    case BTF_RF_PTM: return 6;
    case BTF_RF_LOBES: return lobes >= 1 && lobes <= BTF_RF_MAX_LOBES ? 4 * lobes : -1;
    case BTF_RF_LAFORTUNE: return lobes >= 1 && lobes <= BTF_RF_MAX_LOBES ? 1 + 5 * lobes : -1;
    default: return -1;
    }
}

btf_rf_opts btf_rf_defaults(void)
{
    btf_rf_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.fit = BTF_RF_PTM;
    o.lobes = 2;
    o.iterations = 40;
    o.threads = 0;
    o.memory = (size_t)256 << 20;
    return o;
}

void btf_rf_model_free(btf_rf_model *m)
{
    if (!m)
        return;
    btf_dirset_free(&m->views);
    btf_dirset_free(&m->lights);
    BTF_FREE_ALL(m->lo, m->hi, m->codes, m->map);
    memset(m, 0, sizeof *m);
}

btf_rf_sample_opts btf_rf_sample_defaults(void)
{
    btf_rf_sample_opts o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    return o;
}

void btf_rf_surface_size(const btf_rf_model *m, int *width, int *height)
{
    if (width)
        *width = m ? rf_surface_w(m) : 0;
    if (height)
        *height = m ? rf_surface_h(m) : 0;
}
