/*
 * rf_render_gpu.c — the GPU render pass of reflectance-field models
 * (Meseth, Müller & Klein 2003, section 5: "the four closest measured view
 * directions" evaluated at the exact light and blended, which the paper
 * itself runs in a fragment program; docs/rf.md, "Rendering on the GPU").
 * The host uploads the model's 16-bit codes (two to a 32-bit word, field
 * after field) with each field's and slot's lo and scale, the measured
 * views' angles and rings, a sampled model's coordinate map (paper section
 * 6, src/rf/rf_map.h: one word per surface texel, u | v << 16, in the int
 * buffer; the shader's BTF_RF_TEXEL_AT looks each texel up through it as
 * rf_surface_texel does, clamp included) and the lights;
 * gpu/rf_render.comp evaluates with src/rf/btf_rf_shared.h, the very text
 * the CPU renderer runs.
 *
 *  - flat (view, light): the fields and weights of the view are the same
 *    for every pixel, so the host computes them (rf_look_at, the CPU's own
 *    call) and uploads only those (at most four) fields; the shader shades
 *    each distinct texel once (the tile) and the host expands it, as the
 *    CPU's btf__rf_render_flat does;
 *  - scene: the G-buffer is traced on the host (rf_scene_trace, the CPU
 *    renderer's own trace and checks) and packed as the CAR render pass
 *    packs it (gpu/render_gpu.h); every field is uploaded, since every
 *    pixel picks its own four views.
 *
 * Device limits: the codes go in up to RFP_CODE_BUFS (8) storage buffers
 * of at most the device's largest (whole fields in each), as many as the
 * device binds per stage beside the pass's 4 others; a model that needs
 * more is refused (BTF_E_UNSUPPORTED, pointing to the CPU backend). A
 * G-buffer or output larger than one buffer goes in bands.
 */
#include "core/core.h"
#include "rf/rf.h"

#include "render_gpu.h"
#include "render_layout.h"
#include "rf_layout.h"
#include "synth_gpu.h"
#include "vk.h"

#include "rf_render_spv.h"

#include <stdlib.h>
#include <string.h>

#define NBUFS (4 + RFP_CODE_BUFS) /* gbuf, ints, floats, out, codes */

/* The host copies of the parameter buffers (gpu/rf_layout.h). */
typedef struct rf_params {
    int32_t *ints;
    size_t n_ints;
    float *floats;
    size_t n_floats;
} rf_params;

typedef struct rf_pass {
    btf_vk *vk;
    btf_vk_pipeline *pipe;
    btf_vk_buffer *bufs[NBUFS];
    rf_params pr;
    uint64_t limit;  /* bytes of one storage buffer */
} rf_pass;

static void pass_free(rf_pass *ps)
{
    btf__vk_pipeline_destroy(ps->pipe);
    for (int i = 0; i < NBUFS; i++)
        btf__vk_buffer_destroy(ps->bufs[i]);
    free(ps->pr.ints);
    free(ps->pr.floats);
}

/* A model the pass can read: sizes consistent, slots within the shader's
 * array (a decoded file always is; a model built by hand may not be). */
static btf_status check_model(const btf_rf_model *m, btf_error *err)
{
    if (!m || !m->codes || !m->lo || !m->hi)
        return btf__fail(err, BTF_E_ARG, "GPU RF render: no model");
    /* a sampled model's surface is its coordinate map into the codes
     * (rf_map.h), uploaded with the parameters */
    if (m->map && (m->surface_width < 1 || m->surface_height < 1))
        return btf__fail(err, BTF_E_ARG, "GPU RF render: a sampled model with a %dx%d surface "
                         "(expected sides >= 1)", m->surface_width, m->surface_height);
    int fields = m->fit == BTF_RF_LAFORTUNE ? 1 : m->views.count;
    if (m->fit < BTF_RF_PTM || m->fit > BTF_RF_LAFORTUNE || m->width < 1 || m->height < 1 ||
        m->lobes < 0 || m->lobes > BTF_RF_MAX_LOBES || m->views.count < 1 || !m->views.dirs ||
        m->params != btf__rf_param_count(m->fit, m->lobes) || m->slots != m->params + 3 ||
        m->slots > BTF_RF_MAX_SLOTS || m->fields != fields)
        return btf__fail(err, BTF_E_ARG, "GPU RF render: an inconsistent model (fit %d, %d lobes, "
                         "%d params, %d slots, %d fields, %d views, %dx%d texels)", m->fit,
                         m->lobes, m->params, m->slots, m->fields, m->views.count, m->width,
                         m->height);
    return BTF_OK;
}

