/*
 * shade.c — the per-pixel rendering of Haindl & Filip 2007, section III and
 * Fig. 1, on a G-buffer (docs/render.md, "Shading"):
 *
 *  1. the local view direction v (tangent frame) selects three measured
 *     views with barycentric weights wv, each light's local direction l
 *     three measured lights with weights wl (render/hemisphere.c);
 *  2. parallax mapping: the texture coordinate is shifted along the view's
 *     tangent-plane direction by the relief-scaled height h of the range
 *     map, (u, v) += r h (v_x, -v_y) / max(v_z, BTF_PARALLAX_MIN_Z) (the
 *     image's rows grow downwards, the frame's y upwards);
 *  3. the nine pairs' subspace images are sampled there (bilinear, wrapped:
 *     the images are tileable) and blended with the weights wv_i wl_j;
 *  4. bump mapping: the blend is multiplied by max(0, n . l) / max(l_z,
 *     BTF_FLAT_MIN_Z), n the range map's normal with its slopes scaled by
 *     r. The measured images already hold the flat surface's mean shading
 *     (l_z), so a flat range map multiplies by exactly 1; a light below the
 *     surface's horizon (l_z <= 0) gives nothing.
 *
 * Each light adds its intensity times that; a negative sum (the CAR
 * model's Gaussian tails) becomes 0; background pixels get the background
 * colour.
 */
#include "render/shade.h"
#include "core/core.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

/* Parallax shifts grow as 1 / v_z towards grazing views; past 76 degrees
 * they are held at 4 h (offset limiting), which keeps them bounded. */
#define BTF_PARALLAX_MIN_Z 0.25f
/* The flat surface's n . l below which the normalisation is held: lights
 * within 3 degrees of the horizon fade out instead of dividing by ~0. */
#define BTF_FLAT_MIN_Z 0.05f

/* The two taps and the fraction of a wrapped bilinear lookup at texture
 * coordinate x (texel centres at i + 1/2) on a side of s texels. */
static inline void wrap_taps(float x, int s, int *i0, int *i1, float *f)
{
    float t = isfinite(x) ? x - 0.5f : 0.0f;
    float fl = floorf(t);
    *f = t - fl;
    float r = fmodf(fl, (float)s);
    if (r < 0.0f)
        r += (float)s;
    int i = (int)r;
    if (i >= s || i < 0)
        i = 0;
    *i0 = i;
    *i1 = i + 1 == s ? 0 : i + 1;
}

typedef struct taps {
    size_t o00, o01, o10, o11; /* pixel offsets */
    float fx, fy;
} taps;

static inline taps taps_at(float u, float v, int s)
{
    int x0, x1, y0, y1;
    taps t;
    wrap_taps(u, s, &x0, &x1, &t.fx);
    wrap_taps(v, s, &y0, &y1, &t.fy);
    t.o00 = (size_t)y0 * (size_t)s + (size_t)x0;
    t.o01 = (size_t)y0 * (size_t)s + (size_t)x1;
    t.o10 = (size_t)y1 * (size_t)s + (size_t)x0;
    t.o11 = (size_t)y1 * (size_t)s + (size_t)x1;
    return t;
}

static inline float tap(const float *d, const taps *t, int c, int channels)
{
    float a = d[t->o00 * channels + c], b = d[t->o01 * channels + c];
    float e = d[t->o10 * channels + c], g = d[t->o11 * channels + c];
    float top = a * (1.0f - t->fx) + b * t->fx;
    float bottom = e * (1.0f - t->fx) + g * t->fx;
    return top * (1.0f - t->fy) + bottom * t->fy;
}

typedef struct shade_job {
    const btf_render_material *rm;
    const btf_gbuffer *g;
    const btf_light *lights;
    int n_lights;
    const float *background;
    float relief;
    btf_image *out;
    atomic_int missing; /* a subspace the material lacks (set by any row) */
} shade_job;

/* The relief-scaled normal at a texture position: the map's normal is
 * (-h_x, -h_y, 1) normalised, so scaling the heights by r scales its x and
 * y by r against z. */
static void relief_normal(const btf_render_material *rm, const taps *t, float r, float n[3])
{
    if (r == 0.0f) {
        n[0] = n[1] = 0.0f;
        n[2] = 1.0f;
        return;
    }
    float x = r * tap(rm->normal.data, t, 0, 3), y = r * tap(rm->normal.data, t, 1, 3);
    float z = tap(rm->normal.data, t, 2, 3);
    float len = sqrtf(x * x + y * y + z * z);
    if (!(len > 1e-20f) || !isfinite(len)) {
        n[0] = n[1] = 0.0f;
        n[2] = 1.0f;
        return;
    }
    n[0] = x / len;
    n[1] = y / len;
    n[2] = z / len;
}

/* One light's contribution to pixel p at texture taps t. 0: none needed;
 * -1: the material lacks a subspace the pixel selects. */
