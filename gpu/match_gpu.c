/*
 * match_gpu.c — colour matching of an image left on the device (docs/gpu.md,
 * "Colour matching on the device"; the CPU's pass: src/synth/colour_match.c).
 * The pass needs the whole image's Lab quantiles before it maps any pixel,
 * so it runs in three steps, one job:
 *   1. match_sample.comp: the Lab of the image's sample grid (the CPU's
 *      grid, at most 16,384 pixels), after the structure layer's multiply;
 *   2. match_sort.comp: a bitonic sort of each channel's samples on the
 *      device (the reduction: the sorted sample, at most 192 KiB, is read
 *      back for the 64 order statistics per channel the quantiles need,
 *      never the image);
 *   3. on the host, the quantiles and the maps by the CPU's own code
 *      (btf__lab_quantiles_at, btf__colour_match_maps: a few microseconds),
 *      then match_apply.comp maps every pixel in place.
 * Each shader does the CPU's float operations in the CPU's order
 * (gpu/match_lab.glsl), so lavapipe gives the CPU's bytes; tests compare
 * them bit for bit.
 */
#include "core/core.h"
#include "model/model.h"
#include "synth/synth.h"

#include "match_layout.h"
#include "synth_gpu.h"
#include "vk.h"

#include "match_apply_spv.h"
#include "match_sample_spv.h"
#include "match_sort_spv.h"

#include <stdlib.h>
#include <string.h>

_Static_assert(BTF_MATCH_SEGS == BTF_LAB_MAP_SEGS, "match_layout.h's segments are the CPU's");
_Static_assert(sizeof(btf_lab_map) == 4 * BTF_MF_MAP_FLOATS, "a map is BTF_MF_MAP_FLOATS floats");

/* The shaders' bindings after the image array's 0-7. */
enum { INTS = BTF_GPU_DEVICE_BUFFERS, FLOATS, PATTERN, KEYS };
_Static_assert(KEYS == 11, "match_sample.comp binds the keys at 11");

struct btf_gpu_matcher {
    btf_vk *vk;
    btf_vk_pipeline *sample, *sort, *apply;
    btf_vk_buffer *placeholder; /* bound where an image buffer or the pattern is unused */
};

