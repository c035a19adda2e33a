/*
 * rf_eval.c — the colour of a texel under a reflectance-field model
 * (Meseth, Müller & Klein 2003, equation (3) for one light): the
 * luminance of the field times the texel's average colour of that field,
 * and at an arbitrary view the four closest measured views' colours
 * weighted as section 5.4 does ("multiply the resulting luminances by the
 * average colors for the reflectance field and the weights w_v, and add
 * them"). The arithmetic is src/rf/btf_rf_shared.h's btf_rf_blend, the
 * renderers' own (CPU and GPU). (x, y) is a texel of the surface, through
 * a sampled model's coordinate map (section 6, rf_map.h).
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

/* Surface texel (x, y), wrapped into the surface, to the model texel it
 * shows (the identity without a map). */
static size_t texel_of(const btf_rf_model *m, int x, int y)
{
    return rf_surface_texel(m, rf_wrap(x, rf_surface_w(m)), rf_wrap(y, rf_surface_h(m)));
}

static void blend_to(const btf_rf_model *m, btf_rf_views vs, const float v[3], btf_dir light,
                     int x, int y, float rgb[3])
{
    rf_ctx c = rf_ctx_of(m);
    double l[3];
    btf_dir_to_vec(light, l);
    btf_rf_rgb r = btf_rf_blend(&c, vs, texel_of(m, x, y), (float)l[0], (float)l[1],
                                (float)l[2], v[0], v[1], v[2]);
    rgb[0] = r.r, rgb[1] = r.g, rgb[2] = r.b;
}

void btf__rf_eval_field(const btf_rf_model *m, int field, btf_dir view, btf_dir light, int x,
                        int y, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!m || !m->codes || field < 0 || field >= m->fields || rf_surface_w(m) < 1 ||
        rf_surface_h(m) < 1)
        return;
    rf_look o = rf_look_at(m, view);
    blend_to(m, btf_rf_make_views(field, 0, 0, 0, 1.0f, 0.0f, 0.0f, 0.0f), o.v, light, x, y,
             rgb);
}

void btf__rf_eval(const btf_rf_model *m, btf_dir view, btf_dir light, int x, int y, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!m || !m->codes || rf_surface_w(m) < 1 || rf_surface_h(m) < 1)
        return;
    rf_look o = rf_look_at(m, view);
    blend_to(m, o.vs, o.v, light, x, y, rgb);
}
