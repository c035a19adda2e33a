/*
 * model_maps.c — the sections of MODEL.btfcar that hold a value per texel
 * (docs/model-format.md): the range map of paper section II.B (RANG:
 * heights on a canonical 16-bit grid, predicted and zigzag-coded, as two
 * byte planes; the grid and the prediction are model/range_code.c's) and
 * the structure layer (STRC, version 1.4; flags and colour layer 1.5:
 * albedo and colour codes on a log2 grid, predicted from their left and
 * upper neighbours). Both are lossless on what the analysis keeps, so a
 * decoded model re-encodes to the same bytes.
 */
#include "model/model_file.h"
#include "model/range_code.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define RANG_PERIODIC 0x01u /* RANG flags bit 0 (1.1): the tile is periodic */
#define STRC_SHADOWS 0x01u  /* STRC flags bit 0 (1.5): the shading casts shadows */
#define STRC_CHROMA 0x02u   /* STRC flags bit 1 (1.5): the colour layer follows */

/* RANG and STRC begin alike: the map's u16 width and height, then an f32
 * (RANG's texel, STRC's ambient term). */
typedef struct map_head {
    int w, h;
    float value;
} map_head;

static map_head read_map_head(btf_box_reader *r)
{
    map_head mh;
    mh.w = (int)btf__box_read_u16(r);
    mh.h = (int)btf__box_read_u16(r);
    mh.value = btf__box_read_f32(r);
    return mh;
}

/* ------------------------------------------------------------ range map */

/* Quantises the heights on their canonical grid and writes the predictor
 * residuals as two byte planes (low bytes, then high bytes): the high plane
 * of a smooth surface is nearly all zeros. */
btf_status btf__model_put_range(btf_box_writer *w, const btf_model *m, const char *name,
                                btf_error *err)
{
    size_t n = (size_t)m->range_width * m->range_height;
    float lo, hi;
    btf__range_extremes(m->range, n, &lo, &hi);
    int e;
    int32_t k;
    if (btf__range_grid_choose(lo, hi, &e, &k) != 0)
        return failf(err, BTF_E_DATA, name,
                     "range map: heights %g..%g span too much for 16-bit quantisation "
                     "(expected magnitudes below about 1e33)", lo, hi);
    uint16_t *q = btf__model_alloc(n, sizeof *q, 0, name, err);
    unsigned char *planes = btf__model_alloc(n, 2, 0, name, err);
    if (!q || !planes) {
        free(q);
        free(planes);
        return BTF_E_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
        q[i] = (uint16_t)(floor(ldexp(m->range[i], -e)) - k);
    int rw = m->range_width;
    for (size_t i = 0; i < n; i++) {
        unsigned z = btf__range_zigzag(q[i], btf__range_predict(q, rw, (int)(i % (size_t)rw),
                                                                (int)(i / (size_t)rw)));
        planes[i] = (unsigned char)z;
        planes[n + i] = (unsigned char)(z >> 8);
    }
    size_t body = btf__box_section_begin(w, btf__model_tags[S_RANG]);
    btf__box_part(w, BTF_MODEL_PART_RANGE);
    btf__box_put_u16(w, (unsigned)m->range_width);
    btf__box_put_u16(w, (unsigned)m->range_height);
    btf__box_put_f32(w, m->range_texel);
    btf__box_put_u16(w, (unsigned)e & 0xFFFFu);
    btf__box_put_u32(w, (uint32_t)k);
    btf__box_put_bytes(w, planes, 2 * n);
    /* The tile in memory is periodic (analysis and the reader make it so;
     * docs/model-format.md, version 1.1). */
    btf__box_put_u8(w, RANG_PERIODIC);
    btf__box_section_end(w, body);
    free(q);
    free(planes);
    return BTF_OK;
}

/* The heights of the planes' codes on grid (e, k); the grid must hold
 * them within 24 bits. *lo, *hi their span. */
static btf_status range_heights(const unsigned char *planes, int w, int h, int e, int32_t k,
                                btf_model *m, float *lo, float *hi, const char *name,
                                btf_error *err)
{
    size_t n = (size_t)w * h;
    uint16_t *q = btf__model_alloc(n, sizeof *q, 0, name, err);
    if (!q)
        return BTF_E_NOMEM;
    unsigned qmax = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned z = planes[i] | (unsigned)planes[n + i] << 8;
        q[i] = (uint16_t)btf__range_unzigzag(
            z, btf__range_predict(q, w, (int)(i % (size_t)w), (int)(i / (size_t)w)));
        qmax = q[i] > qmax ? q[i] : qmax;
    }
    if ((double)k + qmax + 1.0 > BTF_RANGE_GRID_K_LIMIT) {
        free(q);
        return failf(err, BTF_E_FORMAT, name,
                     "range map: offset %ld + height %u exceeds 2^23 (expected a 24-bit grid)",
                     (long)k, qmax);
    }
    m->range = btf__model_alloc(n, sizeof *m->range, 0, name, err);
    if (!m->range) {
        free(q);
        return BTF_E_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        m->range[i] = btf__range_grid_value(e, k, q[i]);
        *lo = (i == 0 || m->range[i] < *lo) ? m->range[i] : *lo;
        *hi = (i == 0 || m->range[i] > *hi) ? m->range[i] : *hi;
    }
    free(q);
    return BTF_OK;
}