btf_status btf__gpu_matcher_create(btf_vk *vk, btf_gpu_matcher **out, btf_error *err)
{
    *out = NULL;
    btf_gpu_matcher *mt = btf__calloc(1, sizeof *mt, err);
    if (!mt)
        return BTF_E_NOMEM;
    mt->vk = vk;
    btf_status rc = btf__vk_pipeline_create(vk, match_sample_spv, sizeof match_sample_spv, 12, 0,
                                            NULL, 0, &mt->sample, err);
    if (rc == BTF_OK)
        rc = btf__vk_pipeline_create(vk, match_sort_spv, sizeof match_sort_spv, 1, 16, NULL, 0,
                                     &mt->sort, err);
    if (rc == BTF_OK)
        rc = btf__vk_pipeline_create(vk, match_apply_spv, sizeof match_apply_spv, 11, 0, NULL, 0,
                                     &mt->apply, err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(vk, 16, &mt->placeholder, err);
    if (rc) {
        btf__gpu_matcher_free(mt);
        return rc;
    }
    *out = mt;
    return BTF_OK;
}

void btf__gpu_matcher_free(btf_gpu_matcher *mt)
{
    if (!mt)
        return;
    btf__vk_pipeline_destroy(mt->sample);
    btf__vk_pipeline_destroy(mt->sort);
    btf__vk_pipeline_destroy(mt->apply);
    btf__vk_buffer_destroy(mt->placeholder);
    free(mt);
}

/* One match's parameters (gpu/match_layout.h) and the host's copy of what
 * the device computes from them. */
typedef struct match_params {
    int32_t ints[BTF_MP_INTS];
    float floats[BTF_MF_MAPS + 3 * BTF_MF_MAP_FLOATS];
    btf_lab_sample grid; /* the CPU's sample grid (its steps and size only) */
    size_t npad;
} match_params;

static void params_fill(match_params *p, const btf_marginal *mg, const btf_gpu_images *im,
                        uint64_t off, int w, int h, const btf_image *pattern, int match,
                        uint32_t max_x)
{
    memset(p->ints, 0, sizeof p->ints);
    memset(p->floats, 0, sizeof p->floats);
    int32_t *pi = p->ints;
    pi[BTF_MP_WIDTH] = w, pi[BTF_MP_HEIGHT] = h;
    pi[BTF_MP_OFF] = (int32_t)off, pi[BTF_MP_CAP] = (int32_t)im->cap;
    pi[BTF_MP_SX] = p->grid.sx, pi[BTF_MP_SY] = p->grid.sy, pi[BTF_MP_COLS] = p->grid.cols;
    pi[BTF_MP_NSAMPLE] = (int32_t)p->grid.n, pi[BTF_MP_NPAD] = (int32_t)p->npad;
    if (pattern && pattern->data) {
        pi[BTF_MP_PW] = pattern->width, pi[BTF_MP_PH] = pattern->height;
        pi[BTF_MP_PCH] = pattern->channels == 3 ? 3 : 1;
    }
    pi[BTF_MP_MATCH] = match;
    uint64_t groups = ((uint64_t)w * h + 63) / 64; /* as dispatch_rows lays them out */
    pi[BTF_MP_ROW_PIX] = 64 * (int32_t)(groups < max_x ? groups : max_x);
    float *pf = p->floats;
    if (match) {
        pf[BTF_MF_SCALE] = btf__lab_scale(mg);
        pf[BTF_MF_INV] = 1.0f / pf[BTF_MF_SCALE]; /* as btf__lab_match_row */
        memcpy(pf + BTF_MF_LO, mg->rgb_lo, 3 * sizeof(float));
        memcpy(pf + BTF_MF_HI, mg->rgb_hi, 3 * sizeof(float));
    }
    btf__lab_constants(pf + BTF_MF_TO_XYZ, pf + BTF_MF_TO_RGB, pf + BTF_MF_CONST,
                       &pi[BTF_MP_MAGIC]);
}

/* The smallest power of two >= n (n <= BTF_LAB_MATCH_SAMPLE). */
static size_t pow2_at_least(size_t n)
{
    size_t p = 1;
    while (p < n)
        p *= 2;
    return p;
}

/* Dispatches `invocations` of 64-wide workgroups in rows of at most the
 * device's x limit; *row_pix: the pixels per row (for the shader). */
static btf_status dispatch_rows(btf_vk_job *job, const btf_vk_pipeline *pipe,
                                btf_vk_buffer *const *bufs, int nbufs, const void *push,
                                uint32_t push_bytes, uint64_t invocations, uint32_t max_x,
                                btf_error *err)
{
    uint64_t groups = (invocations + 63) / 64, gx = groups < max_x ? groups : max_x;
    uint64_t gy = (groups + gx - 1) / gx;
    return btf__vk_job_dispatch(job, pipe, bufs, nbufs, push, push_bytes, (uint32_t)gx,
                                (uint32_t)gy, 1, err);
}

/* The bitonic network over rows of npad keys: for each run length k, each
 * distance j = k/2 .. 1, one step (a dispatch; the job's barriers order them). */
static btf_status record_sort(btf_vk_job *job, const btf_gpu_matcher *mt, btf_vk_buffer *keys,
                              size_t npad, uint32_t max_x, btf_error *err)
{
    btf_status rc = BTF_OK;
    for (uint32_t k = 2; rc == BTF_OK && k <= npad; k *= 2)
        for (uint32_t j = k / 2; rc == BTF_OK && j >= 1; j /= 2) {
            uint32_t push[4] = {j, k, (uint32_t)npad, 0};
            rc = dispatch_rows(job, mt->sort, &keys, 1, push, sizeof push, 3 * (uint64_t)npad,
                               max_x, err);
        }
    return rc;
}

/* Steps 1 and 2 (sample, sort: one job), then the quantiles' order
 * statistics read back and the maps made into p->floats as the CPU makes
 * them. */
static btf_status device_maps(btf_vk *vk, const btf_gpu_matcher *mt, btf_vk_buffer **bufs,
                              const btf_marginal *mg, match_params *p, btf_error *err)
{
    uint32_t max_x = btf__vk_info(vk)->max_workgroup_count[0];
    btf_vk_job *job = NULL;
    btf_status rc = btf__vk_job_begin(vk, &job, err);
    if (rc == BTF_OK)
        rc = dispatch_rows(job, mt->sample, bufs, 12, NULL, 0, p->npad, max_x, err);
    if (rc == BTF_OK)
        rc = record_sort(job, mt, bufs[KEYS], p->npad, max_x, err);
    if (rc == BTF_OK) {
        rc = btf__vk_job_submit_wait(job, err);
        job = NULL;
    }
    btf__vk_job_abort(job);
    size_t ranks[2 * BTF_MARGIN_KNOTS];
    double frac[BTF_MARGIN_KNOTS];
    int nr = btf__lab_quantile_ranks(p->grid.n, ranks, frac);
    float src[3][BTF_MARGIN_KNOTS], *sorted = NULL;
    if (rc == BTF_OK && !(sorted = btf__alloc(3 * p->npad, sizeof(float), err)))
        rc = BTF_E_NOMEM;
    if (rc == BTF_OK) /* one read: a few round trips cost more than 192 KiB on a real GPU */
        rc = btf__vk_buffer_download(vk, bufs[KEYS], 0, sorted, 4 * 3 * (uint64_t)p->npad, err);
    for (int c = 0; rc == BTF_OK && c < 3; c++) {
        float at[2 * BTF_MARGIN_KNOTS];
        for (int r = 0; r < nr; r++)
            at[r] = sorted[c * p->npad + ranks[r]];
        btf__lab_quantiles_at(c, at, frac, src[c]);
    }
    free(sorted);
    if (rc == BTF_OK) {
        btf_lab_map maps[3];
        btf__colour_match_maps(mg, (const float (*)[BTF_MARGIN_KNOTS])src, maps);
        memcpy(p->floats + BTF_MF_MAPS, maps, sizeof maps);
    }
    return rc;
}

static btf_status apply_maps(btf_vk *vk, const btf_gpu_matcher *mt, btf_vk_buffer **bufs,
                             const match_params *p, uint64_t pixels, btf_error *err)
{
    uint32_t max_x = btf__vk_info(vk)->max_workgroup_count[0];
    btf_vk_job *job = NULL;
    btf_status rc = btf__vk_buffer_upload(vk, bufs[FLOATS], 0, p->floats, sizeof p->floats, err);
    if (rc == BTF_OK)
        rc = btf__vk_job_begin(vk, &job, err);
    if (rc == BTF_OK)
        rc = dispatch_rows(job, mt->apply, bufs, 11, NULL, 0, pixels, max_x, err);
    if (rc == BTF_OK) {
        rc = btf__vk_job_submit_wait(job, err);
        job = NULL;
    }
    btf__vk_job_abort(job);
    return rc;
}

btf_status btf__gpu_match_images(btf_vk *vk, const btf_gpu_matcher *mt, const btf_model *m,
                                 int subspace, int match, const btf_gpu_images *im,
                                 uint64_t off, int w, int h, const btf_image *pattern,
                                 btf_error *err)
{
    if (!match && !(pattern && pattern->data))
        return BTF_OK;
    const btf_marginal *mg = &m->subspaces[subspace].marginal;
    uint64_t pixels = (uint64_t)w * h;
    if (off + 3 * pixels > 0x7FFFFFFFull || im->cap > 0x7FFFFFFFull)
        return btf__fail(err, BTF_E_UNSUPPORTED, "colour matching on the device: an image at "
                         "float %llu is past the shaders' 32-bit indices",
                         (unsigned long long)off);
    match_params *p = btf__calloc(1, sizeof *p, err); /* 6 KB of maps: not on the stack */
    if (!p)
        return BTF_E_NOMEM;
    btf_status rc = BTF_OK;
    btf__lab_sample_grid(&p->grid, w, h, BTF_LAB_MATCH_SAMPLE); /* the device holds the values */
    p->npad = pow2_at_least(p->grid.n);
    params_fill(p, mg, im, off, w, h, pattern, match, btf__vk_info(vk)->max_workgroup_count[0]);
    /* bindings: the image array 0-7, ints, floats, the pattern, the keys */
    btf_vk_buffer *bufs[12] = {0};
    for (int b = 0; b < BTF_GPU_DEVICE_BUFFERS; b++)
        bufs[b] = im->buf[b] ? im->buf[b] : mt->placeholder;
    uint64_t pat_floats = pattern && pattern->data
                              ? (uint64_t)pattern->width * pattern->height * pattern->channels
                              : 0;
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(vk, sizeof p->ints, &bufs[INTS], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_create(vk, sizeof p->floats, &bufs[FLOATS], err);
    if (rc == BTF_OK && pat_floats)
        rc = btf__vk_buffer_create(vk, 4 * pat_floats, &bufs[PATTERN], err);
    if (rc == BTF_OK && match)
        rc = btf__vk_buffer_create(vk, 4 * 3 * (uint64_t)p->npad, &bufs[KEYS], err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(vk, bufs[INTS], 0, p->ints, sizeof p->ints, err);
    if (rc == BTF_OK)
        rc = btf__vk_buffer_upload(vk, bufs[FLOATS], 0, p->floats, sizeof p->floats, err);
    if (rc == BTF_OK && pat_floats)
        rc = btf__vk_buffer_upload(vk, bufs[PATTERN], 0, pattern->data, 4 * pat_floats, err);
    btf_vk_buffer *owned[4] = {bufs[INTS], bufs[FLOATS], bufs[PATTERN], bufs[KEYS]};
    bufs[PATTERN] = bufs[PATTERN] ? bufs[PATTERN] : mt->placeholder;
    bufs[KEYS] = bufs[KEYS] ? bufs[KEYS] : mt->placeholder;
    if (rc == BTF_OK && match)
        rc = device_maps(vk, mt, bufs, mg, p, err);
    if (rc == BTF_OK)
        rc = apply_maps(vk, mt, bufs, p, pixels, err);
    for (int i = 0; i < 4; i++)
        btf__vk_buffer_destroy(owned[i]);
    free(p);
    return rc;
}
