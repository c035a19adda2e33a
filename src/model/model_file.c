/*
 * model_file.c — the model file MODEL.btfcar: everything synthesis and
 * rendering need (direction sets, index table, per-subspace spectral basis
 * and CAR parameters of paper section II.C, the range-map tile of section
 * II.B) in a few kilobytes. The layout, the limits and the range-map
 * quantisation are specified in docs/model-format.md; this file is its
 * reference implementation: encoding and decoding in memory, and the file
 * forms as thin wrappers (an atomic write, a whole-file read). The range
 * map's grid and prediction coding are model/model_range.c's.
 *
 * The validator (model/model_check.c) serves both directions: the encoder
 * refuses any model the decoder would reject, so whatever btfcar writes it
 * can read, and the decoder trusts nothing it has not checked. Decoding is
 * designed for hostile input (it runs under libFuzzer, tests/fuzz_model.c):
 * every count is bounded before it sizes an allocation, every read is
 * bounds-checked, and a failure frees whatever was built.
 */
#include "car/car.h"
#include "model/model.h"
#include "synth/synth.h"
#include "model/range_code.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ------------------------------------------------------------ constants */

/* PNG-style signature: the high byte catches 7-bit channels, CR LF and the
 * lone LF catch line-ending conversion, ^Z stops DOS `type`. */
#define SIG_LEN 11
#define SIG_STEM 7 /* "\x89BTFCAR": what survives a text-mode transfer */
static const unsigned char SIGNATURE[SIG_LEN] = {0x89, 'B', 'T', 'F', 'C', 'A',
                                                 'R',  '\r', '\n', 0x1a, '\n'};

#define FMT_MAJOR 1
/* 1.1 added the RANG flags (the tile is periodic); a model without a range
 * map is still written as 1.0, the lowest version that holds it. */
#define FMT_MINOR_RANGE_FLAGS 1
/* 1.2 added the MARG section (marginal transfers); a model without one is
 * written as 1.1 or 1.0. */
#define FMT_MINOR_MARGINALS 2
/* 1.3 added the LABQ section (the exemplars' CIE Lab histograms, for
 * colour matching); a model without one is written as 1.2 or older. */
#define FMT_MINOR_LAB 3
/* 1.4 added the STRC section (the structure layer: the albedo pattern and
 * the shading's ambient term; the CAR fields then model the remainder); a
 * model without one is written as 1.3 or older. */
#define FMT_MINOR_STRUCTURE 4
/* 1.5 added the GAIN section (the pair gains) and STRC's flags byte (the
 * shading casts shadows; the colour layer follows); a model without either is written as 1.4 or
 * older. */
#define FMT_MINOR_GAINS 5
/* 1.6 lets INDX hold 255 (BTF_PAIR_NONE): a pair a sparse set did not
 * measure. Only such a model is written as 1.6; an older reader refuses
 * it (an index beyond the subspaces), never misreads it. */
#define FMT_MINOR_SPARSE 6
#define HEADER_BYTES 26 /* signature .. stored size, version 1.0 */
#define RANG_PERIODIC 0x01u /* RANG flags bit 0: the tile is periodic */
#define STRC_SHADOWS 0x01u  /* STRC flags bit 0 (1.5): the shading casts shadows */
#define STRC_CHROMA 0x02u   /* STRC flags bit 1 (1.5): the colour layer follows */
#define CRC_BYTES 4
#define COMP_STORED 0
#define COMP_ZLIB 1
/* deflate cannot expand by more than ~1032:1; a larger claimed payload is a
 * lie that would only cost us an allocation. */
#define ZLIB_MAX_RATIO 1032u

#define MAX_FILE_BYTES ((size_t)64 << 20)
#define MAX_PAYLOAD_BYTES ((size_t)64 << 20)

enum { S_VIEW, S_LGHT, S_INDX, S_SUBS, S_RANG, S_MARG, S_LABQ, S_STRC, S_GAIN, S_COUNT };
static const char TAGS[S_COUNT][5] = {"VIEW", "LGHT", "INDX", "SUBS", "RANG", "MARG", "LABQ",
                                      "STRC", "GAIN"};

/* ------------------------------------------------------------- messages */

/* Every message names the file or buffer (model/model_check.c). */
#define failf btf_model_fail

/* Allocation whose failure message names the file, like every other. */
static void *alloc_named(size_t count, size_t size, int zero, const char *name, btf_error *err)
{
    void *p = zero ? btf_calloc(count, size, NULL) : btf_alloc(count, size, NULL);
    if (!p)
        failf(err, BTF_E_NOMEM, name, "out of memory allocating %zu x %zu bytes", count,
              size);
    return p;
}

/* ------------------------------------------------- little-endian writer */

typedef struct wbuf {
    unsigned char *p;
    size_t n, cap;
    int failed; /* sticky: an allocation failed */
    /* With `labelled`, lab[i] is the btf_model_part of byte i (the current
     * `part` when it was written), for the report's accounting
     * (btf_model_encode_parts); lab has the same capacity as p. */
    int labelled;
    unsigned char part;
    unsigned char *lab;
} wbuf;

/* What the following bytes hold (btf_model_part, include/btfcar.h). */
static void w_part(wbuf *b, btf_model_part part)
{
    b->part = (unsigned char)part;
}

static void w_bytes(wbuf *b, const void *src, size_t n)
{
    if (b->failed)
        return;
    if (b->cap - b->n < n) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap - b->n < n)
            cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (p)
            b->p = p;
        unsigned char *lab = p && b->labelled ? realloc(b->lab, cap) : NULL;
        if (lab)
            b->lab = lab;
        if (!p || (b->labelled && !lab)) {
            b->failed = 1;
            return;
        }
        b->cap = cap;
    }
    memcpy(b->p + b->n, src, n);
    if (b->labelled)
        memset(b->lab + b->n, b->part, n);
    b->n += n;
}

static void w_u8(wbuf *b, unsigned v)
{
    unsigned char c = (unsigned char)v;
    w_bytes(b, &c, 1);
}