static int light_term(const shade_job *j, size_t p, const float *frame, const int iv[3],
                      const float wv[3], const btf_light *light, const taps *t,
                      const float n[3], float acc[3])
{
    const btf_render_material *rm = j->rm;
    float dir[3], rgb[3], ll[3];
    if (!btf_render_light_at(light, j->g->position + 3 * p, dir, rgb))
        return 0;
    btf_render_to_local(frame, dir, ll);
    if (!(ll[2] > 0.0f))
        return 0;
    int il[3];
    float wl[3];
    btf_hemisphere_lookup(rm->lights, ll, il, wl);
    btf_render_pairs pairs;
    btf_render_pairs_of(rm->index, rm->n_lights, iv, wv, il, wl, &pairs);
    float c[3] = {0.0f, 0.0f, 0.0f};
    for (int d = 0; d < pairs.n; d++) {
        const btf_image *tex = &rm->tex[pairs.sub[d]];
        if (!tex->data)
            return -1;
        for (int ch = 0; ch < 3; ch++)
            c[ch] += pairs.w[d] * tap(tex->data, t, ch, 3);
    }
    float ndotl = n[0] * ll[0] + n[1] * ll[1] + n[2] * ll[2];
    float flat = ll[2] > BTF_FLAT_MIN_Z ? ll[2] : BTF_FLAT_MIN_Z;
    float factor = ndotl > 0.0f ? ndotl / flat : 0.0f;
    /* Beyond the outermost measured light ring the hull rule keeps that
     * ring's images, whose irradiance is cos(theta_outer): continue the
     * foreshortening down to 0 at the horizon (docs/render.md). */
    if (ll[2] < rm->light_outer_z)
        factor *= ll[2] / rm->light_outer_z;
    for (int ch = 0; ch < 3; ch++)
        acc[ch] += rgb[ch] * c[ch] * factor;
    return 0;
}

static int shade_pixel(const shade_job *j, size_t p, float out[3])
{
    const btf_render_material *rm = j->rm;
    const float *frame = j->g->frame + 9 * p;
    float vl[3];
    btf_render_local_view(frame, j->g->view + 3 * p, vl);
    int iv[3];
    float wv[3];
    btf_hemisphere_lookup(rm->views, vl, iv, wv);
    float u = j->g->uv[2 * p], v = j->g->uv[2 * p + 1];
    if (j->relief != 0.0f) {
        taps t0 = taps_at(u, v, rm->size);
        float h = j->relief * tap(rm->height.data, &t0, 0, 1);
        float z = vl[2] > BTF_PARALLAX_MIN_Z ? vl[2] : BTF_PARALLAX_MIN_Z;
        u += h * vl[0] / z;
        v -= h * vl[1] / z;
    }
    taps t = taps_at(u, v, rm->size);
    float n[3];
    relief_normal(rm, &t, j->relief, n);
    float acc[3] = {0.0f, 0.0f, 0.0f};
    for (int k = 0; k < j->n_lights; k++)
        if (light_term(j, p, frame, iv, wv, &j->lights[k], &t, n, acc) < 0)
            return -1;
    /* No negative radiance: the CAR model's Gaussian tails can take a
     * subspace image below 0 (docs/render.md). */
    for (int ch = 0; ch < 3; ch++)
        out[ch] = isfinite(acc[ch]) && acc[ch] > 0.0f ? acc[ch] : 0.0f;
    return 0;
}

static btf_status shade_row(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    shade_job *j = user;
    int w = j->g->width;
    for (int x = 0; x < w; x++) {
        size_t p = (size_t)y * (size_t)w + (size_t)x;
        float *o = j->out->data + 3 * p;
        if (j->g->object[p] < 0) {
            memcpy(o, j->background, 3 * sizeof(float));
            continue;
        }
        if (shade_pixel(j, p, o) < 0)
            atomic_store(&j->missing, 1);
    }
    return BTF_OK;
}

btf_status btf_render_shade(const btf_render_material *rm, const btf_gbuffer *g,
                            const btf_light *lights, int n_lights, const float background[3],
                            double relief, int threads, btf_image *out, btf_error *err)
{
    static const float black[3] = {0.0f, 0.0f, 0.0f};
    if (!rm || !g || !out || (n_lights > 0 && !lights) || n_lights < 0)
        return btf_fail(err, BTF_E_ARG, "shade: missing material, G-buffer, lights or output");
    if (!isfinite(relief) || fabs(relief) > 1e6)
        return btf_fail(err, BTF_E_ARG, "relief %g: expected a finite scale up to 1e6", relief);
    memset(out, 0, sizeof *out);
    btf_status rc = btf_image_alloc(out, g->width, g->height, 3, err);
    if (rc)
        return rc;
    shade_job j = {rm, g, lights, n_lights, background ? background : black, (float)relief,
                   out, 0};
    rc = btf_pool_run(g->height, threads, shade_row, &j, NULL, err);
    if (rc == BTF_OK && atomic_load(&j.missing))
        rc = btf_fail(err, BTF_E_ARG, "shade: a pixel selects a subspace the material was "
                      "not built with (btf_render_needed gives the set)");
    if (rc)
        btf_image_free(out);
    return rc;
}
