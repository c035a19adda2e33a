/*
 * rf_scene.c — a scene rendered with a reflectance-field model (Meseth,
 * Müller & Klein 2003, section 5, on the CPU; docs/rf.md, "Rendering"):
 * the scene is traced into the G-buffer the CAR renderer shades
 * (btf_scene_trace), and per pixel the local view and light directions are
 * taken in the pixel's tangent frame exactly as src/render/ takes them
 * (btf_render_shared.h's btf_shade_pixel: T, B, N rows, the view held at
 * least 1e-3 above the horizon, a light below the surface's
 * horizon giving nothing, a point light falling off as 1/d^2). The texel
 * is the pixel's uv wrapped to the model's texels (floor, as the flat
 * render's pixel (x, y) is texel (x, y)); the four closest measured views'
 * fields are evaluated at the exact light direction and blended (rf.h's
 * rf_views_at and rf_blend, the flat render's code path). No parallax and
 * no bump mapping: the fields hold the surface's relief themselves. A
 * sampled model's (section 6) uv wraps into its surface, and the texel is
 * looked up through the coordinate map (rf_map.h).
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The renderer's BTF_RENDER_MIN_Z and BTF_RENDER_COORD_MAX
 * (src/render/btf_render_shared.h), kept equal. */
#define RF_SCENE_MIN_Z 1e-3
#define RF_SCENE_COORD_MAX 1.0e30

typedef struct scene_job {
    const btf_rf_model *m;
    const btf_scene *s;
    const btf_gbuffer *g;
    btf_image *out;
} scene_job;

static double dot3(const float *a, const double *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* The texel index of a texture coordinate along a side of n texels. */
static int wrap_texel(float c, int n)
{
    double u = c;
    if (!(fabs(u) < RF_SCENE_COORD_MAX))
        u = 0.0;
    double r = fmod(floor(u), (double)n);
    int i = (int)r;
    return i < 0 ? i + n : i >= n ? i - n : i;
}

/* The unit world direction towards light j from pos and its intensity
 * scale (1, or 1/d^2 for a point light); 0 when it gives no light. */
static double light_dir(const btf_light *lt, const float *pos, double d[3])
{
    double q[3], scale = 1.0;
    for (int k = 0; k < 3; k++)
        q[k] = lt->kind == BTF_LIGHT_POINT ? lt->position[k] - pos[k] : lt->direction[k];
    double d2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    if (!(d2 > 1e-24) || !(d2 < RF_SCENE_COORD_MAX))
        return 0.0;
    if (lt->kind == BTF_LIGHT_POINT)
        scale = 1.0 / d2;
    double r = sqrt(d2);
    for (int k = 0; k < 3; k++)
        d[k] = q[k] / r;
    return scale;
}

static void shade_pixel(const scene_job *j, size_t p, float *o)
{
    const btf_rf_model *m = j->m;
    const btf_gbuffer *g = j->g;
    const float *f = g->frame + 9 * p, *pos = g->position + 3 * p;
    double e[3] = {g->view[3 * p], g->view[3 * p + 1], g->view[3 * p + 2]};
    double v[3] = {dot3(f, e), dot3(f + 3, e), dot3(f + 6, e)};
    v[2] = v[2] > RF_SCENE_MIN_Z ? v[2] : RF_SCENE_MIN_Z;
    double vn = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (vn > 0.0 && isfinite(vn) && fabs(vn - 1.0) > 1e-12)
        for (int k = 0; k < 3; k++)
            v[k] /= vn;
    rf_views vs;
    rf_views_at(m, btf_vec_to_dir(v), v, &vs);
    int tx = wrap_texel(g->uv[2 * p], rf_surface_w(m));
    int ty = wrap_texel(g->uv[2 * p + 1], rf_surface_h(m));
    size_t t = rf_surface_texel(m, tx, ty);
    double sum[3] = {0, 0, 0};
    for (int i = 0; i < j->s->n_lights; i++) {
        const btf_light *lt = &j->s->lights[i];
        double d[3];
        double scale = light_dir(lt, pos, d);
        if (scale == 0.0)
            continue;
        double l[3] = {dot3(f, d), dot3(f + 3, d), dot3(f + 6, d)};
        if (!(l[2] > 0.0))
            continue; /* below the surface's horizon: no light */
        double c[3];
        rf_blend(m, &vs, t, l, c);
        for (int k = 0; k < 3; k++)
            sum[k] += (double)lt->rgb[k] * scale * c[k];
    }
    for (int k = 0; k < 3; k++) {
        float x = (float)sum[k];
        o[k] = x > 0.0f && x < (float)RF_SCENE_COORD_MAX ? x : 0.0f;
    }
}

static btf_status row_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const scene_job *j = user;
    int w = j->g->width;
    for (int x = 0; x < w; x++) {
        size_t p = (size_t)y * (size_t)w + (size_t)x;
        float *o = j->out->data + 3 * p;
        if (j->g->object[p] < 0)
            memcpy(o, j->s->background, 3 * sizeof(float));
        else
            shade_pixel(j, p, o);
    }
    return BTF_OK;
}

btf_status btf_rf_render_scene(const btf_rf_model *m, const btf_scene *s, int width,
                               int height, int threads, btf_image *out, btf_render_info *info,
                               btf_error *err)
{
    if (info)
        memset(info, 0, sizeof *info);
    if (!out)
        return btf_fail(err, BTF_E_ARG, "btf_rf_render_scene: no output image");
    memset(out, 0, sizeof *out);
    if (!m || !m->codes || m->width < 1 || m->height < 1 || m->fields < 1 ||
        (m->map && (m->surface_width < 1 || m->surface_height < 1)))
        return btf_fail(err, BTF_E_ARG, "btf_rf_render_scene: no model");
    if (!s)
        return btf_fail(err, BTF_E_ARG, "btf_rf_render_scene: no scene given");
    width = width ? width : 512;
    height = height ? height : 512;
    if (width < 1 || height < 1 || width > BTF_RENDER_MAX_SIDE || height > BTF_RENDER_MAX_SIDE ||
        threads < 0)
        return btf_fail(err, BTF_E_ARG, "scene render: frame %dx%d, threads %d (expected "
                        "each side 1..%d, threads >= 0)", width, height, threads,
                        BTF_RENDER_MAX_SIDE);
    btf_status rc = btf_scene_check(s, err);
    if (rc)
        return rc;
    if (s->n_lights > 0 && !s->lights)
        return btf_fail(err, BTF_E_ARG, "scene: %d lights but no light array", s->n_lights);
    btf_gbuffer g;
    memset(&g, 0, sizeof g);
    double t0 = btf_now();
    if ((rc = btf_scene_trace(s, width, height, threads, &g, err)))
        return rc;
    double t1 = btf_now();
    if ((rc = btf_image_alloc(out, width, height, 3, err))) {
        btf_gbuffer_free(&g);
        return rc;
    }
    scene_job j = {m, s, &g, out};
    rc = btf_pool_run(height, threads, row_job, &j, NULL, err);
    btf_gbuffer_free(&g);
    if (rc) {
        btf_image_free(out);
        return rc;
    }
    if (info) {
        info->trace_s = t1 - t0;
        info->shade_s = btf_now() - t1;
    }
    return BTF_OK;
}
