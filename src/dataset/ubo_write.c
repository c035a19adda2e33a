/*
 * ubo_write.c — writing Bonn .btf files (docs/datasets.md, "UBO2014 .btf
 * files"): the common header as btflib's writer emits it
 * (dataset/ubo_out.c), then the body of the variant:
 *
 *   DFMF  (§3) no rotations, the colour model as given, per channel S, U
 *         and S x V;
 *   FMF   (§4) "!FMF12FCER" (rotations, then the extended header: version,
 *         dynamic_range_reduction_method, the height map's sides and
 *         values), "!FMF06FCR" (rotations) or "!FMF06FC" (neither); then
 *         K, the scalar size, K again, rows, columns, S, U and S x V;
 *         btf_ubo2014_variant names each signature (and the logarithmic
 *         FMF) as a value of its own;
 *   BDIF  (§6) 4 scan lines per chunk, compression 0, an all-ones mask, no
 *         rotations, chunks of halves per texel;
 *   PVF   (§5) in dataset/ubo_write_pvf.c.
 *
 * From images, btf_ubo2014_write factorises with dataset/ubo_factor.c (DFMF,
 * FMF) or dataset/ubo_write_pvf.c (PVF), or stores the halves (BDIF).
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* S: the norms of S x V's columns (the readers ignore it, §3). */
static btf_status store_norms(unsigned char **p, const float *sxv, uint64_t rows, uint32_t k,
                              int s)
{
    for (uint32_t j = 0; j < k; j++) {
        double n2 = 0;
        for (uint64_t r = 0; r < rows; r++)
            n2 += (double)sxv[r * k + j] * sxv[r * k + j];
        ubo_store(*p, (float)sqrt(n2), s);
        *p += s;
    }
    return BTF_OK;
}

/* One matrix block of a DFMF channel or an FMF body: S, U, S x V. */
static btf_status store_factors(unsigned char **p, const float *s_values, const float *u,
                                uint64_t rows, const float *sxv, uint64_t cols, uint32_t k,
                                int s, const char *path, const char *channel, btf_error *err)
{
    char what[64];
    btf_status rc = s_values ? ubo_store_all(p, s_values, k, s, path, "S", err)
                             : store_norms(p, sxv, cols, k, s);
    snprintf(what, sizeof what, "U%s", channel);
    if (rc == BTF_OK)
        rc = ubo_store_all(p, u, rows * k, s, path, what, err);
    snprintf(what, sizeof what, "SxV%s", channel);
    if (rc == BTF_OK)
        rc = ubo_store_all(p, sxv, cols * k, s, path, what, err);
    return rc;
}

static void put_u32_at(unsigned char **p, uint32_t v)
{
    ubo_wr32(*p, v);
    *p += 4;
}

btf_status btf__ubo2014_write_factors(const char *path, const btf_dirset *views,
                                      const btf_dirset *lights, int width, int height,
                                      const btf_ubo2014_factors *f, btf_error *err)
{
    btf_status rc = ubo_check_sets(path, views, lights, width, height, err);
    if (rc)
        return rc;
    int s = f->scalar_size ? f->scalar_size : 2;
    if (s != 2 && s != 4 && s != 8)
        return btf__fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2, 4 or 8", path, s);
    int kmax = 0;
    for (int c = 0; c < 3; c++) {
        if (f->components[c] < 1 || !f->u[c] || !f->sxv[c])
            return btf__fail(err, BTF_E_ARG, "%s: channel %d has %d components or no matrices",
                             path, c, f->components[c]);
        kmax = f->components[c] > kmax ? f->components[c] : kmax;
    }
    uint64_t rows = (uint64_t)views->count * lights->count, cols = (uint64_t)width * height;
    ubo_bytes h = {0};
    ubo_common_header(&h, "!DFMF08FCR", views, lights, width, height, f->cosine_flag);
    ubo_put_u32(&h, 0); /* num_rotations */
    ubo_put_u32(&h, (uint32_t)kmax);
    ubo_put_u32(&h, (uint32_t)f->colour_model);
    for (int i = 0; i < 3; i++)
        ubo_put_f32(&h, 0.0f);
    for (int i = 0; i < 9; i++)
        ubo_put_f32(&h, i % 4 == 0 ? 1.0f : 0.0f);
    uint64_t body = 0;
    for (int c = 0; c < 3; c++)
        body += 13 + (uint64_t)s * f->components[c] * (1 + rows + cols);
    ubo_outfile o;
    unsigned char *p;
    rc = ubo_out_header(&o, path, &h, body, &p, err);
    if (rc)
        return rc;
    static const char *const names[3] = {" of channel 0", " of channel 1", " of channel 2"};
    for (int c = 0; c < 3 && rc == BTF_OK; c++) {
        uint32_t k = (uint32_t)f->components[c];
        *p++ = (unsigned char)s;
        put_u32_at(&p, k);
        put_u32_at(&p, (uint32_t)rows);
        put_u32_at(&p, (uint32_t)cols);
        rc = store_factors(&p, NULL, f->u[c], rows, f->sxv[c], cols, k, s, path, names[c], err);
    }
    return ubo_out_close(&o, path, rc, err);
}