/* Rebuilds the heights from the predictor residuals and checks that the
 * grid is in range and canonical (what the encoder picks for them), so that
 * a decoded model re-encodes to the same bytes. */
btf_status btf__model_read_range(const btf_box_span *sp, btf_model *m, const char *name,
                                 btf_error *err)
{
    btf_box_reader r = {sp->p, sp->n, 0, 0};
    map_head mh = read_map_head(&r);
    int w = mh.w, h = mh.h, e = btf__box_read_i16(&r);
    int32_t k = btf__box_read_i32(&r);
    if (r.short_read)
        return btf__model_short(S_RANG, name, err);
    if (w < 1 || h < 1 || (long)w * h > BTF_MODEL_MAX_RANGE_SAMPLES)
        return failf(err, BTF_E_FORMAT, name,
                     "range map: size %d x %d (expected 1..%d on each side, at most %ld samples)",
                     w, h, BTF_MODEL_MAX_RANGE_SIDE, BTF_MODEL_MAX_RANGE_SAMPLES);
    const unsigned char *planes = btf__box_take(&r, 2 * (size_t)w * h);
    if (!planes)
        return btf__model_short(S_RANG, name, err);
    /* Version 1.1's flags; a 1.0 section ends before them. Bits other than
     * bit 0 are reserved (written 0, ignored). */
    int periodic = r.pos < r.n && (r.p[r.pos] & RANG_PERIODIC);
    if (e < BTF_RANGE_GRID_E_MIN || e > BTF_RANGE_GRID_E_MAX || k < -BTF_RANGE_GRID_K_LIMIT ||
        k >= BTF_RANGE_GRID_K_LIMIT)
        return failf(err, BTF_E_FORMAT, name,
                     "range map: grid 2^%d, offset %ld (expected exponent %d..%d, offset "
                     "-2^23..2^23-1)",
                     e, (long)k, BTF_RANGE_GRID_E_MIN, BTF_RANGE_GRID_E_MAX);
    float lo = 0, hi = 0;
    btf_status rc = range_heights(planes, w, h, e, k, m, &lo, &hi, name, err);
    if (rc)
        return rc;
    m->range_width = w;
    m->range_height = h;
    m->range_texel = mh.value;
    int ce;
    int32_t ck;
    if (btf__range_grid_choose(lo, hi, &ce, &ck) != 0 || ce != e || ck != k)
        return failf(err, BTF_E_FORMAT, name,
                     "range map: grid 2^%d, offset %ld is not canonical for heights %g..%g "
                     "(expected 2^%d, offset %ld)", e, (long)k, lo, hi, ce, (long)ck);
    /* A tile not marked periodic (format 1.0) is converted now, as the
     * analysis of today would have stored it. */
    btf_error pe = {0};
    if (!periodic && btf_range_make_periodic(m->range, w, h, &pe) != BTF_OK)
        return failf(err, pe.code == BTF_E_NOMEM ? BTF_E_NOMEM : BTF_E_FORMAT, name,
                     "range map of format 1.0 not made periodic: %s (expected a DFT of %d x %d "
                     "to succeed)", pe.msg, w, h);
    return BTF_OK;
}

/* ------------------------------------------------------ structure layer */

/* The prediction of albedo code (x, y) from its left and upper neighbours
 * (their mean; the left one on the first row, the upper on the first
 * column): the pattern's flat cells leave residuals near 0. */
static unsigned albedo_predict(const unsigned char *q, int w, int x, int y)
{
    if (y == 0)
        return x == 0 ? 128u : q[x - 1];
    const unsigned char *row = q + (size_t)y * w;
    return x == 0 ? row[x - w] : (row[x - 1] + row[x - w] + 1u) / 2u;
}

/* One plane of n values v[0], v[stride], ... as codes q and their
 * residuals res from the prediction, modulo 256. */
static void encode_plane(const float *v, size_t stride, size_t n, int w, unsigned char *q,
                         unsigned char *res)
{
    for (size_t i = 0; i < n; i++)
        q[i] = (unsigned char)btf__albedo_code(v[i * stride]);
    for (size_t i = 0; i < n; i++)
        res[i] = (unsigned char)(q[i] - albedo_predict(q, w, (int)(i % (size_t)w),
                                                       (int)(i / (size_t)w)));
}

