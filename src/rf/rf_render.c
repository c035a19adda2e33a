/*
 * rf_render.c — the flat (view, light) render of docs/render.md with a
 * reflectance-field model (Meseth, Müller & Klein 2003, section 5, on the
 * CPU): an orthographic patch, pixel (x, y) on texel (x mod width,
 * y mod height), seen from one view and lit by one unit directional light
 * at the exact light direction; the four closest measured views' fields
 * (section 5.4) are evaluated and blended with their weights (equation (3)
 * with one light), by src/rf/btf_rf_shared.h's btf_rf_blend, the GPU
 * pass's own text. A sampled model's (section 6) texels are its surface's,
 * each looked up through the coordinate map (rf_map.h, BTF_RF_TEXEL_AT).
 *
 * Why a tile: every pixel of the frame shows a texel of the surface with
 * the same view and light, so a frame larger than the surface repeats the
 * same colours. Each distinct texel (at most the surface's width x height)
 * is shaded once, rows in parallel, and the frame is filled by copying (a
 * 1024^2 frame of a 64^2 model shades 4,096 texels, not 2^20); the GPU
 * pass (gpu/rf_render_gpu.c) shades the same tile and expands it with
 * rf_tile_expand.
 */
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdlib.h>
#include <string.h>

typedef struct render_ctx {
    rf_ctx c;
    rf_look look;
    float l[3];
    float *tile;
    int tile_w;
} render_ctx;

/* Row y of the tile. */
static btf_status tile_job(void *user, int y, int worker, btf_error *err)
{
    (void)worker, (void)err;
    const render_ctx *r = user;
    float *row = r->tile + (size_t)y * r->tile_w * 3;
    for (int x = 0; x < r->tile_w; x++) {
        btf_rf_rgb c = btf_rf_blend(&r->c, r->look.vs, BTF_RF_TEXEL_AT(&r->c, x, y), r->l[0],
                                    r->l[1], r->l[2], r->look.v[0], r->look.v[1],
                                    r->look.v[2]);
        row[3 * x] = c.r, row[3 * x + 1] = c.g, row[3 * x + 2] = c.b;
    }
    return BTF_OK;
}

void rf_tile_expand(const float *tile, int tile_w, int tw, int th, btf_image *out)
{
    for (int y = 0; y < out->height; y++) {
        const float *src = tile + (size_t)(y % th) * tile_w * 3;
        float *dst = out->data + (size_t)y * out->width * 3;
        /* pixel x is texel x mod tw; tile_w < tw only when the frame is
         * narrower than the model, and then the one copy is the row */
        for (int x = 0; x < out->width; x += tw) {
            int n = out->width - x < tile_w ? out->width - x : tile_w;
            memcpy(dst + (size_t)x * 3, src, (size_t)n * 3 * sizeof(float));
        }
    }
}

btf_status rf_flat_check(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                         int height, int threads, btf_error *err)
{
    if (!m || !m->codes || m->width < 1 || m->height < 1 ||
        (m->map && (m->surface_width < 1 || m->surface_height < 1)))
        return btf__fail(err, BTF_E_ARG, "flat render: no model");
    if (width < 0 || height < 0 || threads < 0 || !(view.theta >= 0 && view.theta <= 90) ||
        !(light.theta >= 0 && light.theta <= 90) || !isfinite(view.phi) || !isfinite(light.phi))
        return btf__fail(err, BTF_E_ARG, "flat render: size %dx%d, threads %d, view (%g, %g), "
                         "light (%g, %g) (expected sizes and threads >= 0, theta in [0, 90])",
                         width, height, threads, view.theta, view.phi, light.theta, light.phi);
    return BTF_OK;
}

btf_status btf__rf_render_flat(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                               int height, int threads, btf_image *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_render_flat: no output image");
    memset(out, 0, sizeof *out);
    btf_status rc = rf_flat_check(m, view, light, width, height, threads, err);
    if (rc)
        return rc;
    int sw = rf_surface_w(m), sh = rf_surface_h(m);
    width = width ? width : sw;
    height = height ? height : sh;
    render_ctx r;
    memset(&r, 0, sizeof r);
    r.c = rf_ctx_of(m);
    r.look = rf_look_at(m, view);
    double l[3];
    btf_dir_to_vec(light, l);
    for (int k = 0; k < 3; k++)
        r.l[k] = (float)l[k];
    r.tile_w = width < sw ? width : sw;
    int tile_h = height < sh ? height : sh;
    r.tile = btf__alloc((size_t)r.tile_w * tile_h, 3 * sizeof(float), err);
    if (!r.tile)
        return BTF_E_NOMEM;
    rc = btf__pool_run(tile_h, threads, tile_job, &r, NULL, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, height, 3, err);
    if (rc == BTF_OK)
        rf_tile_expand(r.tile, r.tile_w, sw, sh, out);
    free(r.tile);
    return rc;
}