/* Words of one field's codes (two 16-bit codes a word, the last padded). */
static uint64_t field_words(const btf_rf_model *m)
{
    return ((uint64_t)m->width * m->height * m->slots + 1) / 2;
}

/* Places the fields with want[f] set into code buffers, whole fields in
 * each, each buffer at most ps->limit bytes: buf[f] (-1: not uploaded),
 * base[f] (first word), words[b] (size of buffer b). */
static btf_status plan_codes(const rf_pass *ps, const btf_rf_model *m, const uint8_t *want,
                             int32_t *buf, int32_t *base, uint64_t words[RFP_CODE_BUFS],
                             btf_error *err)
{
    uint64_t fw = field_words(m), cap = ps->limit / 4;
    int64_t most = (int64_t)btf__vk_info(ps->vk)->max_storage_buffers - 4;
    most = most > RFP_CODE_BUFS ? RFP_CODE_BUFS : most < 1 ? 1 : most;
    if (fw > cap)
        return btf__fail(err, BTF_E_UNSUPPORTED, "GPU RF render: one field's codes (%llu bytes) "
                         "exceed the device's largest storage buffer (%llu bytes); use "
                         "--backend cpu", (unsigned long long)fw * 4,
                         (unsigned long long)ps->limit);
    int b = 0;
    uint64_t total = 0;
    for (int i = 0; i < RFP_CODE_BUFS; i++)
        words[i] = 0;
    for (int f = 0; f < m->fields; f++) {
        buf[f] = -1, base[f] = 0;
        if (!want[f])
            continue;
        total += fw;
        if (words[b] + fw > cap)
            b++;
        if (b >= most)
            return btf__fail(err, BTF_E_UNSUPPORTED, "GPU RF render: the model's codes (%llu "
                             "bytes and more) exceed %d storage buffers of %llu bytes; use "
                             "--backend cpu", (unsigned long long)total * 4, (int)most,
                             (unsigned long long)ps->limit);
        buf[f] = b, base[f] = (int32_t)words[b];
        words[b] += fw;
    }
    return BTF_OK;
}

/* The codes of the planned fields into their buffers, one field at a time
 * through a scratch of its words (code 2i in the low half of word i). */
static btf_status upload_codes(rf_pass *ps, const btf_rf_model *m, const int32_t *buf,
                               const int32_t *base, const uint64_t words[RFP_CODE_BUFS],
                               btf_error *err)
{
    btf_status rc = BTF_OK;
    for (int b = 0; rc == BTF_OK && b < RFP_CODE_BUFS; b++)
        rc = btf__vk_buffer_create(ps->vk, words[b] ? words[b] * 4 : 16, &ps->bufs[4 + b], err);
    uint64_t fw = field_words(m);
    size_t codes = (size_t)m->width * m->height * m->slots;
    uint32_t *w = rc == BTF_OK ? btf__alloc((size_t)fw, sizeof *w, err) : NULL;
    if (rc == BTF_OK && !w)
        rc = BTF_E_NOMEM;
    for (int f = 0; rc == BTF_OK && f < m->fields; f++) {
        if (buf[f] < 0)
            continue;
        const uint16_t *q = m->codes + (size_t)f * codes;
        for (size_t i = 0; i < (size_t)fw; i++) {
            uint32_t hi = 2 * i + 1 < codes ? q[2 * i + 1] : 0;
            w[i] = (uint32_t)q[2 * i] | hi << 16;
        }
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[4 + buf[f]], (uint64_t)base[f] * 4, w,
                                   fw * 4, err);
    }
    free(w);
    return rc;
}

/* Appends n ints (floats) to the parameters; their offset, -1 without
 * memory. */
static long add_ints(rf_params *pr, const int32_t *v, size_t n)
{
    int32_t *p = realloc(pr->ints, (pr->n_ints + n) * sizeof *p);
    if (!p)
        return -1;
    pr->ints = p;
    memcpy(p + pr->n_ints, v, n * sizeof *v);
    pr->n_ints += n;
    return (long)(pr->n_ints - n);
}

static long add_floats(rf_params *pr, const float *v, size_t n)
{
    float *p = realloc(pr->floats, (pr->n_floats + n) * sizeof *p);
    if (!p)
        return -1;
    pr->floats = p;
    memcpy(p + pr->n_floats, v, n * sizeof *v);
    pr->n_floats += n;
    return (long)(pr->n_floats - n);
}