/* The inverse: codes q rebuilt from the residuals, values into v[i stride]. */
static void decode_plane(const unsigned char *res, size_t n, int w, unsigned char *q, float *v,
                         size_t stride)
{
    for (size_t i = 0; i < n; i++) {
        q[i] = (unsigned char)(res[i] + albedo_predict(q, w, (int)(i % (size_t)w),
                                                       (int)(i / (size_t)w)));
        v[i * stride] = btf__albedo_value(q[i]);
    }
}

/* STRC: width, height (the range map's), the ambient term, then one byte
 * per texel: the albedo code minus its prediction, modulo 256; since 1.5
 * a flags byte when a bit is set, then with the colour layer its three
 * planes coded alike. */
btf_status btf__model_put_structure(btf_box_writer *w, const btf_model *m, const char *name,
                                    btf_error *err)
{
    int rw = m->range_width, rh = m->range_height;
    size_t n = (size_t)rw * rh;
    unsigned char *q = btf__model_alloc(n, 2, 0, name, err);
    if (!q)
        return BTF_E_NOMEM;
    unsigned char *res = q + n;
    encode_plane(m->albedo, 1, n, rw, q, res);
    size_t body = btf__box_section_begin(w, btf__model_tags[S_STRC]);
    btf__box_part(w, BTF_MODEL_PART_STRUCTURE);
    btf__box_put_u16(w, (unsigned)rw);
    btf__box_put_u16(w, (unsigned)rh);
    btf__box_put_f32(w, m->ambient);
    btf__box_put_bytes(w, res, n);
    if (m->shadows || m->chroma) /* 1.5: a flags byte after the codes */
        btf__box_put_u8(w, (m->shadows ? STRC_SHADOWS : 0u) | (m->chroma ? STRC_CHROMA : 0u));
    for (int c = 0; m->chroma && c < 3; c++) { /* then each channel's codes, predicted */
        encode_plane(m->chroma + c, 3, n, rw, q, res);
        btf__box_put_bytes(w, res, n);
    }
    btf__box_section_end(w, body);
    free(q);
    return BTF_OK;
}

/* 1.5: the flags byte, then exactly the colour planes its bit 1 asks for
 * (docs/model-format.md, "STRC": stricter than the rule for a section's
 * end). q: the n-byte scratch of the codes. */
static btf_status read_structure_flags(btf_box_reader *r, btf_model *m, size_t n, int w,
                                       unsigned char *q, const char *name, btf_error *err)
{
    unsigned flags = btf__box_read_u8(r);
    size_t want = flags & STRC_CHROMA ? 3 * n : 0;
    if ((flags & ~(STRC_SHADOWS | STRC_CHROMA)) || r->n - r->pos != want)
        return failf(err, BTF_E_FORMAT, name, "section STRC: flags 0x%02x and %zu more "
                     "bytes (expected bits 0-1 and %zu)", flags, r->n - r->pos, want);
    m->shadows = (flags & STRC_SHADOWS) != 0;
    if (want && !(m->chroma = btf__model_alloc(3 * n, sizeof(float), 0, name, err)))
        return BTF_E_NOMEM;
    for (int c = 0; want && c < 3; c++)
        decode_plane(btf__box_take(r, n), n, w, q, m->chroma + c, 3);
    return BTF_OK;
}

/* The albedo codes rebuilt from their residuals; the layer needs a range
 * map of the same size at texel 1 (checked by btf__model_validate). */
btf_status btf__model_read_structure(const btf_box_span *sp, btf_model *m, const char *name,
                                     btf_error *err)
{
    btf_box_reader r = {sp->p, sp->n, 0, 0};
    map_head mh = read_map_head(&r);
    int w = mh.w, h = mh.h;
    if (r.short_read)
        return btf__model_short(S_STRC, name, err);
    if (!m->range || w != m->range_width || h != m->range_height)
        return failf(err, BTF_E_FORMAT, name,
                     "section STRC: %d x %d (expected the range map's size, %d x %d)", w, h,
                     m->range_width, m->range_height);
    size_t n = (size_t)w * h;
    const unsigned char *res = btf__box_take(&r, n);
    if (!res)
        return btf__model_short(S_STRC, name, err);
    unsigned char *q = btf__model_alloc(n, 1, 0, name, err);
    m->albedo = q ? btf__model_alloc(n, sizeof(float), 0, name, err) : NULL;
    if (!m->albedo) {
        free(q);
        return BTF_E_NOMEM;
    }
    decode_plane(res, n, w, q, m->albedo, 1);
    m->ambient = mh.value;
    btf_status rc = BTF_OK;
    if (r.pos < r.n)
        rc = read_structure_flags(&r, m, n, w, q, name, err);
    free(q);
    return rc;
}