static void w_u16(wbuf *b, unsigned v)
{
    unsigned char c[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    w_bytes(b, c, 2);
}

static void put_u32(unsigned char *c, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        c[i] = (unsigned char)(v >> (8 * i));
}

static void w_u32(wbuf *b, uint32_t v)
{
    unsigned char c[4];
    put_u32(c, v);
    w_bytes(b, c, 4);
}

static void w_f32(wbuf *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    w_u32(b, v);
}

static void w_f64(wbuf *b, double f)
{
    uint64_t v;
    memcpy(&v, &f, 8);
    w_u32(b, (uint32_t)v);
    w_u32(b, (uint32_t)(v >> 32));
}

/* A section is its tag, a u32 length and the body; the length is patched in
 * when the body is complete. */
static size_t w_section_begin(wbuf *b, int tag)
{
    w_part(b, BTF_MODEL_PART_FRAMING);
    w_bytes(b, TAGS[tag], 4);
    w_u32(b, 0);
    return b->n;
}

static void w_section_end(wbuf *b, size_t body)
{
    if (!b->failed)
        put_u32(b->p + body - 4, (uint32_t)(b->n - body));
}

/* ------------------------------------------------- little-endian reader */

typedef struct rbuf {
    const unsigned char *p;
    size_t n, pos;
    int short_read; /* sticky: a read ran past the end (values read as 0) */
} rbuf;

static const unsigned char *r_take(rbuf *r, size_t k)
{
    if (r->short_read || r->n - r->pos < k) {
        r->short_read = 1;
        return NULL;
    }
    const unsigned char *p = r->p + r->pos;
    r->pos += k;
    return p;
}

static unsigned get_u16(const unsigned char *c)
{
    return (unsigned)c[0] | (unsigned)c[1] << 8;
}

static uint32_t get_u32(const unsigned char *c)
{
    return (uint32_t)c[0] | (uint32_t)c[1] << 8 | (uint32_t)c[2] << 16 | (uint32_t)c[3] << 24;
}

static unsigned r_u8(rbuf *r)
{
    const unsigned char *c = r_take(r, 1);
    return c ? c[0] : 0;
}

static unsigned r_u16(rbuf *r)
{
    const unsigned char *c = r_take(r, 2);
    return c ? get_u16(c) : 0;
}

static int r_i16(rbuf *r)
{
    unsigned v = r_u16(r);
    return v >= 0x8000u ? (int)v - 0x10000 : (int)v;
}

static uint32_t r_u32(rbuf *r)
{
    const unsigned char *c = r_take(r, 4);
    return c ? get_u32(c) : 0;
}

static int32_t r_i32(rbuf *r)
{
    uint32_t v = r_u32(r);
    return v >= 0x80000000u ? (int32_t)(v - 0x80000000u) - INT32_MAX - 1 : (int32_t)v;
}

static float r_f32(rbuf *r)
{
    uint32_t v = r_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

static double r_f64(rbuf *r)
{
    uint64_t lo = r_u32(r), hi = r_u32(r);
    uint64_t v = lo | hi << 32;
    double f;
    memcpy(&f, &v, 8);
    return f;
}

/* -------------------------------------------------------------- encoding */

static void put_dirset(wbuf *b, int tag, const btf_dirset *s)
{
    size_t body = w_section_begin(b, tag);
    w_part(b, BTF_MODEL_PART_DIRECTIONS);
    size_t len = strlen(s->name);
    w_u8(b, (unsigned)len);
    w_bytes(b, s->name, len);
    w_u16(b, (unsigned)s->count);
    for (int i = 0; i < s->count; i++) {
        w_f64(b, s->dirs[i].theta);
        w_f64(b, s->dirs[i].phi);
    }
    w_section_end(b, body);
}

static void put_band(wbuf *b, const btf_car_band *c)
{
    w_part(b, BTF_MODEL_PART_NEIGHBOURHOODS);
    w_u8(b, (unsigned)c->n);
    for (int i = 0; i < c->n; i++) {
        w_u8(b, (unsigned)(uint8_t)c->offsets[i].row);
        w_u8(b, (unsigned)(uint8_t)c->offsets[i].col);
    }
    w_part(b, BTF_MODEL_PART_GAMMAS);
    for (int i = 0; i < c->n; i++)
        w_f32(b, c->gamma[i]);
    w_part(b, BTF_MODEL_PART_SIGMAS);
    w_f32(b, c->sigma);
    w_part(b, BTF_MODEL_PART_BAND_MEANS);
    w_f32(b, c->mean);
}

static void put_subspaces(wbuf *b, const btf_model *m)
{
    size_t body = w_section_begin(b, S_SUBS);
    w_u16(b, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_subspace_model *sm = &m->subspaces[s];
        w_part(b, BTF_MODEL_PART_FRAMING);
        w_u16(b, (unsigned)sm->view & 0xFFFFu);
        w_u16(b, (unsigned)sm->light & 0xFFFFu);
        w_u32(b, (uint32_t)sm->width);
        w_u32(b, (uint32_t)sm->height);
        w_part(b, BTF_MODEL_PART_SPECTRAL);
        for (int c = 0; c < 3; c++)
            w_f32(b, sm->mean[c]);
        for (int i = 0; i < 9; i++)
            w_f32(b, sm->basis[i]);
        w_part(b, BTF_MODEL_PART_LEVELS);
        w_u8(b, (unsigned)sm->levels);
        for (int band = 0; band < 3; band++)
            for (int l = 0; l < sm->levels; l++)
                put_band(b, &sm->bands[band][l]);
    }
    w_section_end(b, body);
}

static int has_marginals(const btf_model *m)
{
    for (int s = 0; s < m->n_subspaces; s++)
        if (m->subspaces[s].marginal.knots)
            return 1;
    return 0;
}

/* MARG (version 1.2): per subspace a u8 knot count, 0 or 32; with 32, per
 * band its synthesised mean and sd and 32 quantiles, then the RGB box. */
static void put_marginals(wbuf *b, const btf_model *m)
{
    size_t body = w_section_begin(b, S_MARG);
    w_u16(b, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_marginal *mg = &m->subspaces[s].marginal;
        w_part(b, BTF_MODEL_PART_MARGINALS);
        w_u8(b, (unsigned)mg->knots);
        if (!mg->knots)
            continue;
        for (int band = 0; band < 3; band++) {
            w_f32(b, mg->synth_mean[band]);
            w_f32(b, mg->synth_sd[band]);
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                w_f32(b, mg->quantile[band][j]);
        }
        for (int k = 0; k < 3; k++)
            w_f32(b, mg->rgb_lo[k]);
        for (int k = 0; k < 3; k++)
            w_f32(b, mg->rgb_hi[k]);
    }
    w_section_end(b, body);
}

/* Whether the index table marks a pair not measured (format 1.6). */
static int has_unmeasured(const btf_model *m)
{
    size_t n = m->index ? (size_t)m->views.count * (size_t)m->lights.count : 0;
    for (size_t i = 0; i < n; i++)
        if (m->index[i] == BTF_PAIR_NONE)
            return 1;
    return 0;
}

static int has_lab(const btf_model *m)
{
    for (int s = 0; s < m->n_subspaces; s++)
        if (m->subspaces[s].marginal.knots && m->subspaces[s].marginal.lab_knots)
            return 1;
    return 0;
}

/* LABQ (version 1.3): per subspace a u8 knot count, 0 or 32 (0 where MARG
 * has none); with 32, per channel L*, a*, b* its 32 quantiles as u16 codes
 * over [0, 100] and [-128, 128] (synth/colour_lab.c). */
static void put_lab(wbuf *b, const btf_model *m)
{
    size_t body = w_section_begin(b, S_LABQ);
    w_u16(b, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_marginal *mg = &m->subspaces[s].marginal;
        int knots = mg->knots ? mg->lab_knots : 0;
        w_part(b, BTF_MODEL_PART_MARGINALS);
        w_u8(b, (unsigned)knots);
        for (int c = 0; knots && c < 3; c++)
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                w_u16(b, btf_lab_code(c, mg->lab_quantile[c][j]));
    }
    w_section_end(b, body);
}

/* Quantises the heights on their canonical grid and writes the predictor
 * residuals as two byte planes (low bytes, then high bytes): the high plane
 * of a smooth surface is nearly all zeros. */
static btf_status put_range(wbuf *b, const btf_model *m, const char *name, btf_error *err)
{
    size_t n = (size_t)m->range_width * m->range_height;
    float lo = m->range[0], hi = m->range[0];
    for (size_t i = 1; i < n; i++) {
        lo = m->range[i] < lo ? m->range[i] : lo;
        hi = m->range[i] > hi ? m->range[i] : hi;
    }
    int e;
    int32_t k;
    if (btf_range_grid_choose(lo, hi, &e, &k) != 0)
        return failf(err, BTF_E_DATA, name,
                     "range map: heights %g..%g span too much for 16-bit quantisation "
                     "(expected magnitudes below about 1e33)", lo, hi);
    uint16_t *q = alloc_named(n, sizeof *q, 0, name, err);
    unsigned char *planes = alloc_named(n, 2, 0, name, err);
    if (!q || !planes) {
        free(q);
        free(planes);
        return BTF_E_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
        q[i] = (uint16_t)(floor(ldexp(m->range[i], -e)) - k);
    int w = m->range_width;
    for (size_t i = 0; i < n; i++) {
        unsigned z = btf_range_zigzag(q[i], btf_range_predict(q, w, (int)(i % (size_t)w),
                                                              (int)(i / (size_t)w)));
        planes[i] = (unsigned char)z;
        planes[n + i] = (unsigned char)(z >> 8);
    }
    size_t body = w_section_begin(b, S_RANG);
    w_part(b, BTF_MODEL_PART_RANGE);
    w_u16(b, (unsigned)m->range_width);
    w_u16(b, (unsigned)m->range_height);
    w_f32(b, m->range_texel);
    w_u16(b, (unsigned)e & 0xFFFFu);
    w_u32(b, (uint32_t)k);
    w_bytes(b, planes, 2 * n);
    /* The tile in memory is periodic (analysis and the reader make it so;
     * docs/model-format.md, version 1.1). */
    w_u8(b, RANG_PERIODIC);
    w_section_end(b, body);
    free(q);
    free(planes);
    return BTF_OK;
}

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

/* STRC: width, height (the range map's), the ambient term, then one byte
 * per texel: the albedo code minus its prediction, modulo 256. */
static btf_status put_structure(wbuf *b, const btf_model *m, const char *name, btf_error *err)
{
    int w = m->range_width, h = m->range_height;
    size_t n = (size_t)w * h;
    unsigned char *q = alloc_named(n, 2, 0, name, err);
    if (!q)
        return BTF_E_NOMEM;
    unsigned char *res = q + n;
    for (size_t i = 0; i < n; i++)
        q[i] = (unsigned char)btf_albedo_code(m->albedo[i]);
    for (size_t i = 0; i < n; i++)
        res[i] = (unsigned char)(q[i] - albedo_predict(q, w, (int)(i % (size_t)w),
                                                       (int)(i / (size_t)w)));
    size_t body = w_section_begin(b, S_STRC);
    w_part(b, BTF_MODEL_PART_STRUCTURE);
    w_u16(b, (unsigned)w);
    w_u16(b, (unsigned)h);
    w_f32(b, m->ambient);
    w_bytes(b, res, n);
    if (m->shadows || m->chroma) /* 1.5: a flags byte after the codes */
        w_u8(b, (m->shadows ? STRC_SHADOWS : 0u) | (m->chroma ? STRC_CHROMA : 0u));
    for (int c = 0; m->chroma && c < 3; c++) { /* then each channel's codes, predicted */
        for (size_t i = 0; i < n; i++)
            q[i] = (unsigned char)btf_albedo_code(m->chroma[3 * i + c]);
        for (size_t i = 0; i < n; i++)
            res[i] = (unsigned char)(q[i] - albedo_predict(q, w, (int)(i % (size_t)w),
                                                           (int)(i / (size_t)w)));
        w_bytes(b, res, n);
    }
    w_section_end(b, body);
    free(q);
    return BTF_OK;
}

/* GAIN: per pair (views x lights, the index table's order) and channel
 * the gain's code (a signed byte, btf_gain_code) minus the previous
 * pair's code of that channel, modulo 256: neighbouring lights differ
 * little, so the residuals are near 0. */
static btf_status put_gains(wbuf *b, const btf_model *m, const char *name, btf_error *err)
{
    size_t n = (size_t)m->views.count * m->lights.count * 3;
    unsigned char *res = alloc_named(n, 1, 0, name, err);
    if (!res)
        return BTF_E_NOMEM;
    int prev[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        int q = btf_gain_code(m->gain[i]);
        res[i] = (unsigned char)((q - prev[i % 3]) & 0xff);
        prev[i % 3] = q;
    }
    size_t body = w_section_begin(b, S_GAIN);
    w_part(b, BTF_MODEL_PART_GAINS);
    w_bytes(b, res, n);
    w_section_end(b, body);
    free(res);
    return BTF_OK;
}

static btf_status build_payload(const btf_model *m, wbuf *b, const char *name, btf_error *err)
{
    if (m->views.count > 0) {
        put_dirset(b, S_VIEW, &m->views);
        put_dirset(b, S_LGHT, &m->lights);
        size_t body = w_section_begin(b, S_INDX);
        w_part(b, BTF_MODEL_PART_INDEX);
        w_bytes(b, m->index, (size_t)m->views.count * m->lights.count);
        w_section_end(b, body);
    }
    put_subspaces(b, m);
    if (m->range) {
        btf_status rc = put_range(b, m, name, err);
        if (rc)
            return rc;
    }
    if (has_marginals(m))
        put_marginals(b, m);
    if (has_lab(m))
        put_lab(b, m);
    if (m->albedo) {
        btf_status rc = put_structure(b, m, name, err);
        if (rc)
            return rc;
    }
    if (m->gain) {
        btf_status rc = put_gains(b, m, name, err);
        if (rc)
            return rc;
    }
    if (b->failed)
        return failf(err, BTF_E_NOMEM, name, "out of memory encoding the model");
    return BTF_OK;
}

/* Wraps the payload: header, deflated (or stored, when deflate does not
 * help) body, CRC-32 of everything before it. */
static btf_status wrap_payload(const wbuf *pl, unsigned minor, const char *name,
                               unsigned char **data, size_t *size, btf_error *err)
{
    uLongf zlen = compressBound((uLong)pl->n);
    unsigned char *out = alloc_named(HEADER_BYTES + (size_t)zlen + CRC_BYTES, 1, 0, name, err);
    if (!out)
        return BTF_E_NOMEM;
    unsigned comp = COMP_ZLIB;
    if (compress2(out + HEADER_BYTES, &zlen, pl->p, (uLong)pl->n, 9) != Z_OK ||
        zlen >= pl->n) {
        comp = COMP_STORED;
        zlen = (uLongf)pl->n;
        memcpy(out + HEADER_BYTES, pl->p, pl->n);
    }
    memcpy(out, SIGNATURE, SIG_LEN);
    out[11] = FMT_MAJOR, out[12] = 0;
    out[13] = (unsigned char)minor, out[14] = 0;
    out[15] = HEADER_BYTES, out[16] = 0;
    out[17] = (unsigned char)comp;
    put_u32(out + 18, (uint32_t)pl->n);
    put_u32(out + 22, (uint32_t)zlen);
    size_t body = HEADER_BYTES + (size_t)zlen;
    put_u32(out + body, (uint32_t)crc32(0L, out, (uInt)body));
    *data = out;
    *size = body + CRC_BYTES;
    return BTF_OK;
}

/* parts: NULL, or where the payload and its labels go (btf_model_encode_parts). */
static btf_status encode_named(const btf_model *m, const char *name, unsigned char **data,
                               size_t *size, btf_model_payload_parts *parts, btf_error *err)
{
    if (!data || !size)
        return failf(err, BTF_E_ARG, name, "no output buffer");
    *data = NULL;
    *size = 0;
    if (!m)
        return failf(err, BTF_E_ARG, name, "no model");
    btf_status rc = btf_model_validate(m, name, BTF_E_DATA, err);
    if (rc)
        return rc;
    wbuf pl = {0};
    pl.labelled = parts != NULL;
    rc = build_payload(m, &pl, name, err);
    if (rc == BTF_OK && pl.n > MAX_PAYLOAD_BYTES)
        rc = failf(err, BTF_E_DATA, name, "model of %zu bytes (expected at most %zu)", pl.n,
                   MAX_PAYLOAD_BYTES);
    if (rc == BTF_OK)
        rc = wrap_payload(&pl, has_unmeasured(m)                  ? FMT_MINOR_SPARSE
                               : m->gain || m->shadows || m->chroma ? FMT_MINOR_GAINS
                               : m->albedo        ? FMT_MINOR_STRUCTURE
                               : has_lab(m)       ? FMT_MINOR_LAB
                               : has_marginals(m) ? FMT_MINOR_MARGINALS
                               : m->range       ? FMT_MINOR_RANGE_FLAGS
                                                : 0,
                          name, data, size, err);
    if (rc == BTF_OK && parts) {
        parts->payload = pl.p;
        parts->part = pl.lab;
        parts->n = pl.n;
        return BTF_OK;
    }
    free(pl.p);
    free(pl.lab);
    return rc;
}

btf_status btf_model_encode(const btf_model *m, unsigned char **data, size_t *size, btf_error *err)
{
    return encode_named(m, "model", data, size, NULL, err);
}

btf_status btf_model_encode_parts(const btf_model *m, unsigned char **data, size_t *size,
                                  btf_model_payload_parts *parts, btf_error *err)
{
    if (!parts)
        return failf(err, BTF_E_ARG, "model", "no payload parts to fill");
    memset(parts, 0, sizeof *parts);
    return encode_named(m, "model", data, size, parts, err);
}

btf_status btf_model_write(const char *path, const btf_model *m, btf_error *err)
{
    if (!path)
        return btf_fail(err, BTF_E_ARG, "model: no path to write to");
    unsigned char *data;
    size_t size;
    btf_status rc = encode_named(m, path, &data, &size, NULL, err);
    if (rc)
        return rc;
    rc = btf_write_file_atomic(path, data, size, err);
    free(data);
    return rc;
}

/* -------------------------------------------------------------- decoding */

/* The signature comes first: a foreign file, a truncated one and one mangled
 * by a text-mode transfer each get their own message. */
static btf_status check_signature(const unsigned char *data, size_t size, const char *name,
                                  btf_error *err)
{
    size_t k = size < SIG_LEN ? size : SIG_LEN;
    if (memcmp(data, SIGNATURE, k) == 0) /* a prefix of the signature, or all of it */
        return size < SIG_LEN ? failf(err, BTF_E_FORMAT, name,
                                      "truncated: %zu bytes (expected at least %d)", size,
                                      HEADER_BYTES + CRC_BYTES)
                              : BTF_OK;
    if (size >= SIG_STEM && memcmp(data, SIGNATURE, SIG_STEM) == 0)
        return failf(err, BTF_E_FORMAT, name,
                     "damaged signature, line endings converted by a text-mode transfer? "
                     "(expected bytes 89 42 54 46 43 41 52 0D 0A 1A 0A)");
    return failf(err, BTF_E_FORMAT, name,
                 "not a btfcar model (expected the signature \\x89BTFCAR\\r\\n\\x1a\\n)");
}

static btf_status check_version(const unsigned char *data, size_t size, const char *name,
                                btf_error *err)
{
    if (size < SIG_LEN + 4)
        return failf(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)", size,
                     HEADER_BYTES + CRC_BYTES);
    unsigned major = get_u16(data + 11), minor = get_u16(data + 13);
    if (major > FMT_MAJOR)
        return failf(err, BTF_E_FORMAT, name,
                     "format version %u.%u is newer than this reader (expected major version %d; "
                     "a newer btfcar reads it)", major, minor, FMT_MAJOR);
    if (major != FMT_MAJOR)
        return failf(err, BTF_E_FORMAT, name, "format version %u.%u (expected major version %d)",
                     major, minor, FMT_MAJOR);
    return BTF_OK;
}

static btf_status inflate_payload(const unsigned char *src, size_t n, size_t out_n,
                                  const char *name, unsigned char **out, btf_error *err)
{
    if ((uint64_t)out_n > (uint64_t)n * ZLIB_MAX_RATIO + 64)
        return failf(err, BTF_E_FORMAT, name,
                     "payload of %zu bytes from %zu compressed (expected at most %u:1)", out_n, n,
                     ZLIB_MAX_RATIO);
    unsigned char *p = alloc_named(out_n ? out_n : 1, 1, 0, name, err);
    if (!p)
        return BTF_E_NOMEM;
    uLongf got = (uLongf)out_n;
    uLong used = (uLong)n;
    int zr = uncompress2(p, &got, src, &used);
    if (zr != Z_OK || got != out_n || used != n) {
        free(p);
        if (zr == Z_MEM_ERROR)
            return failf(err, BTF_E_NOMEM, name, "out of memory inflating the payload");
        return failf(err, BTF_E_FORMAT, name,
                     "corrupt compressed payload (expected a zlib stream of %zu bytes giving %zu)",
                     n, out_n);
    }
    *out = p;
    return BTF_OK;
}

/* Checks the container (signature, version, sizes, CRC, compression) and
 * hands back the payload: a pointer into data when stored, an inflated copy
 * in *owned when deflated. */
static btf_status open_container(const unsigned char *data, size_t size, const char *name,
                                 const unsigned char **payload, size_t *payload_n,
                                 unsigned char **owned, btf_error *err)
{
    btf_status rc;
    if ((rc = check_signature(data, size, name, err)) || (rc = check_version(data, size, name, err)))
        return rc;
    if (size > MAX_FILE_BYTES)
        return failf(err, BTF_E_FORMAT, name, "%zu bytes (expected at most %zu)", size,
                     MAX_FILE_BYTES);
    if (size < HEADER_BYTES + CRC_BYTES)
        return failf(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)", size,
                     HEADER_BYTES + CRC_BYTES);
    size_t hdr = get_u16(data + 15);
    unsigned comp = data[17];
    size_t raw_n = get_u32(data + 18), stored_n = get_u32(data + 22);
    if (hdr < HEADER_BYTES)
        return failf(err, BTF_E_FORMAT, name, "header of %zu bytes (expected at least %d)", hdr,
                     HEADER_BYTES);
    /* 64-bit sums of 32-bit terms: no overflow even where size_t is 32-bit. */
    uint64_t total = (uint64_t)hdr + stored_n + CRC_BYTES;
    if ((uint64_t)size < total)
        return failf(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected %llu)", size,
                     (unsigned long long)total);
    if ((uint64_t)size > total)
        return failf(err, BTF_E_FORMAT, name,
                     "%llu bytes after the end (expected %llu bytes in all)",
                     (unsigned long long)(size - total), (unsigned long long)total);
    uint32_t want = get_u32(data + size - CRC_BYTES);
    uint32_t got = (uint32_t)crc32(0L, data, (uInt)(size - CRC_BYTES));
    if (want != got)
        return failf(err, BTF_E_FORMAT, name,
                     "CRC-32 mismatch, the file is corrupt (expected %08x, computed %08x)",
                     (unsigned)want, (unsigned)got);
    if (raw_n > MAX_PAYLOAD_BYTES)
        return failf(err, BTF_E_FORMAT, name, "payload of %zu bytes (expected at most %zu)", raw_n,
                     MAX_PAYLOAD_BYTES);
    if (comp == COMP_STORED) {
        if (raw_n != stored_n)
            return failf(err, BTF_E_FORMAT, name,
                         "stored payload of %zu bytes declared as %zu (expected equal sizes)",
                         stored_n, raw_n);
        *payload = data + hdr;
        *payload_n = raw_n;
        return BTF_OK;
    }
    if (comp != COMP_ZLIB)
        return failf(err, BTF_E_FORMAT, name,
                     "compression method %u (expected 0 stored or 1 zlib)", comp);
    if ((rc = inflate_payload(data + hdr, stored_n, raw_n, name, owned, err)))
        return rc;
    *payload = *owned;
    *payload_n = raw_n;
    return BTF_OK;
}