/* The model's side of the parameters: header, field placement, lo and
 * scale of every field and slot, the views' angles and rings, a sampled
 * model's coordinate map (one word per surface texel, u | v << 16). */
static btf_status model_params(rf_params *pr, const btf_rf_model *m, const int32_t *buf,
                               const int32_t *base, btf_error *err)
{
    int32_t zi[RFP_INTS] = {0};
    float zf[RFP_FLOATS] = {0};
    size_t nfs = (size_t)m->fields * m->slots, nv = (size_t)m->views.count;
    float *lo = btf__alloc(nfs, sizeof *lo, err), *sc = btf__alloc(nfs, sizeof *sc, err);
    float *th = btf__alloc(nv, sizeof *th, err), *ph = btf__alloc(nv, sizeof *ph, err);
    int32_t *ring = btf__alloc(nv, sizeof *ring, err);
    size_t nmap = m->map ? (size_t)m->surface_width * (size_t)m->surface_height : 0;
    int32_t *map = m->map ? btf__alloc(nmap, sizeof *map, err) : NULL;
    btf_status rc = lo && sc && th && ph && ring && (map || !nmap) ? BTF_OK : BTF_E_NOMEM;
    for (size_t i = 0; rc == BTF_OK && i < nmap; i++)
        map[i] = (int32_t)((uint32_t)m->map[2 * i] | (uint32_t)m->map[2 * i + 1] << 16);
    for (size_t i = 0; rc == BTF_OK && i < nfs; i++)
        lo[i] = m->lo[i], sc[i] = btf_rf_scale(m->lo[i], m->hi[i]);
    for (size_t i = 0; rc == BTF_OK && i < nv; i++) {
        th[i] = (float)m->views.dirs[i].theta, ph[i] = (float)m->views.dirs[i].phi;
        ring[i] = rf_ring_end(&m->views, (int)i);
    }
    long o[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
    if (rc == BTF_OK) {
        add_ints(pr, zi, RFP_INTS), add_floats(pr, zf, RFP_FLOATS);
        o[0] = add_ints(pr, buf, (size_t)m->fields), o[1] = add_ints(pr, base, (size_t)m->fields);
        o[2] = add_ints(pr, ring, nv), o[3] = add_floats(pr, lo, nfs);
        o[4] = add_floats(pr, sc, nfs), o[5] = add_floats(pr, th, nv);
        o[6] = add_floats(pr, ph, nv);
        o[7] = nmap ? add_ints(pr, map, nmap) : 0;
    }
    for (int i = 0; rc == BTF_OK && i < 8; i++)
        if (o[i] < 0 || pr->n_ints < RFP_INTS || pr->n_floats < RFP_FLOATS)
            rc = btf__fail(err, BTF_E_NOMEM, "GPU RF render: out of memory for the parameters");
    if (rc == BTF_OK) {
        int32_t *h = pr->ints;
        h[RFP_FIT] = m->fit, h[RFP_LOBES] = m->lobes, h[RFP_NPARAMS] = m->params;
        h[RFP_SLOTS] = m->slots, h[RFP_WIDTH] = rf_surface_w(m), h[RFP_HEIGHT] = rf_surface_h(m);
        h[RFP_SAMPLE_W] = m->width, h[RFP_SAMPLE_H] = m->height;
        h[RFP_MAP] = nmap ? (int32_t)o[7] : -1;
        h[RFP_NVIEWS] = m->views.count;
        h[RFP_FIELD_BUF] = (int32_t)o[0], h[RFP_FIELD_BASE] = (int32_t)o[1];
        h[RFP_RING_END] = (int32_t)o[2], h[RFP_LO] = (int32_t)o[3];
        h[RFP_SCALE] = (int32_t)o[4], h[RFP_THETA] = (int32_t)o[5], h[RFP_PHI] = (int32_t)o[6];
        rf_ctx c = rf_ctx_of(m);
        pr->floats[RFP_INV_W] = c.inv_w, pr->floats[RFP_INV_H] = c.inv_h;
    }
    free(lo), free(sc), free(th), free(ph), free(ring), free(map);
    return rc;
}

/* The scene's lights as the C accessors of src/rf/rf.h read them. */
static btf_status light_params(rf_params *pr, const btf_scene *s, btf_error *err)
{
    int n = s->n_lights;
    int32_t *kind = btf__alloc((size_t)n + 1, sizeof *kind, err);
    float *vec = btf__alloc(3 * (size_t)n + 1, sizeof *vec, err);
    float *rgb = btf__alloc(3 * (size_t)n + 1, sizeof *rgb, err);
    btf_status rc = kind && vec && rgb ? BTF_OK : BTF_E_NOMEM;
    for (int j = 0; rc == BTF_OK && j < n; j++) {
        const btf_light *lt = &s->lights[j];
        kind[j] = (int32_t)lt->kind;
        for (int k = 0; k < 3; k++) {
            vec[3 * j + k] = lt->kind == BTF_LIGHT_POINT ? (float)lt->position[k]
                                                         : (float)lt->direction[k];
            rgb[3 * j + k] = lt->rgb[k];
        }
    }
    long a = rc ? -1 : add_ints(pr, kind, (size_t)n + 1);
    long b = rc ? -1 : add_floats(pr, vec, 3 * (size_t)n + 1);
    long c = rc ? -1 : add_floats(pr, rgb, 3 * (size_t)n + 1);
    if (rc == BTF_OK && (a < 0 || b < 0 || c < 0))
        rc = btf__fail(err, BTF_E_NOMEM, "GPU RF render: out of memory for the lights");
    if (rc == BTF_OK) {
        pr->ints[RFP_NLIGHTS] = n, pr->ints[RFP_LIGHT_KIND] = (int32_t)a;
        pr->ints[RFP_LIGHT_VEC] = (int32_t)b, pr->ints[RFP_LIGHT_RGB] = (int32_t)c;
        for (int k = 0; k < 3; k++)
            pr->floats[RFP_BG + k] = s->background[k];
    }
    free(kind), free(vec), free(rgb);
    return rc;
}

/* Opens the pass on g: the codes of the fields with want[f] set, the
 * model's parameters (the caller adds the mode's to ps->pr before
 * pass_upload). */
static btf_status pass_open(rf_pass *ps, btf_gpu *g, const btf_rf_model *m, const uint8_t *want,
                            btf_error *err)
{
    memset(ps, 0, sizeof *ps);
    ps->vk = btf__gpu_vk(g);
    ps->limit = btf__gpu_max_buffer_bytes(g);
    if (ps->limit > (1ull << 31) - 4) /* int32 word offsets */
        ps->limit = (1ull << 31) - 4;
    int32_t *buf = btf__alloc((size_t)m->fields, sizeof *buf, err);
    int32_t *base = btf__alloc((size_t)m->fields, sizeof *base, err);
    uint64_t words[RFP_CODE_BUFS];
    btf_status rc = buf && base ? BTF_OK : BTF_E_NOMEM;
    if (rc == BTF_OK)
        rc = plan_codes(ps, m, want, buf, base, words, err);
    if (rc == BTF_OK)
        rc = upload_codes(ps, m, buf, base, words, err);
    if (rc == BTF_OK)
        rc = model_params(&ps->pr, m, buf, base, err);
    if (rc == BTF_OK)
        rc = btf__vk_pipeline_create(ps->vk, rf_render_spv, sizeof rf_render_spv, NBUFS, 0, NULL,
                                     0, &ps->pipe, err);
    free(buf);
    free(base);
    return rc;
}

/* The parameter buffers, once complete. */
static btf_status pass_upload(rf_pass *ps, btf_error *err)
{
    /* the int parameters hold a sampled model's map, 4 bytes a surface texel */
    uint64_t ib = ps->pr.n_ints * sizeof(int32_t);
    if (ps->pr.ints[RFP_MAP] >= 0 && ib > ps->limit)
        return btf__fail(err, BTF_E_UNSUPPORTED, "GPU RF render: the int parameters with the "
                         "coordinate map (%llu bytes) exceed the device's largest storage "
                         "buffer (%llu bytes); use --backend cpu", (unsigned long long)ib,
                         (unsigned long long)ps->limit);
    btf_status rc = btf__vk_buffer_create(ps->vk, ps->pr.n_ints * sizeof(int32_t), &ps->bufs[1],
                                          err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, ps->pr.n_floats * sizeof(float), &ps->bufs[2], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[1], 0, ps->pr.ints,
                                   ps->pr.n_ints * sizeof(int32_t), err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[2], 0, ps->pr.floats,
                                   ps->pr.n_floats * sizeof(float), err);
    return rc;
}

/* One band: npix invocations (tile mode: from tile texel pix0), their
 * colours downloaded into dst (npix x 3 floats). */
static btf_status run_band(rf_pass *ps, size_t npix, size_t pix0, float *dst, btf_error *err)
{
    uint32_t groups = (uint32_t)((npix + 63) / 64);
    uint32_t gx = groups < 65535 ? groups : 65535, gy = (groups + gx - 1) / gx;
    ps->pr.ints[RFP_NPIX] = (int32_t)npix;
    ps->pr.ints[RFP_ROW_PIX] = (int32_t)(gx * 64);
    ps->pr.ints[RFP_PIX0] = (int32_t)pix0;
    btf_status rc = btf__vk_buffer_upload(ps->vk, ps->bufs[1], 0, ps->pr.ints,
                                          RFP_INTS * sizeof(int32_t), err);
    btf_vk_job *job = NULL;
    if (rc == BTF_OK)
        rc = btf__vk_job_begin(ps->vk, &job, err);
    if (rc == BTF_OK)
        rc = btf__vk_job_dispatch(job, ps->pipe, ps->bufs, NBUFS, NULL, 0, gx, gy, 1, err);
    if (rc == BTF_OK) {
        rc = btf__vk_job_submit_wait(job, err);
        job = NULL;
    }
    btf__vk_job_abort(job);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_download(ps->vk, ps->bufs[3], 0, dst, npix * 3 * sizeof(float), err);
    return rc;
}

/* Pixels per band: the band's input (in_bytes a pixel) and output must
 * each fit one storage buffer. */
static size_t band_pixels(const rf_pass *ps, size_t in_bytes, size_t total)
{
    size_t per = in_bytes > 3 * sizeof(float) ? in_bytes : 3 * sizeof(float);
    size_t n = (size_t)(ps->limit / per);
    return n < total ? n : total;
}

/* Tile mode: the tile_w x tile_h texels into tile (3 floats each). */
static btf_status shade_tile(rf_pass *ps, int tile_w, int tile_h, float *tile, btf_error *err)
{
    size_t total = (size_t)tile_w * tile_h, band = band_pixels(ps, 0, total);
    ps->pr.ints[RFP_TILE_W] = tile_w;
    btf_status rc = btf__vk_buffer_create(ps->vk, 16, &ps->bufs[0], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, band * 3 * sizeof(float), &ps->bufs[3], err);
    for (size_t p0 = 0; rc == BTF_OK && p0 < total; p0 += band)
        rc = run_band(ps, total - p0 < band ? total - p0 : band, p0, tile + 3 * p0, err);
    return rc;
}

/* Scene mode: the frame in bands of rows of the G-buffer. */
static btf_status shade_scene(rf_pass *ps, const btf_gbuffer *g, btf_image *out, btf_error *err)
{
    size_t rows = band_pixels(ps, BTF_RP_GB * sizeof(float), (size_t)g->width * g->height) /
                  (size_t)g->width;
    if (rows < 1)
        return btf__fail(err, BTF_E_UNSUPPORTED, "GPU RF render: one row of %d pixels needs "
                         "more than the device's largest storage buffer", g->width);
    size_t band_px = rows * g->width;
    float *scratch = btf__alloc(band_px, BTF_RP_GB * sizeof(float), err);
    btf_status rc = scratch ? BTF_OK : BTF_E_NOMEM;
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, band_px * BTF_RP_GB * sizeof(float), &ps->bufs[0], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(ps->vk, band_px * 3 * sizeof(float), &ps->bufs[3], err);
    for (int y0 = 0; rc == BTF_OK && y0 < g->height; y0 += (int)rows) {
        int y1 = y0 + (int)rows < g->height ? y0 + (int)rows : g->height;
        size_t npix = (size_t)(y1 - y0) * g->width;
        btf__render_pack_gbuffer(g, y0, y1, scratch);
        rc = btf__vk_buffer_upload(ps->vk, ps->bufs[0], 0, scratch,
                                   npix * BTF_RP_GB * sizeof(float), err);
        if (rc == BTF_OK)
            rc = run_band(ps, npix, 0, out->data + (size_t)y0 * g->width * 3, err);
    }
    free(scratch);
    return rc;
}

btf_status btf__gpu_rf_render_flat(btf_gpu *g, const btf_rf_model *m, btf_dir view,
                                   btf_dir light, int width, int height, btf_image *out,
                                   btf_render_info *info, btf_error *err)
{
    if (info)
        memset(info, 0, sizeof *info);
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_gpu_rf_render_flat: no output image");
    memset(out, 0, sizeof *out);
    if (!g)
        return btf__fail(err, BTF_E_ARG, "btf_gpu_rf_render_flat: no device");
    btf_status rc = check_model(m, err);
    if (rc == BTF_OK)
        rc = rf_flat_check(m, view, light, width, height, 0, err);
    if (rc)
        return rc;
    int sw = rf_surface_w(m), sh = rf_surface_h(m);
    width = width ? width : sw;
    height = height ? height : sh;
    double t0 = btf__now();
    /* the fields and weights of the view: the CPU render's own call */
    rf_look look = rf_look_at(m, view);
    int fs[4] = {look.vs.i0, look.vs.i1, look.vs.i2, look.vs.i3};
    float ws[4] = {look.vs.w0, look.vs.w1, look.vs.w2, look.vs.w3};
    uint8_t *want = btf__calloc((size_t)m->fields, 1, err);
    if (!want)
        return BTF_E_NOMEM;
    for (int i = 0; i < 4; i++)
        want[fs[i]] |= ws[i] != 0.0f;
    rf_pass ps;
    rc = pass_open(&ps, g, m, want, err);
    free(want);
    if (rc == BTF_OK) {
        double l[3];
        btf_dir_to_vec(light, l);
        ps.pr.ints[RFP_MODE] = RFP_MODE_TILE;
        for (int i = 0; i < 4; i++)
            ps.pr.ints[RFP_VIEW_F + i] = fs[i], ps.pr.floats[RFP_VIEW_W + i] = ws[i];
        for (int k = 0; k < 3; k++)
            ps.pr.floats[RFP_LIGHT + k] = (float)l[k], ps.pr.floats[RFP_VIEW + k] = look.v[k];
        rc = pass_upload(&ps, err);
    }
    double t1 = btf__now();
    /* the surface's distinct texels, as btf__rf_render_flat shades them */
    int tile_w = width < sw ? width : sw, tile_h = height < sh ? height : sh;
    float *tile = rc == BTF_OK ? btf__alloc((size_t)tile_w * tile_h, 3 * sizeof(float), err) : NULL;
    if (rc == BTF_OK && !tile)
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK)
        rc = shade_tile(&ps, tile_w, tile_h, tile, err);
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, height, 3, err);
    if (rc == BTF_OK)
        rf_tile_expand(tile, tile_w, sw, sh, out);
    free(tile);
    pass_free(&ps);
    if (rc == BTF_OK && info)
        info->synth_s = t1 - t0, info->shade_s = btf__now() - t1;
    return rc;
}

