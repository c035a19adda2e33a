/*
 * render_gpu.c — the GPU render pass (Haindl & Filip 2007, section III;
 * docs/render.md, "On the GPU"): the second of the two compute passes. The
 * host traces the scene into a G-buffer (src/scene/) and finds the needed
 * subspaces (render/needed.c) as the CPU renderer does (one plan,
 * render/render_scene.c); the first pass synthesises those subspaces
 * tileable into one device buffer (btf__gpu_synthesise_device), which stays
 * on the device; this pass (gpu/render.comp) shades every pixel from the
 * G-buffer, the hemisphere tables, the index table, that buffer and the
 * range and normal maps, with the shading text the CPU runs
 * (src/render/btf_render_shared.h).
 *
 * Why the G-buffer comes from the host: ray casting against meshes needs a
 * BVH, which the CPU builds and traverses at 2-9 Mrays/s (docs/scene.md);
 * uploading 72 bytes per pixel is cheap beside synthesis, keeps one
 * tracer for both backends (so their hit sets are identical and the parity
 * test compares shading alone), and frees the shader from geometry. A
 * frame whose G-buffer or output would pass the device's largest storage
 * buffer is rendered in bands of rows.
 */
#include "render/shade.h"
#include "core/core.h"

#include "render_gpu.h"
#include "render_layout.h"
#include "synth_gpu.h"
#include "vk.h"

#include "render_spv.h"

#include <stdlib.h>
#include <string.h>

/* The host copies of the parameter buffers (gpu/render_layout.h). */
typedef struct params {
    int32_t *ints;
    size_t n_ints, cap_ints;
    float *floats;
    size_t n_floats, cap_floats;
} params;

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 256;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

/* Appends n elements of elem bytes to a growing array and returns their
 * offset; -1: no memory. put_ints and put_floats keep the element types. */
static long append(void **buf, size_t *cap, size_t *len, const void *v, size_t n, size_t elem)
{
    if (grow(buf, cap, *len + n, elem))
        return -1;
    memcpy((char *)*buf + *len * elem, v, n * elem);
    *len += n;
    return (long)(*len - n);
}

static long put_ints(params *pr, const int32_t *v, size_t n)
{
    return append((void **)&pr->ints, &pr->cap_ints, &pr->n_ints, v, n, sizeof *v);
}

static long put_floats(params *pr, const float *v, size_t n)
{
    return append((void **)&pr->floats, &pr->cap_floats, &pr->n_floats, v, n, sizeof *v);
}

/* One hemisphere table into the parameter buffers, its offsets at tab. */
static int put_table(params *pr, int tab, const btf_hemisphere_table *t)
{
    int32_t *h = pr->ints + BTF_RP_TAB + tab * BTF_RP_TAB_STRIDE;
    int grid = t->grid;
    long tri = put_ints(pr, t->triangles, (size_t)t->n_triangles * 3);
    long cs = put_ints(pr, t->cell_start, (size_t)grid * grid + 1);
    long ct = put_ints(pr, t->cell_tris, (size_t)t->n_cell_tris);
    long hull = put_ints(pr, t->hull, (size_t)t->n_hull);
    long apex = put_ints(pr, t->hull_apex, (size_t)t->n_hull);
    long pts = put_floats(pr, t->points, (size_t)t->n_points * 2);
    if (tri < 0 || cs < 0 || ct < 0 || hull < 0 || apex < 0 || pts < 0)
        return -1;
    h = pr->ints + BTF_RP_TAB + tab * BTF_RP_TAB_STRIDE; /* the buffer may have moved */
    h[BTF_RP_T_GRID] = grid;
    h[BTF_RP_T_NHULL] = t->n_hull;
    h[BTF_RP_T_TRI] = (int32_t)tri;
    h[BTF_RP_T_CS] = (int32_t)cs;
    h[BTF_RP_T_CT] = (int32_t)ct;
    h[BTF_RP_T_HULL] = (int32_t)hull;
    h[BTF_RP_T_APEX] = (int32_t)apex;
    h[BTF_RP_T_PTS] = (int32_t)pts;
    return 0;
}