typedef struct span {
    const unsigned char *p;
    size_t n;
    int present;
} span;

/* Splits the payload into its sections. Unknown tags are skipped: a newer
 * minor version may add sections. */
static btf_status split_sections(const unsigned char *p, size_t n, span sec[S_COUNT],
                                 const char *name, btf_error *err)
{
    size_t pos = 0;
    while (pos < n) {
        if (n - pos < 8)
            return failf(err, BTF_E_FORMAT, name,
                         "truncated section header at payload offset %zu (expected 8 bytes)", pos);
        size_t len = get_u32(p + pos + 4);
        if (len > n - pos - 8)
            return failf(err, BTF_E_FORMAT, name,
                         "section at payload offset %zu: %zu bytes (expected at most %zu)", pos,
                         len, n - pos - 8);
        for (int t = 0; t < S_COUNT; t++)
            if (memcmp(p + pos, TAGS[t], 4) == 0) {
                if (sec[t].present)
                    return failf(err, BTF_E_FORMAT, name,
                                 "section %s appears twice (expected once)", TAGS[t]);
                sec[t] = (span){p + pos + 8, len, 1};
            }
        pos += 8 + len;
    }
    return BTF_OK;
}

static btf_status short_section(int tag, const char *name, btf_error *err)
{
    return failf(err, BTF_E_FORMAT, name, "section %s is truncated (expected more bytes)",
                 TAGS[tag]);
}