btf_status btf__gpu_rf_render_scene(btf_gpu *g, const btf_rf_model *m, const btf_scene *s,
                                    int width, int height, int threads, btf_image *out,
                                    btf_render_info *info, btf_error *err)
{
    if (info)
        memset(info, 0, sizeof *info);
    if (!out)
        return btf__fail(err, BTF_E_ARG, "btf_gpu_rf_render_scene: no output image");
    memset(out, 0, sizeof *out);
    if (!g)
        return btf__fail(err, BTF_E_ARG, "btf_gpu_rf_render_scene: no device");
    btf_status rc = check_model(m, err);
    if (rc)
        return rc;
    btf_gbuffer gb;
    double t0 = btf__now();
    rc = rf_scene_trace(m, s, &width, &height, threads, &gb, err);
    double t1 = btf__now();
    uint8_t *want = rc == BTF_OK ? btf__alloc((size_t)m->fields, 1, err) : NULL;
    if (rc == BTF_OK && !want)
        rc = BTF_E_NOMEM;
    rf_pass ps;
    memset(&ps, 0, sizeof ps);
    if (rc == BTF_OK) {
        memset(want, 1, (size_t)m->fields);
        rc = pass_open(&ps, g, m, want, err);
    }
    free(want);
    if (rc == BTF_OK) {
        ps.pr.ints[RFP_MODE] = RFP_MODE_SCENE;
        rc = light_params(&ps.pr, s, err);
    }
    if (rc == BTF_OK)
        rc = pass_upload(&ps, err);
    double t2 = btf__now();
    if (rc == BTF_OK)
        rc = btf_image_alloc(out, width, height, 3, err);
    if (rc == BTF_OK && (rc = shade_scene(&ps, &gb, out, err)))
        btf_image_free(out);
    pass_free(&ps);
    btf__gbuffer_free(&gb);
    if (rc == BTF_OK && info)
        info->trace_s = t1 - t0, info->synth_s = t2 - t1, info->shade_s = btf__now() - t2;
    return rc;
}