/* Everything the pass reads but the G-buffer and the images. */
static btf_status build_params(const btf_model *m, const btf_render_sets *sets,
                               const btf_render_plan *p, const btf_hemisphere *views,
                               const btf_hemisphere *lights, const int *subs, int n,
                               uint64_t cap, const uint64_t *offsets, params *pr,
                               btf_error *err)
{
    int32_t zero[BTF_RP_INTS] = {0};
    float fzero[BTF_RP_FLOATS] = {0};
    if (put_ints(pr, zero, BTF_RP_INTS) < 0 || put_floats(pr, fzero, BTF_RP_FLOATS) < 0)
        return btf__fail(err, BTF_E_NOMEM, "GPU render: out of memory for the parameters");
    size_t pairs = (size_t)sets->views.count * (size_t)sets->lights.count;
    int32_t *tmp = btf__alloc(pairs + 2 * (size_t)m->n_subspaces + 1, sizeof *tmp, err);
    uint8_t *index = tmp ? btf__render_pair_index(m, sets, err) : NULL; /* sparse sets filled */
    if (!tmp || !index) {
        free(tmp);
        return BTF_E_NOMEM;
    }
    for (size_t i = 0; i < pairs; i++)
        tmp[i] = index[i];
    free(index);
    long idx = put_ints(pr, tmp, pairs);
    int K = m->n_subspaces;
    for (int k = 0; k < K; k++)
        tmp[k] = 0, tmp[K + k] = 0;
    for (int i = 0; i < n; i++) {
        tmp[subs[i]] = 1;
        tmp[K + subs[i]] = (int32_t)offsets[i];
    }
    long have = put_ints(pr, tmp, (size_t)K);
    long texoff = put_ints(pr, tmp + K, (size_t)K);
    free(tmp);
    float *gains = btf__render_gains(m, sets, err);
    if (!gains)
        return BTF_E_NOMEM;
    long gain = put_floats(pr, gains, pairs * 3);
    free(gains);
    btf_hemisphere_table tv, tl;
    btf__hemisphere_get_table(views, &tv);
    btf__hemisphere_get_table(lights, &tl);
    if (idx < 0 || have < 0 || texoff < 0 || gain < 0 || put_table(pr, 0, &tv) || put_table(pr, 1, &tl))
        return btf__fail(err, BTF_E_NOMEM, "GPU render: out of memory for the parameters");
    btf_shade_ctx *ctx = btf__alloc(1, sizeof *ctx, err);
    if (!ctx)
        return BTF_E_NOMEM;
    btf_status rc = btf__render_ctx_lights(ctx, p->lights, p->n_lights, err);
    int32_t *hi = pr->ints;
    float *hf = pr->floats;
    hi[BTF_RP_SIZE] = p->side;
    hi[BTF_RP_NSET] = sets->lights.count;
    hi[BTF_RP_NLIGHTS] = p->n_lights;
    hi[BTF_RP_INDEX] = (int32_t)idx;
    hi[BTF_RP_HAVE] = (int32_t)have;
    hi[BTF_RP_TEXOFF] = (int32_t)texoff;
    hi[BTF_RP_TEXCAP] = (int32_t)(cap > 0 ? cap : 1);
    hi[BTF_RP_NORMAL] = p->side * p->side;
    hi[BTF_RP_GAIN] = (int32_t)gain;
    hf[BTF_RP_OUTER] = btf__render_light_outer_z(m);
    hf[BTF_RP_RELIEF] = (float)p->o.relief;
    hf[BTF_RP_AMBIENT] = btf__render_ambient(m);
    for (int c = 0; c < 3; c++)
        hf[BTF_RP_BG + c] = p->background[c];
    for (int j = 0; rc == BTF_OK && j < p->n_lights; j++) {
        hi[BTF_RP_KIND + j] = ctx->kind[j];
        for (int k = 0; k < 3; k++) {
            hf[BTF_RP_VEC + 3 * j + k] = ctx->vec[j][k];
            hf[BTF_RP_RGB + 3 * j + k] = ctx->rgb[j][k];
        }
    }
    free(ctx);
    return rc;
}

