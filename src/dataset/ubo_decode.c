/*
 * ubo_decode.c — one (view, light) image of a Bonn .btf file, reconstructed
 * from the mapped bytes without expanding the rest (docs/datasets.md,
 * "UBO2014 .btf files"): DFMF d_c = sum_k U_c[lv][k] SxV_c[xy][k]
 * then the colour model (§3a, §3b); FMF value_c = sum_k U[lv*3+c][k] SxV[xy][k]
 * and the dynamic-range restore (§4); PVF's per-view PCA (§5); BDIF's stored
 * halves (§6); then the cosine rule (§3c). Row y = 0 is the file's first row
 * (the first W entries), which btfcar takes as the image's top row (§7;
 * docs/datasets.md, "UBO2014 .btf files", says why).
 *
 * The dot products run over K components per pixel, 8 lanes: lane j sums
 * the products of components j, j+8, ... and the lanes are added in one fixed
 * order, so the F16C path and the portable one give the same bits.
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#include <immintrin.h>
#define UBO_HAVE_F16C_PATH 1
#endif

#define UBO_EPS 1e-5 /* §3b: hard-coded by every reader, not stored */

static float reduce8(const float acc[8])
{
    return ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]));
}

/* out[i * ostride] = sum_k a[k] * b_i[k] for n rows b_i at base + i * stride. */
static void dots_portable(const float *a, uint32_t k, const unsigned char *base, uint64_t stride,
                          int scalar, uint64_t n, float *out, int ostride)
{
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = base + i * stride;
        float acc[8] = {0};
        for (uint32_t j = 0; j < k; j++)
            acc[j & 7] += a[j] * ubo_scalar(b + (uint64_t)j * scalar, scalar);
        out[i * (uint64_t)ostride] = reduce8(acc);
    }
}

#ifdef UBO_HAVE_F16C_PATH
__attribute__((target("f16c,avx"))) static void dots_f16c(const float *a, uint32_t k,
                                                          const unsigned char *base,
                                                          uint64_t stride, uint64_t n,
                                                          float *out, int ostride)
{
    uint32_t k8 = k & ~7u;
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = base + i * stride;
        __m256 acc = _mm256_setzero_ps();
        for (uint32_t j = 0; j < k8; j += 8) {
            __m256 v = _mm256_cvtph_ps(_mm_loadu_si128((const __m128i *)(b + 2 * (uint64_t)j)));
            acc = _mm256_add_ps(acc, _mm256_mul_ps(_mm256_loadu_ps(a + j), v));
        }
        float lanes[8];
        _mm256_storeu_ps(lanes, acc);
        for (uint32_t j = k8; j < k; j++)
            lanes[j & 7] += a[j] * ubo_half_to_float((uint16_t)(b[2 * j] | b[2 * j + 1] << 8));
        out[i * (uint64_t)ostride] = reduce8(lanes);
    }
}

static int have_f16c(void)
{
    unsigned a, b, c, d;
    if (!__get_cpuid(1, &a, &b, &c, &d) || (c & 0x38000000u) != 0x38000000u)
        return 0;
    unsigned lo, hi;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return (lo & 6u) == 6u;
}
#endif

static void dots(const float *a, uint32_t k, const unsigned char *base, uint64_t stride,
                 int scalar, uint64_t n, float *out, int ostride)
{
#ifdef UBO_HAVE_F16C_PATH
    if (scalar == 2 && have_f16c()) {
        dots_f16c(a, k, base, stride, n, out, ostride);
        return;
    }
#endif
    dots_portable(a, k, base, stride, scalar, n, out, ostride);
}

/* Row r of a matrix as floats (its first k components). */
static void row_floats(const ubo_matrix *m, uint64_t r, uint32_t k, float *out)
{
    const unsigned char *p = m->p + r * m->k * (uint64_t)m->scalar;
    for (uint32_t j = 0; j < k; j++)
        out[j] = ubo_scalar(p + (uint64_t)j * m->scalar, m->scalar);
}

