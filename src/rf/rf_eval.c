/*
 * rf_eval.c — the colour of a texel under a reflectance-field model
 * (Meseth, Müller & Klein 2003, equation (3) for one light): the
 * luminance of the field (rf.h's model functions) times the texel's
 * average colour of that field, and at an arbitrary view the four closest
 * measured views' colours weighted as section 5.4 does ("multiply the
 * resulting luminances by the average colors for the reflectance field and
 * the weights w_v, and add them"). (x, y) is a texel of the surface, through
 * a sampled model's coordinate map (section 6, rf_map.h).
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

void btf_rf_eval_field(const btf_rf_model *m, int field, btf_dir view, btf_dir light, int x,
                       int y, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!m || !m->codes || field < 0 || field >= m->fields || rf_surface_w(m) < 1 ||
        rf_surface_h(m) < 1)
        return;
    x = rf_wrap(x, rf_surface_w(m)), y = rf_wrap(y, rf_surface_h(m));
    float p[BTF_RF_MAX_SLOTS];
    rf_texel_params(m, field, rf_surface_texel(m, x, y), p);
    double l[3], v[3];
    btf_dir_to_vec(light, l);
    btf_dir_to_vec(view, v);
    double lum = rf_lum_eval(m->fit, m->lobes, p, l, v);
    for (int i = 0; i < 3; i++)
        rgb[i] = (float)(lum * p[m->params + i]);
}

void btf_rf_eval(const btf_rf_model *m, btf_dir view, btf_dir light, int x, int y, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!m || !m->codes)
        return;
    if (m->fit == BTF_RF_LAFORTUNE) {
        btf_rf_eval_field(m, 0, view, light, x, y, rgb);
        return;
    }
    int idx[4];
    double w[4], sum[3] = {0, 0, 0};
    btf_rf_view_weights(&m->views, view, idx, w);
    for (int i = 0; i < 4; i++) {
        if (w[i] == 0.0)
            continue;
        float c[3];
        btf_rf_eval_field(m, idx[i], m->views.dirs[idx[i]], light, x, y, c);
        for (int k = 0; k < 3; k++)
            sum[k] += w[i] * c[k];
    }
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)sum[k];
}