/* Rows [y0, y1) of the G-buffer, packed BTF_RP_GB floats per pixel (also
 * the reflectance-field pass's input, gpu/render_gpu.h). */
void btf__render_pack_gbuffer(const btf_gbuffer *g, int y0, int y1, float *out)
{
    for (size_t p = (size_t)y0 * g->width, q = 0; p < (size_t)y1 * g->width; p++, q++) {
        float *o = out + q * BTF_RP_GB;
        o[0] = g->object[p] >= 0 ? 1.0f : -1.0f;
        o[1] = g->uv[2 * p];
        o[2] = g->uv[2 * p + 1];
        memcpy(o + 3, g->frame + 9 * p, 9 * sizeof(float));
        memcpy(o + 12, g->position + 3 * p, 3 * sizeof(float));
        memcpy(o + 15, g->view + 3 * p, 3 * sizeof(float));
    }
}

/* A structure layer's textures hold reflectance (btf__render_reflectance):
 * each is read back, scaled by the CPU's code and written again, so the
 * two backends shade the same floats. */
static btf_status scale_textures(btf_vk *vk, const btf_model *m, const int *subs, int n,
                                 const uint64_t *offs, int side, const btf_gpu_images *tex,
                                 btf_error *err)
{
    if (!m->albedo)
        return BTF_OK;
    size_t floats = (size_t)side * side * 3;
    float *buf = btf__alloc(floats, sizeof(float), err);
    btf_status rc = buf ? BTF_OK : BTF_E_NOMEM;
    for (int j = 0; rc == BTF_OK && j < n; j++) {
        rc = btf__gpu_images_download(vk, tex, offs[j], buf, floats, err);
        btf__render_scale_texture(buf, floats, btf__render_reflectance(m, subs[j]));
        if (rc == BTF_OK)
            rc = btf__gpu_images_upload(vk, tex, offs[j], buf, floats, err);
    }
    free(buf);
    return rc;
}

/* The range and normal maps of the texture side, one buffer, and the
 * horizon map (the relief's shadows, the CPU's words) in another; a model
 * without shadows binds a small unread buffer there. */