/* ------------------------------------------------------------------- FMF */

/* The signature's flags: rotations field, extended header. */
static int fmf_signature(const char *sig, int *rotations, int *extended)
{
    static const struct {
        const char *sig;
        int rotations, extended;
    } S[] = {{"!FMF12FCER", 1, 1}, {"!FMF06FCR", 1, 0}, {"!FMF06FC", 0, 0}};
    for (size_t i = 0; i < sizeof S / sizeof S[0]; i++)
        if (sig && !strcmp(sig, S[i].sig)) {
            *rotations = S[i].rotations;
            *extended = S[i].extended;
            return 1;
        }
    return 0;
}

static btf_status check_fmf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                            int width, int height, const ubo_fmf *f, btf_error *err)
{
    uint64_t n = (uint64_t)views->count * lights->count, px = (uint64_t)width * height;
    int normal = f->rows == 3 * n && f->cols == px, transposed = f->rows == 3 * px && f->cols == n;
    if (!normal && !transposed)
        return btf__fail(err, BTF_E_ARG, "%s: FMF matrix %u x %u: expected %llu x %llu or %llu x "
                         "%llu", path, f->rows, f->cols, (unsigned long long)(3 * n),
                         (unsigned long long)px, (unsigned long long)(3 * px),
                         (unsigned long long)n);
    if (f->scalar_size != 2 && f->scalar_size != 4 && f->scalar_size != 8)
        return btf__fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2, 4 or 8", path,
                         f->scalar_size);
    if (f->k < 1 || !f->u || !f->sxv)
        return btf__fail(err, BTF_E_ARG, "%s: FMF with %u components or no matrices", path, f->k);
    if (f->header_version < 0 || f->header_version > 2)
        return btf__fail(err, BTF_E_ARG, "%s: FMF header version %d: expected 0, 1 or 2", path,
                         f->header_version);
    return BTF_OK;
}

/* §4: the extended header of "!FMF12FCER" (after the rotations). */
static void put_fmf_extended(ubo_bytes *h, const ubo_fmf *f)
{
    ubo_put_u8(h, (unsigned)f->header_version);
    if (f->header_version >= 1)
        ubo_put_u32(h, f->drr);
    if (f->header_version >= 2) {
        ubo_put_u32(h, f->hm_a);
        ubo_put_u32(h, f->hm_b);
        for (uint64_t i = 0; f->height_map && i < (uint64_t)f->hm_a * f->hm_b; i++) {
            uint16_t v = ubo_float_to_half(f->height_map[i]);
            ubo_put(h, &(unsigned char[2]){(unsigned char)v, (unsigned char)(v >> 8)}, 2);
        }
    }
}

btf_status ubo_write_fmf(const char *path, const btf_dirset *views, const btf_dirset *lights,
                         int width, int height, const ubo_fmf *f, btf_error *err)
{
    int rotations = 0, extended = 0;
    btf_status rc = ubo_check_sets(path, views, lights, width, height, err);
    if (rc == BTF_OK && !fmf_signature(f->signature, &rotations, &extended))
        rc = btf__fail(err, BTF_E_ARG, "%s: FMF signature \"%s\": expected !FMF12FCER, !FMF06FCR "
                       "or !FMF06FC", path, f->signature ? f->signature : "(none)");
    if (rc == BTF_OK)
        rc = check_fmf(path, views, lights, width, height, f, err);
    if (rc)
        return rc;
    ubo_bytes h = {0};
    ubo_common_header(&h, f->signature, views, lights, width, height, 0);
    if (rotations)
        ubo_put_u32(&h, 0);
    if (extended)
        put_fmf_extended(&h, f);
    ubo_put_u32(&h, f->k_file ? f->k_file : f->k);
    ubo_put_u8(&h, (unsigned)f->scalar_size);
    ubo_put_u32(&h, f->k);
    ubo_put_u32(&h, f->rows);
    ubo_put_u32(&h, f->cols);
    uint64_t body = (uint64_t)f->scalar_size * f->k * (1 + (uint64_t)f->rows + f->cols);
    ubo_outfile o;
    unsigned char *p;
    rc = ubo_out_header(&o, path, &h, body, &p, err);
    if (rc == BTF_OK)
        rc = store_factors(&p, f->s, f->u, f->rows, f->sxv, f->cols, f->k, f->scalar_size, path,
                           "", err);
    return ubo_out_close(&o, path, rc, err);
}