/* The chroma matrix M (YUV -> RGB) of §3b. */
static void yuv_to_rgb(double y, double u, double v, float *rgb)
{
    rgb[0] = (float)(y + 1.13983 * v);
    rgb[1] = (float)(y - 0.39465 * u - 0.5806 * v);
    rgb[2] = (float)(y + 2.03211 * u);
}

static double signed_log_inverse(double d)
{
    return (d < 0 ? -1.0 : d > 0 ? 1.0 : 0.0) * UBO_EPS * exp(fabs(d));
}

/* §3b: the decorrelated (d0, d1, d2) of every pixel to RGB in place. */
static void undecorrelate(const ubo_file *f, float *px, uint64_t n)
{
    int model = f->info.colour_model;
    for (uint64_t i = 0; i < n; i++) {
        float *p = px + 3 * i;
        double d0 = p[0], d1 = p[1], d2 = p[2], y;
        switch (model) {
        case 1: yuv_to_rgb(d0, d1, d2, p); break;
        case 3:
            for (int j = 0; j < 3; j++)
                p[j] = (float)(d0 * f->colour_transform[0 * 3 + j] +
                               d1 * f->colour_transform[1 * 3 + j] +
                               d2 * f->colour_transform[2 * 3 + j] + f->colour_mean[j]);
            break;
        case 4:
            p[0] = (float)(d0 + d1 - d2);
            p[1] = (float)(d0 + d2);
            p[2] = (float)(d0 - d1 - d2);
            break;
        case 9: yuv_to_rgb(exp(d0) - UBO_EPS, d1, d2, p); break;
        case 10:
            yuv_to_rgb(exp(d0) - UBO_EPS, signed_log_inverse(d1), signed_log_inverse(d2), p);
            break;
        case 11:
            y = exp(d0);
            yuv_to_rgb(y - UBO_EPS, d1 * y, d2 * y, p);
            break;
        case 12:
            for (int j = 0; j < 3; j++)
                p[j] = (float)(exp((double)p[j]) - UBO_EPS);
            break;
        default: break; /* 0: RGB as stored */
        }
    }
}

static btf_status decode_factors(const ubo_file *f, uint64_t lv, float *out, btf_error *err)
{
    uint64_t px = (uint64_t)f->width * f->height;
    int fmf = f->variant == UBO_FMF;
    uint32_t kmax = 1;
    for (int c = 0; c < 3; c++)
        if (f->u[fmf ? 0 : c].k > kmax)
            kmax = f->u[fmf ? 0 : c].k;
    float *a = btf__alloc(kmax, sizeof *a, err);
    if (!a)
        return BTF_E_NOMEM;
    for (int c = 0; c < 3; c++) {
        const ubo_matrix *u = &f->u[fmf ? 0 : c], *s = &f->sxv[fmf ? 0 : c];
        uint32_t k = fmf ? (uint32_t)f->info.components[0] : u->k;
        /* The small side's row (lv) into a; the big side streams per pixel. */
        const ubo_matrix *small = f->transposed ? s : u, *big = f->transposed ? u : s;
        uint64_t srow = fmf && !f->transposed ? lv * 3 + (uint64_t)c : lv;
        uint64_t bstride = (uint64_t)big->k * big->scalar, bfirst = 0;
        if (fmf && f->transposed) {
            bfirst = (uint64_t)c;
            bstride *= 3;
        }
        row_floats(small, srow, k, a);
        dots(a, k, big->p + bfirst * big->k * (uint64_t)big->scalar, bstride, big->scalar, px,
             out + c, 3);
    }
    free(a);
    if (f->variant == UBO_DFMF)
        undecorrelate(f, out, px);
    else if (f->info.dynamic_range)
        for (uint64_t i = 0; i < 3 * px; i++)
            out[i] = (float)(exp((double)out[i]) - UBO_EPS);
    return BTF_OK;
}