static btf_status upload_maps(btf_vk *vk, const btf_model *m, int side, uint64_t seed,
                              int threads, uint64_t cap, int most, btf_gpu_images *out,
                              btf_vk_buffer **hor, int *shadows, float *bounds, btf_error *err)
{
    btf_image h = {0}, n = {0};
    uint32_t *hz = NULL;
    btf_status rc = btf_structure_maps(m, side, side, seed, &h, &n, NULL, err);
    size_t px = (size_t)side * side;
    if (rc == BTF_OK)
        rc = btf__render_relief(m, &h, threads, &hz, bounds, err);
    *shadows = hz != NULL;
    if (rc == BTF_OK)
        rc = btf__gpu_images_create(vk, px * 4, cap, most,
                                    "GPU render: the range and normal maps", out, err);
    if (rc == BTF_OK)
        rc = btf__gpu_images_upload(vk, out, 0, h.data, px, err);
    if (rc == BTF_OK)
        rc = btf__gpu_images_upload(vk, out, px, n.data, px * 3, err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(vk, hz ? px * 2 * sizeof(uint32_t) : 16, hor, err);
    if (rc == BTF_OK && hz)
        rc = btf__vk_buffer_upload(vk, *hor, 0, hz, px * 2 * sizeof(uint32_t), err);
    free(hz);
    btf_image_free(&h);
    btf_image_free(&n);
    return rc;
}

/* Rows of the frame per band: the G-buffer and output of a band must each
 * fit one storage buffer (and the ints must index them). */
static int band_rows(const btf_gpu *g, int width, int height)
{
    uint64_t lim = btf__gpu_max_buffer_bytes(g);
    if (lim > (1ull << 31) - 4)
        lim = (1ull << 31) - 4;
    uint64_t per_row = (uint64_t)width * BTF_RP_GB * sizeof(float);
    uint64_t rows = per_row ? lim / per_row : (uint64_t)height;
    return rows >= (uint64_t)height ? height : (int)rows;
}

typedef struct pass {
    btf_gpu *gpu;
    btf_vk *vk;
    btf_vk_pipeline *pipe;
    btf_vk_buffer *bufs[22]; /* gbuf, tex, maps, ints, floats, out, horizon, missing,
                                tex1..tex3, maps1..maps3, tex4..tex7, maps4..maps7
                                (render.comp's bindings) */
    btf_gpu_images maps;     /* the range and normal maps (bindings 2, 11..13) */
    btf_vk_buffer *placeholder; /* bound where a texture buffer is unused */
    params pr;
} pass;

static void pass_free(pass *ps)
{
    btf__vk_pipeline_destroy(ps->pipe);
    for (int i = 0; i < 8; i++)
        if (i != 1 && i != 2) /* the images' and maps' arrays own theirs */
            btf__vk_buffer_destroy(ps->bufs[i]);
    btf__gpu_images_free(&ps->maps);
    btf__vk_buffer_destroy(ps->placeholder);
    free(ps->pr.ints);
    free(ps->pr.floats);
}

/* One band of rows [y0, y1): upload, dispatch, download into out. */
static btf_status run_band(pass *ps, const btf_gbuffer *g, int y0, int y1, float *scratch,
                           btf_image *out, btf_error *err)
{
    size_t npix = (size_t)(y1 - y0) * g->width;
    btf__render_pack_gbuffer(g, y0, y1, scratch);
    uint32_t groups = (uint32_t)((npix + 63) / 64);
    uint32_t gx = groups < 65535 ? groups : 65535, gy = (groups + gx - 1) / gx;
    ps->pr.ints[BTF_RP_NPIX] = (int32_t)npix;
    ps->pr.ints[BTF_RP_ROW_PIX] = (int32_t)(gx * 64);
    btf_status rc = btf__vk_buffer_upload(ps->vk, ps->bufs[0], 0, scratch,
                                          npix * BTF_RP_GB * sizeof(float), err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[3], 0, ps->pr.ints,
                                   ps->pr.n_ints * sizeof(int32_t), err);
    btf_vk_job *job = NULL;
    if (rc == BTF_OK)
        rc = btf__vk_job_begin(ps->vk, &job, err);
    if (rc == BTF_OK) /* the flag of a band's missing subspaces starts clear */
        rc = btf__vk_job_fill(job, ps->bufs[7], 0, sizeof(uint32_t), 0, err);
    if (rc == BTF_OK)
        rc = btf__vk_job_dispatch(job, ps->pipe, ps->bufs, 22, NULL, 0, gx, gy, 1, err);
    if (rc == BTF_OK) {
        rc = btf__vk_job_submit_wait(job, err);
        job = NULL;
    }
    btf__vk_job_abort(job);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_download(ps->vk, ps->bufs[5], 0,
                                     out->data + (size_t)y0 * g->width * 3,
                                     npix * 3 * sizeof(float), err);
    uint32_t missing = 0;
    if (rc == BTF_OK)
        rc = btf__vk_buffer_download(ps->vk, ps->bufs[7], 0, &missing, sizeof missing, err);
    if (rc == BTF_OK && missing != 0)
        rc = btf__fail(err, BTF_E_ARG, "GPU render: a pixel selects a subspace the first "
                       "pass did not synthesise");
    return rc;
}

/* The pass over the whole frame, in bands. */
static btf_status shade_frame(pass *ps, const btf_gbuffer *g, btf_image *out, btf_error *err)
{
    int rows = band_rows(ps->gpu, g->width, g->height);
    if (rows < 1)
        return btf__fail(err, BTF_E_UNSUPPORTED, "GPU render: one row of %d pixels needs more "
                         "than the device's largest storage buffer", g->width);
    size_t band_px = (size_t)rows * g->width;
    float *scratch = btf__alloc(band_px, BTF_RP_GB * sizeof(float), err);
    if (!scratch)
        return BTF_E_NOMEM;
    btf_status rc = btf__vk_buffer_create(ps->vk, band_px * BTF_RP_GB * sizeof(float),
                                          &ps->bufs[0], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, band_px * 3 * sizeof(float), &ps->bufs[5], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, 16, &ps->bufs[7], err);
    for (int y0 = 0; rc == BTF_OK && y0 < g->height; y0 += rows)
        rc = run_band(ps, g, y0, y0 + rows < g->height ? y0 + rows : g->height, scratch, out,
                      err);
    free(scratch);
    return rc;
}

static btf_status upload_params(pass *ps, btf_error *err)
{
    btf_status rc = btf__vk_buffer_create(ps->vk, ps->pr.n_ints * sizeof(int32_t), &ps->bufs[3],
                                          err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, ps->pr.n_floats * sizeof(float), &ps->bufs[4], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[4], 0, ps->pr.floats,
                                   ps->pr.n_floats * sizeof(float), err);
    return rc;
}

/* The GPU backend on a plan: the first pass (synthesis into a device
 * buffer), the second (this shader), the frame downloaded. */
static btf_status render_plan_gpu(btf_gpu *gpu, const btf_model *m, const btf_render_plan *p,
                                  btf_image *out, btf_render_info *info, btf_error *err)
{
    pass ps;
    memset(&ps, 0, sizeof ps);
    ps.gpu = gpu;
    ps.vk = btf__gpu_vk(gpu);
    int *subs = btf__alloc((size_t)m->n_subspaces, sizeof *subs, err);
    uint64_t *offs = btf__alloc((size_t)m->n_subspaces, sizeof *offs, err);
    btf_hemisphere *views = NULL, *lights = NULL;
    btf_gpu_images tex;
    memset(&tex, 0, sizeof tex);
    btf_status rc = subs && offs ? BTF_OK : BTF_E_NOMEM;
    int n = 0;
    for (int k = 0; rc == BTF_OK && k < m->n_subspaces; k++)
        if (p->needed[k])
            subs[n++] = k;
    double t0 = btf__now();
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = p->side;
    so.seed = p->o.seed;
    so.tileable = 1;
    if (rc == BTF_OK && n > 0)
        rc = btf__gpu_synthesise_device(gpu, m, subs, n, &so, &tex, offs, err);
    if (rc == BTF_OK && n > 0)
        rc = scale_textures(ps.vk, m, subs, n, offs, p->side, &tex, err);
    double t1 = btf__now();
    /* unused texture bindings: a buffer the shader may bind, never read */
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps.vk, 16, &ps.placeholder, err);
    static const int slot[BTF_GPU_DEVICE_BUFFERS] = {1, 8, 9, 10, 14, 15, 16, 17}; /* render.comp */
    for (int b = 0; rc == BTF_OK && b < BTF_GPU_DEVICE_BUFFERS; b++)
        ps.bufs[slot[b]] = tex.buf[b] ? tex.buf[b] : ps.placeholder;
    btf_render_sets sets;
    memset(&sets, 0, sizeof sets);
    if (rc == BTF_OK)
        rc = btf__render_sets_make(m, &sets, err);
    if (rc == BTF_OK)
        rc = btf_hemisphere_build(&sets.views, &views, err);
    if (rc == BTF_OK)
        rc = btf_hemisphere_build(&sets.lights, &lights, err);
    if (rc == BTF_OK)
        rc = build_params(m, &sets, p, views, lights, subs, n, btf__gpu_images_cap(ps.gpu), offs,
                          &ps.pr, err);
    btf__render_sets_free(&sets);
    int shadows = 0;
    float bounds[2] = {0.0f, 0.0f};
    if (rc == BTF_OK)
        rc = upload_maps(ps.vk, m, p->side, p->o.seed, p->o.threads,
                         btf__gpu_images_cap(ps.gpu), btf__gpu_images_buffers(ps.gpu), &ps.maps,
                         &ps.bufs[6], &shadows, bounds, err);
    static const int mslot[BTF_GPU_DEVICE_BUFFERS] = {2, 11, 12, 13, 18, 19, 20, 21};
    for (int b = 0; rc == BTF_OK && b < BTF_GPU_DEVICE_BUFFERS; b++) /* render.comp */
        ps.bufs[mslot[b]] = ps.maps.buf[b] ? ps.maps.buf[b] : ps.placeholder;
    if (rc == BTF_OK) {
        ps.pr.ints[BTF_RP_HORIZON] = shadows;
        ps.pr.floats[BTF_RP_HMIN] = bounds[0];
        ps.pr.floats[BTF_RP_HMAX] = bounds[1];
        rc = upload_params(&ps, err);
    }
    if (rc == BTF_OK)
        rc = btf__vk_pipeline_create(ps.vk, render_spv, sizeof render_spv, 22, 0, NULL, 0,
                                     &ps.pipe, err);
    if (rc == BTF_OK && (rc = btf_image_alloc(out, p->g.width, p->g.height, 3, err)) == BTF_OK) {
        rc = shade_frame(&ps, &p->g, out, err);
        if (rc)
            btf_image_free(out);
    }
    double t2 = btf__now();
    btf__render_plan_info(m, p, info);
    if (info) {
        info->synth_s = p->needed_s + (t1 - t0);
        info->shade_s = t2 - t1;
    }
    pass_free(&ps);
    btf__gpu_images_free(&tex);
    btf_hemisphere_free(views);
    btf_hemisphere_free(lights);
    free(subs);
    free(offs);
    return rc;
}