static btf_status read_dirset(const span *sp, int tag, btf_dirset *s, const char *name,
                              btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    unsigned len = r_u8(&r);
    if (len > BTF_MODEL_MAX_NAME)
        return failf(err, BTF_E_FORMAT, name, "section %s: set name of %u bytes (expected at most %d)",
                     TAGS[tag], len, BTF_MODEL_MAX_NAME);
    const unsigned char *nm = r_take(&r, len);
    unsigned count = r_u16(&r);
    if (r.short_read)
        return short_section(tag, name, err);
    if (count < 1 || count > BTF_MODEL_MAX_DIRS)
        return failf(err, BTF_E_FORMAT, name, "section %s: %u directions (expected 1..%d)",
                     TAGS[tag], count, BTF_MODEL_MAX_DIRS);
    if (r.n - r.pos < (size_t)count * 16)
        return short_section(tag, name, err);
    memcpy(s->name, nm, len);
    s->dirs = alloc_named(count, sizeof *s->dirs, 0, name, err);
    if (!s->dirs)
        return BTF_E_NOMEM;
    s->count = (int)count;
    for (unsigned i = 0; i < count; i++) {
        s->dirs[i].theta = r_f64(&r);
        s->dirs[i].phi = r_f64(&r);
    }
    return BTF_OK;
}