static btf_status decode_pvf(const ubo_file *f, uint32_t v, uint32_t l, float *out, btf_error *err)
{
    const ubo_pvf_slot *sl = &f->slots[v];
    uint64_t px = (uint64_t)f->width * f->height, sz = (uint64_t)sl->scalar;
    float *a = btf__alloc(sl->k ? sl->k : 1, sizeof *a, err);
    if (!a)
        return BTF_E_NOMEM;
    for (int c = 0; c < 3; c++) {
        if (sl->dim == 3 * f->nl) { /* W per pixel, C per light */
            uint64_t r = (uint64_t)l * 3 + (uint64_t)c;
            for (uint32_t j = 0; j < sl->k; j++)
                a[j] = ubo_scalar(sl->c + (r * sl->k + j) * sz, sl->scalar);
            dots(a, sl->k, sl->w, sl->k * sz, sl->scalar, px, out + c, 3);
            float mean = ubo_scalar(sl->mean + r * sz, sl->scalar);
            for (uint64_t i = 0; i < px; i++)
                out[3 * i + c] += mean;
        } else { /* C per pixel, W per light */
            for (uint32_t j = 0; j < sl->k; j++)
                a[j] = ubo_scalar(sl->w + ((uint64_t)l * sl->k + j) * sz, sl->scalar);
            dots(a, sl->k, sl->c + (uint64_t)c * sl->k * sz, 3 * sl->k * sz, sl->scalar, px,
                 out + c, 3);
            for (uint64_t i = 0; i < px; i++)
                out[3 * i + c] += ubo_scalar(sl->mean + (3 * i + (uint64_t)c) * sz, sl->scalar);
        }
    }
    free(a);
    return BTF_OK;
}

static void decode_bdif(const ubo_file *f, uint32_t v, uint32_t l, float *out)
{
    uint64_t px = (uint64_t)f->width * f->height;
    uint64_t per_texel = (uint64_t)f->nv * f->nl * 3 * 2;
    uint64_t a = (f->chunk_stride - 4) / per_texel;
    uint64_t off = ((uint64_t)v * f->nl + l) * 3 * 2;
    for (uint64_t i = 0; i < px; i++) {
        uint64_t s = f->rank ? f->rank[i] : i;
        if (s == UINT32_MAX || s >= f->stored) {
            out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = 0.0f;
            continue;
        }
        const unsigned char *p = f->chunk0 + (s / a) * f->chunk_stride + 4 + (s % a) * per_texel + off;
        for (int c = 0; c < 3; c++)
            out[3 * i + (uint64_t)c] = ubo_half_to_float((uint16_t)(p[2 * c] | p[2 * c + 1] << 8));
    }
}

btf_status ubo_decode(const ubo_file *f, uint32_t fv, uint32_t fl, float *out, btf_error *err)
{
    if (fv >= f->nv || fl >= f->nl)
        return btf__fail(err, BTF_E_ARG, "%s: no view %u, light %u in %u x %u", f->name, fv, fl,
                         f->nv, f->nl);
    uint64_t px = (uint64_t)f->width * f->height;
    if (f->variant == UBO_BDIF) {
        decode_bdif(f, fv, fl, out);
    } else if (f->variant == UBO_PVF) {
        btf_status rc = decode_pvf(f, fv, fl, out, err);
        if (rc)
            return rc;
    } else {
        btf_status rc = decode_factors(f, (uint64_t)fv * f->nl + fl, out, err);
        if (rc)
            return rc;
    }
    /* §3c: the cosine of the light is divided out when the flag says the
     * data hold it (btflib); parsing refused lights at grazing angles. */
    if (f->info.cosine_flag) {
        float inv = (float)(1.0 / cos((double)f->light_rad[2 * fl]));
        for (uint64_t i = 0; i < 3 * px; i++)
            out[i] *= inv;
    }
    for (uint64_t i = 0; i < 3 * px; i++)
        if (!isfinite(out[i]))
            return btf__fail(err, BTF_E_DATA,
                             "%s: view %u, light %u: pixel (%llu, %llu) decodes to a non-finite "
                             "value", f->name, fv, fl, (unsigned long long)(i / 3 % f->width),
                             (unsigned long long)(i / 3 / f->width));
    return BTF_OK;
}