/* Checks and clears the outputs of a GPU render. */
static btf_status begin(btf_gpu *g, btf_image *out, btf_render_info *info, btf_error *err)
{
    if (!g || !out)
        return btf__fail(err, BTF_E_ARG, "GPU render: no device or output given");
    memset(out, 0, sizeof *out);
    if (info)
        memset(info, 0, sizeof *info);
    return BTF_OK;
}

/* Runs the passes on a plan built with status rc, then frees it. */
static btf_status finish(btf_gpu *g, const btf_model *m, btf_render_plan *p, btf_status rc,
                         btf_image *out, btf_render_info *info, btf_error *err)
{
    if (rc == BTF_OK)
        rc = render_plan_gpu(g, m, p, out, info, err);
    btf__render_plan_free(p);
    return rc;
}

btf_status btf_gpu_render_scene(btf_gpu *g, const btf_model *m, const btf_scene *s,
                                const btf_render_opts *opts, btf_image *out,
                                btf_render_info *info, btf_error *err)
{
    btf_status rc = begin(g, out, info, err);
    if (rc)
        return rc;
    btf_render_plan p;
    rc = btf__render_plan_scene(m, s, opts, &p, err);
    return finish(g, m, &p, rc, out, info, err);
}

btf_status btf_gpu_render_flat(btf_gpu *g, const btf_model *m, btf_dir view, btf_dir light,
                               const btf_render_opts *opts, btf_image *out,
                               btf_render_info *info, btf_error *err)
{
    btf_status rc = begin(g, out, info, err);
    if (rc)
        return rc;
    btf_render_plan p;
    rc = btf__render_plan_flat(m, view, light, opts, &p, err);
    return finish(g, m, &p, rc, out, info, err);
}