static btf_status read_index(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    size_t n = (size_t)m->views.count * m->lights.count;
    if (sp->n < n)
        return short_section(S_INDX, name, err);
    m->index = alloc_named(n, 1, 0, name, err);
    if (!m->index)
        return BTF_E_NOMEM;
    memcpy(m->index, sp->p, n);
    return BTF_OK;
}

static int8_t s8(unsigned char c)
{
    return (int8_t)(c >= 0x80 ? (int)c - 0x100 : (int)c);
}

static void read_band(rbuf *r, btf_car_band *b)
{
    for (int i = 0; i < b->n; i++) {
        const unsigned char *c = r_take(r, 2);
        b->offsets[i].row = c ? s8(c[0]) : 0;
        b->offsets[i].col = c ? s8(c[1]) : 0;
    }
    for (int i = 0; i < b->n; i++)
        b->gamma[i] = r_f32(r);
    b->sigma = r_f32(r);
    b->mean = r_f32(r);
}

/* Reads one subspace; counts that size loops (levels, n) are checked at
 * once, everything else by btf_model_validate (model/model_check.c). */
static btf_status read_subspace(rbuf *r, btf_subspace_model *sm, int s, const char *name,
                                btf_error *err)
{
    sm->view = r_i16(r);
    sm->light = r_i16(r);
    uint32_t w = r_u32(r), h = r_u32(r);
    if (!r->short_read && (w < 1 || w > BTF_MODEL_MAX_IMAGE_SIDE || h < 1 || h > BTF_MODEL_MAX_IMAGE_SIDE))
        return failf(err, BTF_E_FORMAT, name,
                     "subspace %d: size %lu x %lu (expected 1..%d on each side)", s,
                     (unsigned long)w, (unsigned long)h, BTF_MODEL_MAX_IMAGE_SIDE);
    sm->width = (int)w;
    sm->height = (int)h;
    for (int c = 0; c < 3; c++)
        sm->mean[c] = r_f32(r);
    for (int i = 0; i < 9; i++)
        sm->basis[i] = r_f32(r);
    sm->levels = (int)r_u8(r);
    if (r->short_read)
        return short_section(S_SUBS, name, err);
    if (sm->levels < 1 || sm->levels > BTF_MAX_LEVELS)
        return failf(err, BTF_E_FORMAT, name, "subspace %d: %d pyramid levels (expected 1..%d)", s,
                     sm->levels, BTF_MAX_LEVELS);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < sm->levels; l++) {
            btf_car_band *cb = &sm->bands[b][l];
            cb->n = (int)r_u8(r);
            if (cb->n > BTF_CAR_MAX_NEIGHBOURS)
                return failf(err, BTF_E_FORMAT, name,
                             "subspace %d, band %d, level %d: %d neighbours (expected 0..%d)", s, b,
                             l, cb->n, BTF_CAR_MAX_NEIGHBOURS);
            read_band(r, cb);
            if (r->short_read)
                return short_section(S_SUBS, name, err);
        }
    return BTF_OK;
}