/* ------------------------------------------------------------------ BDIF */

static btf_status write_bdif(const ubo_source *src, btf_ubo2014_write_stats *st, btf_error *err)
{
    const uint32_t lines = 4;
    const char *path = src->path;
    int width = src->width;
    uint64_t n = (uint64_t)src->views->count * src->lights->count;
    uint64_t px = (uint64_t)width * src->height;
    uint64_t per_texel = n * 3 * 2, a = (uint64_t)width * lines;
    uint64_t chunks = (px + a - 1) / a;
    if (a * per_texel > UINT32_MAX)
        return btf__fail(err, BTF_E_ARG, "%s: a chunk of %llu texels of %llu bytes exceeds the "
                         "format's 4 GiB chunk size", path, (unsigned long long)a,
                         (unsigned long long)per_texel);
    ubo_bytes h = {0};
    ubo_common_header(&h, "!BDIF06R2!", src->views, src->lights, width, src->height, 0);
    ubo_put_u32(&h, lines);
    ubo_put_u8(&h, 0);
    for (uint64_t i = 0; i < px; i++)
        ubo_put_u8(&h, 1);
    ubo_put_u32(&h, 0); /* num_rotations */
    ubo_outfile of;
    unsigned char *base;
    btf_status rc = ubo_out_header(&of, path, &h, chunks * 4 + px * per_texel, &base, err);
    if (rc)
        return rc;
    for (uint64_t i = 0; i < chunks; i++) {
        uint64_t t = i + 1 < chunks ? a : px - i * a;
        ubo_wr32(base + i * (4 + a * per_texel), (uint32_t)(t * per_texel));
    }
    double sum2[3] = {0}, maxe[3] = {0};
    for (uint64_t pair = 0; pair < n && rc == BTF_OK; pair++) {
        btf_image img = {0};
        rc = ubo_get_image(src, pair, &img, err);
        for (uint64_t i = 0; rc == BTF_OK && i < px; i++) {
            unsigned char *p = base + (i / a) * (4 + a * per_texel) + 4 + (i % a) * per_texel +
                               pair * 6;
            for (int c = 0; c < 3; c++) {
                float x = img.data[3 * i + (uint64_t)c];
                ubo_store(p + 2 * c, x, 2);
                double e = (double)ubo_stored(x, 2) - x;
                sum2[c] += e * e;
                maxe[c] = fmax(maxe[c], fabs(e));
            }
        }
        btf_image_free(&img);
        ubo_report(src, (double)(pair + 1) / (double)n, "writing images");
    }
    rc = ubo_out_close(&of, path, rc, err);
    for (int c = 0; rc == BTF_OK && st && c < 3; c++) {
        st->rms_error[c] = sqrt(sum2[c] / (double)(n * px));
        st->max_error[c] = maxe[c];
        st->energy[c] = 1.0;
    }
    return rc;
}

/* ------------------------------------------------------- from the images */

static btf_status write_dfmf(const ubo_source *src, const btf_ubo2014_write_opts *o,
                             btf_ubo2014_write_stats *st, btf_error *err)
{
    ubo_factors fa;
    btf_status rc = ubo_factorise(src, 0, 0, o->components, o->scalar_size, o->max_bytes, &fa, st,
                                  err);
    if (rc)
        return rc;
    btf_ubo2014_factors f = {.colour_model = 0, .scalar_size = o->scalar_size};
    for (int c = 0; c < 3; c++) {
        f.components[c] = fa.kc[c];
        f.u[c] = fa.u[c];
        f.sxv[c] = fa.sxv[c];
    }
    rc = btf__ubo2014_write_factors(src->path, src->views, src->lights, src->width, src->height, &f,
                                    err);
    ubo_factors_free(&fa);
    return rc;
}

static btf_status write_fmf_images(const ubo_source *src, const btf_ubo2014_write_opts *o,
                                   const char *sig, int log_values, btf_ubo2014_write_stats *st,
                                   btf_error *err)
{
    ubo_factors fa;
    btf_status rc = ubo_factorise(src, 1, log_values, o->components, o->scalar_size,
                                  o->max_bytes, &fa, st, err);
    if (rc)
        return rc;
    uint64_t n = (uint64_t)src->views->count * src->lights->count;
    ubo_fmf f = {.signature = sig, .header_version = 2, .drr = log_values ? 1 : 0,
                 .scalar_size = o->scalar_size, .k = (uint32_t)fa.kc[0],
                 .rows = (uint32_t)(3 * n), .cols = (uint32_t)src->width * (uint32_t)src->height,
                 .u = fa.u[0], .sxv = fa.sxv[0]};
    rc = ubo_write_fmf(src->path, src->views, src->lights, src->width, src->height, &f, err);
    ubo_factors_free(&fa);
    return rc;
}