static btf_status read_subspaces(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    unsigned count = r_u16(&r);
    if (r.short_read)
        return short_section(S_SUBS, name, err);
    if (count < 1 || count > BTF_MODEL_MAX_SUBSPACES)
        return failf(err, BTF_E_FORMAT, name, "%u subspaces (expected 1..%d)", count,
                     BTF_MODEL_MAX_SUBSPACES);
    m->subspaces = alloc_named(count, sizeof *m->subspaces, 1, name, err);
    if (!m->subspaces)
        return BTF_E_NOMEM;
    m->n_subspaces = (int)count;
    for (int s = 0; s < (int)count; s++) {
        btf_status rc = read_subspace(&r, &m->subspaces[s], s, name, err);
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* Rebuilds the heights from the predictor residuals and checks that the
 * grid is in range and canonical (what the encoder picks for them), so that
 * a decoded model re-encodes to the same bytes. */
static btf_status read_range(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    int w = (int)r_u16(&r), h = (int)r_u16(&r);
    float texel = r_f32(&r);
    int e = r_i16(&r);
    int32_t k = r_i32(&r);
    if (r.short_read)
        return short_section(S_RANG, name, err);
    if (w < 1 || h < 1 || (long)w * h > BTF_MODEL_MAX_RANGE_SAMPLES)
        return failf(err, BTF_E_FORMAT, name,
                     "range map: size %d x %d (expected 1..%d on each side, at most %ld samples)",
                     w, h, BTF_MODEL_MAX_RANGE_SIDE, BTF_MODEL_MAX_RANGE_SAMPLES);
    size_t n = (size_t)w * h;
    const unsigned char *planes = r_take(&r, 2 * n);
    if (!planes)
        return short_section(S_RANG, name, err);
    /* Version 1.1's flags; a 1.0 section ends before them. Bits other than
     * bit 0 are reserved (written 0, ignored). */
    int periodic = r.pos < r.n && (r.p[r.pos] & RANG_PERIODIC);
    if (e < BTF_RANGE_GRID_E_MIN || e > BTF_RANGE_GRID_E_MAX || k < -BTF_RANGE_GRID_K_LIMIT ||
        k >= BTF_RANGE_GRID_K_LIMIT)
        return failf(err, BTF_E_FORMAT, name,
                     "range map: grid 2^%d, offset %ld (expected exponent %d..%d, offset "
                     "-2^23..2^23-1)",
                     e, (long)k, BTF_RANGE_GRID_E_MIN, BTF_RANGE_GRID_E_MAX);
    uint16_t *q = alloc_named(n, sizeof *q, 0, name, err);
    if (!q)
        return BTF_E_NOMEM;
    unsigned qmax = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned z = planes[i] | (unsigned)planes[n + i] << 8;
        q[i] = (uint16_t)btf_range_unzigzag(
            z, btf_range_predict(q, w, (int)(i % (size_t)w), (int)(i / (size_t)w)));
        qmax = q[i] > qmax ? q[i] : qmax;
    }
    int ce;
    int32_t ck;
    if ((double)k + qmax + 1.0 > BTF_RANGE_GRID_K_LIMIT) {
        free(q);
        return failf(err, BTF_E_FORMAT, name,
                     "range map: offset %ld + height %u exceeds 2^23 (expected a 24-bit grid)",
                     (long)k, qmax);
    }
    m->range = alloc_named(n, sizeof *m->range, 0, name, err);
    if (!m->range) {
        free(q);
        return BTF_E_NOMEM;
    }
    float lo = 0, hi = 0;
    for (size_t i = 0; i < n; i++) {
        m->range[i] = btf_range_grid_value(e, k, q[i]);
        lo = (i == 0 || m->range[i] < lo) ? m->range[i] : lo;
        hi = (i == 0 || m->range[i] > hi) ? m->range[i] : hi;
    }
    free(q);
    m->range_width = w;
    m->range_height = h;
    m->range_texel = texel;
    if (btf_range_grid_choose(lo, hi, &ce, &ck) != 0 || ce != e || ck != k)
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

/* MARG: counts checked here, the numbers by btf_model_validate. A model
 * without the section (format 1.0, 1.1) keeps knots 0: no transfer. */
static btf_status read_marginals(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    unsigned count = r_u16(&r);
    if (r.short_read)
        return short_section(S_MARG, name, err);
    if ((int)count != m->n_subspaces)
        return failf(err, BTF_E_FORMAT, name,
                     "section MARG: %u subspaces (expected %d, as SUBS)", count, m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        btf_marginal *mg = &m->subspaces[s].marginal;
        unsigned knots = r_u8(&r);
        if (r.short_read)
            return short_section(S_MARG, name, err);
        if (knots != 0 && knots != BTF_MARGIN_KNOTS)
            return failf(err, BTF_E_FORMAT, name,
                         "section MARG: subspace %d has %u knots (expected 0 or %d)", s, knots,
                         BTF_MARGIN_KNOTS);
        mg->knots = (int)knots;
        if (!knots)
            continue;
        for (int band = 0; band < 3; band++) {
            mg->synth_mean[band] = r_f32(&r);
            mg->synth_sd[band] = r_f32(&r);
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                mg->quantile[band][j] = r_f32(&r);
        }
        for (int k = 0; k < 3; k++)
            mg->rgb_lo[k] = r_f32(&r);
        for (int k = 0; k < 3; k++)
            mg->rgb_hi[k] = r_f32(&r);
        if (r.short_read)
            return short_section(S_MARG, name, err);
    }
    return BTF_OK;
}

/* LABQ: counts checked here (a subspace without MARG knots has none), the
 * numbers by btf_model_validate. A model without the section (format 1.2
 * or older) keeps lab_knots 0: no colour matching. */
static btf_status read_lab(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    unsigned count = r_u16(&r);
    if (r.short_read)
        return short_section(S_LABQ, name, err);
    if ((int)count != m->n_subspaces)
        return failf(err, BTF_E_FORMAT, name,
                     "section LABQ: %u subspaces (expected %d, as SUBS)", count, m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        btf_marginal *mg = &m->subspaces[s].marginal;
        unsigned knots = r_u8(&r);
        if (r.short_read)
            return short_section(S_LABQ, name, err);
        if (knots != 0 && (knots != BTF_MARGIN_KNOTS || !mg->knots))
            return failf(err, BTF_E_FORMAT, name,
                         "section LABQ: subspace %d has %u knots (expected 0%s%s)", s, knots,
                         mg->knots ? " or " : ": it has no marginal transfer",
                         mg->knots ? "32" : "");
        mg->lab_knots = (int)knots;
        for (int c = 0; knots && c < 3; c++)
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                mg->lab_quantile[c][j] = btf_lab_decode(c, r_u16(&r));
        if (r.short_read)
            return short_section(S_LABQ, name, err);
    }
    return BTF_OK;
}

/* STRC: the albedo codes rebuilt from their residuals; the layer needs a
 * range map of the same size at texel 1 (checked by btf_model_validate). */
static btf_status read_structure(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    rbuf r = {sp->p, sp->n, 0, 0};
    int w = (int)r_u16(&r), h = (int)r_u16(&r);
    float ambient = r_f32(&r);
    if (r.short_read)
        return short_section(S_STRC, name, err);
    if (!m->range || w != m->range_width || h != m->range_height)
        return failf(err, BTF_E_FORMAT, name,
                     "section STRC: %d x %d (expected the range map's size, %d x %d)", w, h,
                     m->range_width, m->range_height);
    size_t n = (size_t)w * h;
    const unsigned char *res = r_take(&r, n);
    if (!res)
        return short_section(S_STRC, name, err);
    unsigned char *q = alloc_named(n, 1, 0, name, err);
    m->albedo = q ? alloc_named(n, sizeof(float), 0, name, err) : NULL;
    if (!m->albedo) {
        free(q);
        return BTF_E_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        q[i] = (unsigned char)(res[i] + albedo_predict(q, w, (int)(i % (size_t)w),
                                                       (int)(i / (size_t)w)));
        m->albedo[i] = btf_albedo_value(q[i]);
    }
    m->ambient = ambient;
    btf_status rc = BTF_OK;
    if (r.pos < r.n) { /* 1.5: the flags byte, then the colour layer */
        unsigned flags = r_u8(&r);
        size_t want = flags & STRC_CHROMA ? 3 * n : 0;
        if ((flags & ~(STRC_SHADOWS | STRC_CHROMA)) || r.n - r.pos != want)
            rc = failf(err, BTF_E_FORMAT, name, "section STRC: flags 0x%02x and %zu more "
                       "bytes (expected bits 0-1 and %zu)", flags, r.n - r.pos, want);
        m->shadows = (flags & STRC_SHADOWS) != 0;
        if (rc == BTF_OK && want &&
            !(m->chroma = alloc_named(3 * n, sizeof(float), 0, name, err)))
            rc = BTF_E_NOMEM;
        for (int c = 0; rc == BTF_OK && want && c < 3; c++) {
            const unsigned char *cr = r_take(&r, n);
            for (size_t i = 0; i < n; i++) {
                q[i] = (unsigned char)(cr[i] + albedo_predict(q, w, (int)(i % (size_t)w),
                                                              (int)(i / (size_t)w)));
                m->chroma[3 * i + c] = btf_albedo_value(q[i]);
            }
        }
    }
    free(q);
    return rc;
}

/* GAIN: the codes rebuilt from their residuals (put_gains); the index
 * table gives the pair count. */
static btf_status read_gains(const span *sp, btf_model *m, const char *name, btf_error *err)
{
    if (m->views.count < 1)
        return failf(err, BTF_E_FORMAT, name, "section GAIN without directions (expected VIEW, "
                     "LGHT and INDX)");
    size_t n = (size_t)m->views.count * m->lights.count * 3;
    if (sp->n != n)
        return failf(err, BTF_E_FORMAT, name, "section GAIN: %zu bytes (expected %zu: 3 per "
                     "pair)", sp->n, n);
    m->gain = alloc_named(n, sizeof(float), 0, name, err);
    if (!m->gain)
        return BTF_E_NOMEM;
    int prev[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        int q = (int)(signed char)(unsigned char)(sp->p[i] + prev[i % 3]);
        prev[i % 3] = q;
        m->gain[i] = btf_gain_value(q);
    }
    return BTF_OK;
}

static btf_status read_payload(const unsigned char *p, size_t n, btf_model *m, const char *name,
                               btf_error *err)
{
    span sec[S_COUNT] = {{0}};
    btf_status rc = split_sections(p, n, sec, name, err);
    if (rc)
        return rc;
    if (sec[S_VIEW].present != sec[S_LGHT].present ||
        sec[S_VIEW].present != sec[S_INDX].present)
        return failf(err, BTF_E_FORMAT, name,
                     "sections VIEW %s, LGHT %s, INDX %s (expected all three or none)",
                     sec[S_VIEW].present ? "present" : "absent",
                     sec[S_LGHT].present ? "present" : "absent",
                     sec[S_INDX].present ? "present" : "absent");
    if (!sec[S_SUBS].present)
        return failf(err, BTF_E_FORMAT, name, "no SUBS section (expected one)");
    if (sec[S_VIEW].present &&
        ((rc = read_dirset(&sec[S_VIEW], S_VIEW, &m->views, name, err)) ||
         (rc = read_dirset(&sec[S_LGHT], S_LGHT, &m->lights, name, err)) ||
         (rc = read_index(&sec[S_INDX], m, name, err))))
        return rc;
    if ((rc = read_subspaces(&sec[S_SUBS], m, name, err)))
        return rc;
    if (sec[S_RANG].present && (rc = read_range(&sec[S_RANG], m, name, err)))
        return rc;
    if (sec[S_MARG].present && (rc = read_marginals(&sec[S_MARG], m, name, err)))
        return rc;
    if (sec[S_LABQ].present && (rc = read_lab(&sec[S_LABQ], m, name, err)))
        return rc;
    if (sec[S_STRC].present && (rc = read_structure(&sec[S_STRC], m, name, err)))
        return rc;
    if (sec[S_GAIN].present && (rc = read_gains(&sec[S_GAIN], m, name, err)))
        return rc;
    return btf_model_validate(m, name, BTF_E_FORMAT, err);
}

btf_status btf_model_decode(const unsigned char *data, size_t size, const char *name,
                            btf_model *m, btf_error *err)
{
    if (!name)
        name = "model";
    if (!m)
        return failf(err, BTF_E_ARG, name, "no model to decode into");
    memset(m, 0, sizeof *m);
    if (!data && size)
        return failf(err, BTF_E_ARG, name, "no data");
    if (!data)
        data = (const unsigned char *)"";
    const unsigned char *payload = NULL;
    size_t payload_n = 0;
    unsigned char *owned = NULL;
    btf_status rc = open_container(data, size, name, &payload, &payload_n, &owned, err);
    if (rc == BTF_OK)
        rc = read_payload(payload, payload_n, m, name, err);
    free(owned);
    /* Margins are not stored: they follow from the coefficients. A budget
     * (about a second of work) keeps a small crafted file of thousands of
     * nearly unstable bands from costing minutes; past it a band takes the
     * largest margin, which is always safe. Synthesis finds them in
     * m->internal. */
    if (rc == BTF_OK && btf_model_keep_margins(m, 1e9) != BTF_OK)
        rc = failf(err, BTF_E_NOMEM, name, "out of memory");
    if (rc)
        btf_model_free(m);
    return rc;
}

btf_status btf_model_read(const char *path, btf_model *m, btf_error *err)
{
    if (!m)
        return btf_fail(err, BTF_E_ARG, "model: nothing to read into");
    memset(m, 0, sizeof *m);
    if (!path)
        return btf_fail(err, BTF_E_ARG, "model: no path to read");
    unsigned char *data;
    size_t n;
    btf_status rc = btf_read_file(path, MAX_FILE_BYTES, &data, &n, err);
    if (rc)
        return rc;
    rc = btf_model_decode(data, n, path, m, err);
    free(data);
    return rc;
}