btf_ubo2014_write_opts btf_ubo2014_write_defaults(void)
{
    return (btf_ubo2014_write_opts){.struct_size = sizeof(btf_ubo2014_write_opts),
                                    .variant = BTF_UBO2014_DFMF, .components = 16,
                                    .scalar_size = 2, .max_bytes = (uint64_t)1 << 31};
}

/* What each variant is written as: its body, its signature, and for FMF
 * whether the values are stored as logarithms (§4's dynamic-range flag). */
static const struct {
    int body; /* BTF_UBO2014_DFMF, _BDIF, _FMF or _PVF */
    const char *sig;
    int log_values;
} VARIANTS[] = {
    [BTF_UBO2014_DFMF] = {BTF_UBO2014_DFMF, "!DFMF08FCR", 0},
    [BTF_UBO2014_BDIF] = {BTF_UBO2014_BDIF, "!BDIF06R2!", 0},
    [BTF_UBO2014_FMF] = {BTF_UBO2014_FMF, "!FMF12FCER", 0},
    [BTF_UBO2014_FMF_LOG] = {BTF_UBO2014_FMF, "!FMF12FCER", 1},
    [BTF_UBO2014_FMF06R] = {BTF_UBO2014_FMF, "!FMF06FCR", 0},
    [BTF_UBO2014_FMF06] = {BTF_UBO2014_FMF, "!FMF06FC", 0},
    [BTF_UBO2014_PVF] = {BTF_UBO2014_PVF, "!PVF06FCR", 0},
    [BTF_UBO2014_PVF06] = {BTF_UBO2014_PVF, "!PVF06FC", 0},
};
#define N_VARIANTS ((int)(sizeof VARIANTS / sizeof VARIANTS[0]))

static btf_status check_opts(const char *path, const btf_ubo2014_write_opts *o, btf_error *err)
{
    if (o->variant < 0 || o->variant >= N_VARIANTS)
        return btf__fail(err, BTF_E_ARG, "%s: variant %d: expected 0 (DFMF) to %d (PVF06)", path,
                         o->variant, N_VARIANTS - 1);
    if (o->components < 1)
        return btf__fail(err, BTF_E_ARG, "%s: %d components: expected at least 1", path,
                         o->components);
    if (o->variant != BTF_UBO2014_BDIF && o->scalar_size != 2 && o->scalar_size != 4)
        return btf__fail(err, BTF_E_ARG, "%s: scalar size %d: expected 2 (half) or 4 (float)",
                         path, o->scalar_size);
    return BTF_OK;
}

btf_status btf_ubo2014_write(const char *path, const btf_dirset *views, const btf_dirset *lights,
                             int width, int height, btf_pair_image_fn image, void *user,
                             const btf_ubo2014_write_opts *opts, btf_ubo2014_write_stats *stats,
                             btf_error *err)
{
    btf_ubo2014_write_opts d = btf_ubo2014_write_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_ubo2014_write", err))
        return BTF_E_ARG;
    if (o.components == 0)
        o.components = d.components;
    if (o.scalar_size == 0)
        o.scalar_size = d.scalar_size;
    if (o.max_bytes == 0)
        o.max_bytes = d.max_bytes;
    if (stats)
        memset(stats, 0, sizeof *stats);
    btf_status rc = ubo_check_sets(path, views, lights, width, height, err);
    if (rc == BTF_OK)
        rc = check_opts(path, &o, err);
    if (rc == BTF_OK && !image)
        rc = btf__fail(err, BTF_E_ARG, "%s: no image callback", path);
    if (rc)
        return rc;
    ubo_source src = {path, views, lights, width, height, image, user, o.progress,
                      o.progress_user};
    int body = VARIANTS[o.variant].body;
    const char *sig = VARIANTS[o.variant].sig;
    if (body == BTF_UBO2014_BDIF)
        rc = write_bdif(&src, stats, err);
    else if (body == BTF_UBO2014_DFMF)
        rc = write_dfmf(&src, &o, stats, err);
    else if (body == BTF_UBO2014_FMF)
        rc = write_fmf_images(&src, &o, sig, VARIANTS[o.variant].log_values, stats, err);
    else
        rc = ubo_write_pvf_images(&src, sig, o.components, o.scalar_size, o.max_bytes, stats, err);
    if (rc == BTF_OK && stats) {
        struct stat st; /* the size only: nothing to open */
        if (stat(path, &st) == 0)
            stats->bytes = (uint64_t)st.st_size;
    }
    if (rc == BTF_OK)
        ubo_report(&src, 1.0, "written");
    return rc;
}
