/*
 * rf_file.c — the reflectance-field model file (docs/rf.md, "File"): the
 * container of MODEL.btfcar (container/; docs/model-format.md: version,
 * zlib, CRC-32 over everything before it, the section framing) with its
 * own signature "\x89BTFRFL\r\n\x1a\n", so that neither reader mistakes
 * the other's file, and its own sections:
 * VIEW and LGHT (direction sets, as in MODEL.btfcar), RFHD (fit, lobes,
 * sizes), RFQR (per field and slot the quantisation range) and RFCD (the
 * 16-bit codes of Meseth, Müller & Klein 2003's per-view parameter
 * textures, section 5.2, as byte planes: per field and slot the low bytes
 * of every texel, then the high bytes, which deflate better), and, in a
 * sampled model (section 6, format 2.0), RFMP: the coordinate map of the
 * surface into the sample, each texel's shift from the identity, which is
 * constant over a quilted block and so deflates to little.
 *
 * One validator serves both directions: the encoder refuses a model the
 * decoder would reject, and the decoder trusts nothing it has not checked
 * (every size bounded before it sizes an allocation, every read
 * bounds-checked); a corrupt or truncated file is BTF_E_FORMAT naming it.
 */
#include "container/container.h"
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdlib.h>
#include <string.h>

static const unsigned char SIGNATURE[BTF_BOX_SIG_LEN] = {0x89, 'B',  'T',  'F',  'R', 'F',
                                                         'L',  '\r', '\n', 0x1a, '\n'};
#define FMT_MAJOR 1
#define FMT_MAJOR_MAP 2 /* an older reader must not skip RFMP: a new major */
#define FMT_MINOR 0
#define MAX_BYTES ((size_t)1 << 30) /* file and payload */
#define MAX_DIRS BTF_BOX_MAX_DIRS
#define MAX_SIDE 65536
#define MAX_ABS_RANGE 1e30f
static const btf_box_format FORMAT = {SIGNATURE, MAX_BYTES, 6, "in all"};

enum { S_VIEW, S_LGHT, S_RFHD, S_RFQR, S_RFCD, S_RFMP, S_COUNT };
#define S_REQUIRED S_RFMP /* the sections before it are in every file */
static const char TAGS[S_COUNT][5] = {"VIEW", "LGHT", "RFHD", "RFQR", "RFCD", "RFMP"};
#define RFHD_BYTES 17
#define RFMP_HEAD 17
#define RFMP_VERSION 1

#define failn btf__box_fail

int btf__rf_sniff(const unsigned char *data, size_t size)
{
    return btf__box_stem(SIGNATURE, data, size);
}

/* ----------------------------------------------------------- validation */

/* The name's bytes, in memory or in the file: printable ASCII (a NUL
 * inside would shorten the name written back). */
static btf_status check_name(const char *set, size_t len, const char *what, const char *name,
                             int code, btf_error *err)
{
    size_t i = btf__box_name_unprintable(set, len);
    if (i < len)
        return failn(err, code, name, "%s: name byte %zu is 0x%02x (expected printable ASCII)",
                     what, i, (unsigned char)set[i]);
    return BTF_OK;
}

/* A reflectance field's sets are ring by ring, the renderer's order
 * (docs/rf.md, "File"). */
static btf_status check_dirset(const btf_dirset *s, const char *what, const char *name,
                               int code, btf_error *err)
{
    if (s->count < 1 || s->count > MAX_DIRS || !s->dirs)
        return failn(err, code, name, "%s: %d directions (expected 1..%d)", what, s->count,
                     MAX_DIRS);
    size_t len = strnlen(s->name, sizeof s->name);
    if (len >= sizeof s->name)
        return failn(err, code, name, "%s: unterminated name", what);
    btf_status rc = check_name(s->name, len, what, name, code, err);
    for (int i = 0; rc == BTF_OK && i < s->count; i++) {
        btf_dir d = s->dirs[i];
        if (!btf__box_dir_in_range(d))
            return failn(err, code, name, "%s: direction %d is (%g, %g) (expected theta in "
                         "[0, 90], phi in [0, 360))", what, i, d.theta, d.phi);
        btf_dir p = i > 0 ? s->dirs[i - 1] : d;
        if (i > 0 && !btf__box_dir_follows(p, d))
            return failn(err, code, name, "%s: direction %d (%g, %g) after (%g, %g) "
                         "(expected ring by ring, theta ascending, phi ascending in a "
                         "ring)", what, i, d.theta, d.phi, p.theta, p.phi);
    }
    return rc;
}

/* A sampled model's map (section 6): a surface within the bounds, every
 * entry a texel of the sample. */
static btf_status validate_map(const btf_rf_model *m, const char *name, int code,
                               btf_error *err)
{
    if (m->surface_width < 1 || m->surface_height < 1 ||
        m->surface_width > BTF_RF_MAX_SURFACE_SIDE || m->surface_height > BTF_RF_MAX_SURFACE_SIDE)
        return failn(err, code, name, "coordinate map of %dx%d texels (expected sides 1..%d)",
                     m->surface_width, m->surface_height, BTF_RF_MAX_SURFACE_SIDE);
    if (m->sample_x < 0 || m->sample_y < 0 || m->sample_x > MAX_SIDE - m->width ||
        m->sample_y > MAX_SIDE - m->height)
        return failn(err, code, name, "sample at (%d, %d) (expected a place within %d texels)",
                     m->sample_x, m->sample_y, MAX_SIDE);
    size_t n = (size_t)m->surface_width * m->surface_height;
    for (size_t t = 0; t < n; t++)
        if (m->map[2 * t] >= m->width || m->map[2 * t + 1] >= m->height)
            return failn(err, code, name, "coordinate map: texel (%zu, %zu) shows (%u, %u) "
                         "(expected a texel of the %dx%d sample)", t % m->surface_width,
                         t / m->surface_width, m->map[2 * t], m->map[2 * t + 1], m->width,
                         m->height);
    return BTF_OK;
}

/* The rules both directions share; code: BTF_E_DATA (encoder) or
 * BTF_E_FORMAT (decoder). The codes are not checked: any code is legal. */
static btf_status validate(const btf_rf_model *m, const char *name, int code, btf_error *err)
{
    btf_status rc;
    if ((rc = check_dirset(&m->views, "views", name, code, err)) ||
        (rc = check_dirset(&m->lights, "lights", name, code, err)))
        return rc;
    if (!btf_rf_fit_name(m->fit))
        return failn(err, code, name, "fit %d (expected 0 ptm, 1 lobes or 2 lafortune)", m->fit);
    if (m->fit == BTF_RF_PTM ? m->lobes != 0 : (m->lobes < 1 || m->lobes > BTF_RF_MAX_LOBES))
        return failn(err, code, name, "%d lobes with the %s fit (expected %s)", m->lobes,
                     btf_rf_fit_name(m->fit), m->fit == BTF_RF_PTM ? "0" : "1..4");
    int params = btf__rf_param_count(m->fit, m->fit == BTF_RF_PTM ? 2 : m->lobes);
    if (m->params != params || m->slots != params + 3)
        return failn(err, code, name, "%d parameters in %d slots (expected %d in %d for %s)",
                     m->params, m->slots, params, params + 3, btf_rf_fit_name(m->fit));
    int fields = m->fit == BTF_RF_LAFORTUNE ? 1 : m->views.count;
    if (m->fields != fields)
        return failn(err, code, name, "%d fields (expected %d)", m->fields, fields);
    if (m->width < 1 || m->width > MAX_SIDE || m->height < 1 || m->height > MAX_SIDE)
        return failn(err, code, name, "%dx%d texels (expected sides 1..%d)", m->width,
                     m->height, MAX_SIDE);
    if (!m->lo || !m->hi || !m->codes)
        return failn(err, code, name, "no parameters");
    for (int i = 0; i < m->fields * m->slots; i++) {
        float a = m->lo[i], b = m->hi[i];
        if (!isfinite(a) || !isfinite(b) || !(a <= b) || fabsf(a) > MAX_ABS_RANGE ||
            fabsf(b) > MAX_ABS_RANGE)
            return failn(err, code, name, "field %d, slot %d: range [%g, %g] (expected finite, "
                         "lo <= hi, magnitudes <= 1e30)", i / m->slots, i % m->slots, a, b);
    }
    return m->map ? validate_map(m, name, code, err) : BTF_OK;
}

/* ------------------------------------------------------------- writing */

/* RFMP: u8 version, u32 surface width and height, u32 sample x and y,
 * then per surface texel the shift of its sample texel from the identity
 * (the texel's place less the sample's, wrapped into the sample) as byte
 * planes: x shifts' low bytes, their high bytes, y shifts' low, high. */
static void w_map(btf_box_writer *b, const btf_rf_model *m)
{
    size_t body = btf__box_section_begin(b, TAGS[S_RFMP]);
    btf__box_put_u8(b, RFMP_VERSION);
    btf__box_put_u32(b, (uint32_t)m->surface_width), btf__box_put_u32(b, (uint32_t)m->surface_height);
    btf__box_put_u32(b, (uint32_t)m->sample_x), btf__box_put_u32(b, (uint32_t)m->sample_y);
    size_t n = (size_t)m->surface_width * m->surface_height;
    unsigned char *p = btf__box_reserve(b, 4 * n);
    if (p)
        for (size_t t = 0; t < n; t++) {
            int x = (int)(t % m->surface_width), y = (int)(t / m->surface_width);
            unsigned dx = (unsigned)rf_wrap(m->map[2 * t] - rf_wrap(x - m->sample_x, m->width),
                                            m->width);
            unsigned dy = (unsigned)rf_wrap(m->map[2 * t + 1] -
                                                rf_wrap(y - m->sample_y, m->height),
                                            m->height);
            p[t] = dx & 255, p[n + t] = dx >> 8, p[2 * n + t] = dy & 255, p[3 * n + t] = dy >> 8;
        }
    btf__box_section_end(b, body);
}

/* The payload: the direction sets, RFHD, RFQR, RFCD and, in a sampled
 * model, RFMP. */
static void build_payload(btf_box_writer *b, const btf_rf_model *m, size_t planes,
                          size_t texels)
{
    btf__box_put_dirset(b, TAGS[S_VIEW], &m->views, 0);
    btf__box_put_dirset(b, TAGS[S_LGHT], &m->lights, 0);
    size_t body = btf__box_section_begin(b, TAGS[S_RFHD]);
    btf__box_put_u8(b, (unsigned)m->fit), btf__box_put_u8(b, (unsigned)m->lobes);
    btf__box_put_u16(b, (unsigned)m->params), btf__box_put_u16(b, (unsigned)m->slots);
    btf__box_put_u32(b, (uint32_t)m->width), btf__box_put_u32(b, (uint32_t)m->height);
    btf__box_put_u32(b, (uint32_t)m->fields);
    btf__box_section_end(b, body);
    body = btf__box_section_begin(b, TAGS[S_RFQR]);
    for (size_t i = 0; i < planes; i++)
        btf__box_put_f32(b, m->lo[i]), btf__box_put_f32(b, m->hi[i]);
    btf__box_section_end(b, body);
    body = btf__box_section_begin(b, TAGS[S_RFCD]);
    unsigned char *cd = btf__box_reserve(b, planes * texels * 2);
    if (cd)
        for (size_t pl = 0; pl < planes; pl++) {
            size_t f = pl / m->slots, s = pl % m->slots;
            const uint16_t *q = m->codes + f * texels * m->slots + s;
            unsigned char *lo = cd + pl * texels * 2, *hi = lo + texels;
            for (size_t t = 0; t < texels; t++) {
                uint16_t v = q[t * m->slots];
                lo[t] = (unsigned char)(v & 255), hi[t] = (unsigned char)(v >> 8);
            }
        }
    btf__box_section_end(b, body);
    if (m->map)
        w_map(b, m);
}

btf_status btf_rf_encode(const btf_rf_model *m, unsigned char **data, size_t *size,
                         btf_error *err)
{
    const char *name = "reflectance-field model";
    btf_status rc = btf__box_output(data, size, name, err);
    if (rc)
        return rc;
    if (!m)
        return failn(err, BTF_E_ARG, name, "no model");
    if ((rc = validate(m, name, BTF_E_DATA, err)))
        return rc;
    size_t texels = (size_t)m->width * m->height;
    size_t planes = (size_t)m->fields * m->slots;
    size_t map_bytes = m->map ? RFMP_HEAD + 4 * (size_t)m->surface_width * m->surface_height : 0;
    if (planes * texels * 2 + map_bytes >
        MAX_BYTES - 65536 - 32 * (size_t)MAX_DIRS - planes * 8)
        return failn(err, BTF_E_DATA, name, "%zu parameter codes and %zu bytes of coordinate "
                     "map (expected a payload of at most %zu bytes)", planes * texels,
                     map_bytes, MAX_BYTES);
    btf_box_writer b = {0};
    build_payload(&b, m, planes, texels);
    unsigned char *out = b.failed ? NULL : btf__alloc(btf__box_bound(b.n), 1, NULL);
    if (!out) {
        free(b.p);
        return failn(err, BTF_E_NOMEM, name, "out of memory encoding the model");
    }
    *size = btf__box_seal(&FORMAT, m->map ? FMT_MAJOR_MAP : FMT_MAJOR, FMT_MINOR, b.p, b.n, out);
    *data = out;
    free(b.p);
    return BTF_OK;
}

btf_status btf_rf_write(const char *path, const btf_rf_model *m, btf_error *err)
{
    if (!path)
        return btf__fail(err, BTF_E_ARG, "btf_rf_write: no path");
    unsigned char *data;
    size_t n;
    btf_status rc = btf_rf_encode(m, &data, &n, err);
    if (rc) {
        btf__error_name(err, path);
        return rc;
    }
    rc = btf_write_file_atomic(path, data, n, err);
    free(data);
    return rc;
}

/* ------------------------------------------------------------- reading */

/* Signature (this family's, not damaged), version 1 or 2, then the
 * container (docs/rf.md, "File"); hands back the payload, inflated into
 * *owned when deflated. */
static btf_status open_payload(const unsigned char *data, size_t size, const char *name,
                               btf_box_payload *pl, unsigned char **owned, unsigned *major_out,
                               btf_error *err)
{
    if (!btf__box_stem(SIGNATURE, data, size))
        return failn(err, BTF_E_FORMAT, name, "not a reflectance-field model (expected the "
                     "signature \\x89BTFRFL)");
    if (btf__box_signature(SIGNATURE, data, size) != BTF_BOX_WHOLE)
        return failn(err, BTF_E_FORMAT, name, "damaged signature: the file went through a "
                     "text-mode transfer (expected \\x89BTFRFL\\r\\n\\x1a\\n; line endings "
                     "converted)");
    if (size < BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES)
        return failn(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)",
                     size, BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES);
    unsigned major = btf__box_load_u16(data + BTF_BOX_AT_MAJOR);
    unsigned minor = btf__box_load_u16(data + BTF_BOX_AT_MINOR);
    if (major != FMT_MAJOR && major != FMT_MAJOR_MAP)
        return failn(err, BTF_E_FORMAT, name, "format version %u.%u (expected major version %d "
                     "or %d%s)", major, minor, FMT_MAJOR, FMT_MAJOR_MAP,
                     major > FMT_MAJOR_MAP ? "; a newer btfcar reads it" : "");
    *major_out = major;
    btf_status rc = btf__box_open(&FORMAT, data, size, name, pl, err);
    if (rc || !pl->deflated)
        return rc;
    *owned = btf__alloc(pl->size ? pl->size : 1, 1, NULL);
    if (!*owned)
        return failn(err, BTF_E_NOMEM, name, "out of memory inflating %zu bytes", pl->size);
    rc = btf__box_inflate(pl, *owned, name, err);
    pl->data = *owned;
    pl->n = pl->size;
    return rc;
}

/* VIEW, LGHT: exactly the name, the count and the directions. */
static btf_status read_dirset(const btf_box_span *s, const char *what, const char *name,
                              btf_dirset *d, btf_error *err)
{
    if (s->n < 3)
        return failn(err, BTF_E_FORMAT, name, "%s section of %zu bytes (expected at least 3)",
                     what, s->n);
    btf_box_dirset_head h;
    btf__box_dirset_head_of(s->p, s->n, &h);
    if (h.name_len > BTF_BOX_MAX_NAME || s->n < h.head)
        return failn(err, BTF_E_FORMAT, name, "%s: name of %zu bytes in a section of %zu "
                     "(expected at most 31)", what, h.name_len, s->n);
    btf_status rc = check_name((const char *)h.name, h.name_len, what, name, BTF_E_FORMAT, err);
    if (rc)
        return rc;
    if (h.count < 1 || h.count > MAX_DIRS || s->n != h.head + BTF_BOX_DIR_BYTES * h.count)
        return failn(err, BTF_E_FORMAT, name, "%s: %zu directions in %zu bytes (expected 1..%d "
                     "directions of 16 bytes)", what, h.count, s->n, MAX_DIRS);
    d->dirs = btf__alloc(h.count, sizeof(btf_dir), NULL);
    if (!d->dirs)
        return failn(err, BTF_E_NOMEM, name, "out of memory reading the %s", what);
    btf__box_dirset_fill(s->p, &h, d);
    return BTF_OK;
}

/* RFMP (format 2): the map, every shift checked against the sample. */
static btf_status read_map(const btf_box_span *s, const char *name, btf_rf_model *m, btf_error *err)
{
    if (s->n < RFMP_HEAD || s->p[0] != RFMP_VERSION)
        return failn(err, BTF_E_FORMAT, name, "RFMP section of %zu bytes, version %d (expected "
                     "at least %d bytes, version %d)", s->n, s->n ? s->p[0] : -1, RFMP_HEAD,
                     RFMP_VERSION);
    uint32_t sw = btf__box_load_u32(s->p + 1), sh = btf__box_load_u32(s->p + 5);
    uint32_t x0 = btf__box_load_u32(s->p + 9), y0 = btf__box_load_u32(s->p + 13);
    if (sw < 1 || sw > BTF_RF_MAX_SURFACE_SIDE || sh < 1 || sh > BTF_RF_MAX_SURFACE_SIDE ||
        x0 > (uint32_t)(MAX_SIDE - m->width) || y0 > (uint32_t)(MAX_SIDE - m->height))
        return failn(err, BTF_E_FORMAT, name, "coordinate map of %ux%u texels, sample at (%u, "
                     "%u) (expected sides 1..%d, a place within %d texels)", sw, sh, x0, y0,
                     BTF_RF_MAX_SURFACE_SIDE, MAX_SIDE);
    size_t n = (size_t)sw * sh;
    if (s->n != RFMP_HEAD + 4 * n)
        return failn(err, BTF_E_FORMAT, name, "RFMP section of %zu bytes (expected %zu for a "
                     "%ux%u map)", s->n, RFMP_HEAD + 4 * n, sw, sh);
    m->map = btf__alloc(n, 2 * sizeof(uint16_t), NULL);
    if (!m->map)
        return failn(err, BTF_E_NOMEM, name, "out of memory for a %ux%u coordinate map", sw, sh);
    m->surface_width = (int)sw, m->surface_height = (int)sh;
    m->sample_x = (int)x0, m->sample_y = (int)y0;
    const unsigned char *q = s->p + RFMP_HEAD;
    for (size_t t = 0; t < n; t++) {
        unsigned dx = q[t] | (unsigned)q[n + t] << 8, dy = q[2 * n + t] | (unsigned)q[3 * n + t] << 8;
        if (dx >= (unsigned)m->width || dy >= (unsigned)m->height)
            return failn(err, BTF_E_FORMAT, name, "coordinate map: texel (%zu, %zu) shifted by "
                         "(%u, %u) (expected less than the %dx%d sample)", t % sw, t / sw, dx,
                         dy, m->width, m->height);
        int x = (int)(t % sw), y = (int)(t / sw);
        m->map[2 * t] = (uint16_t)rf_wrap(rf_wrap(x - m->sample_x, m->width) + (int)dx, m->width);
        m->map[2 * t + 1] =
            (uint16_t)rf_wrap(rf_wrap(y - m->sample_y, m->height) + (int)dy, m->height);
    }
    return BTF_OK;
}

/* Sections (each known one at most once, any order, unknown tags
 * skipped) filling the payload exactly; the required ones present, RFMP
 * in format 2 only. */
static btf_status split_payload(const btf_box_payload *pl, unsigned major, btf_box_span *sec,
                                const char *name, btf_error *err)
{
    char tag[5];
    btf_box_split_at at;
    switch (btf__box_split(pl->data, pl->size, TAGS, S_COUNT, sec, &at)) {
    case BTF_BOX_SPLIT_OK:
        break;
    case BTF_BOX_SPLIT_SHORT_HEAD:
        return failn(err, BTF_E_FORMAT, name, "truncated section header at payload byte %zu "
                     "(expected 8 bytes)", at.at);
    case BTF_BOX_SPLIT_PAST_END:
        return failn(err, BTF_E_FORMAT, name, "section '%s' of %zu bytes at payload byte %zu "
                     "runs past the payload (expected at most %zu bytes)",
                     btf__box_tag_text(pl->data + at.at, tag), at.len, at.at, at.room);
    default:
        return failn(err, BTF_E_FORMAT, name, "section %s twice (expected once)", TAGS[at.tag]);
    }
    for (int s = 0; s < S_REQUIRED; s++)
        if (!sec[s].present)
            return failn(err, BTF_E_FORMAT, name, "no %s section (expected every one of VIEW, "
                         "LGHT, RFHD, RFQR, RFCD)", TAGS[s]);
    if (sec[S_RFMP].present != (major == FMT_MAJOR_MAP))
        return failn(err, BTF_E_FORMAT, name, "format %u %s an RFMP section (expected one in "
                     "format %d, a sampled model, and none in format %d)", major,
                     sec[S_RFMP].present ? "with" : "without", FMT_MAJOR_MAP, FMT_MAJOR);
    return BTF_OK;
}

/* RFHD: the fit and the sizes that size everything after it. */
static btf_status read_header(const btf_box_span *h, const char *name, btf_rf_model *m,
                              btf_error *err)
{
    if (h->n < RFHD_BYTES)
        return failn(err, BTF_E_FORMAT, name, "RFHD section of %zu bytes (expected %d)", h->n,
                     RFHD_BYTES);
    m->fit = h->p[0], m->lobes = h->p[1];
    m->params = (int)btf__box_load_u16(h->p + 2), m->slots = (int)btf__box_load_u16(h->p + 4);
    uint32_t w = btf__box_load_u32(h->p + 6), ht = btf__box_load_u32(h->p + 10);
    uint32_t fields = btf__box_load_u32(h->p + 14);
    if (w < 1 || w > MAX_SIDE || ht < 1 || ht > MAX_SIDE || fields < 1 || fields > MAX_DIRS ||
        m->slots < 1 || m->slots > BTF_RF_MAX_SLOTS)
        return failn(err, BTF_E_FORMAT, name, "%ux%u texels, %u fields, %d slots (expected sides "
                     "1..%d, 1..%d fields, 1..%d slots)", w, ht, fields, m->slots, MAX_SIDE,
                     MAX_DIRS, BTF_RF_MAX_SLOTS);
    m->width = (int)w, m->height = (int)ht, m->fields = (int)fields;
    return BTF_OK;
}

/* RFQR and RFCD: per field and slot the range and the codes' byte planes,
 * of exactly the sizes RFHD gives. */
static btf_status read_codes(const btf_box_span *qr, const btf_box_span *cd, const char *name,
                             btf_rf_model *m, btf_error *err)
{
    size_t planes = (size_t)m->fields * m->slots, texels = (size_t)m->width * m->height;
    if (qr->n != planes * 8)
        return failn(err, BTF_E_FORMAT, name, "RFQR section of %zu bytes (expected %zu: %zu "
                     "ranges)", qr->n, planes * 8, planes);
    /* planes <= 4096 x 23 and texels <= 2^32: the product fits 64 bits */
    if ((uint64_t)cd->n != (uint64_t)planes * texels * 2)
        return failn(err, BTF_E_FORMAT, name, "RFCD section of %zu bytes (expected %llu: %zu "
                     "fields x %d slots x %ux%u texels x 2)", cd->n,
                     (unsigned long long)planes * texels * 2, (size_t)m->fields, m->slots,
                     (unsigned)m->width, (unsigned)m->height);
    m->lo = btf__alloc(planes, sizeof(float), NULL);
    m->hi = btf__alloc(planes, sizeof(float), NULL);
    m->codes = btf__alloc(planes * texels, sizeof(uint16_t), NULL);
    if (!m->lo || !m->hi || !m->codes)
        return failn(err, BTF_E_NOMEM, name, "out of memory for %zu parameter codes",
                     planes * texels);
    for (size_t i = 0; i < planes; i++) {
        m->lo[i] = btf__box_load_f32(qr->p + 8 * i);
        m->hi[i] = btf__box_load_f32(qr->p + 8 * i + 4);
    }
    for (size_t pl = 0; pl < planes; pl++) {
        size_t f = pl / m->slots, s = pl % m->slots;
        uint16_t *q = m->codes + f * texels * m->slots + s;
        const unsigned char *lo = cd->p + pl * texels * 2, *hi = lo + texels;
        for (size_t t = 0; t < texels; t++)
            q[t * m->slots] = (uint16_t)(lo[t] | hi[t] << 8);
    }
    return BTF_OK;
}

static btf_status decode_payload(const btf_box_payload *pl, const char *name, unsigned major,
                                 btf_rf_model *m, btf_error *err)
{
    btf_box_span sec[S_COUNT] = {{0}};
    btf_status rc;
    if ((rc = split_payload(pl, major, sec, name, err)) ||
        (rc = read_dirset(&sec[S_VIEW], "views", name, &m->views, err)) ||
        (rc = read_dirset(&sec[S_LGHT], "lights", name, &m->lights, err)) ||
        (rc = read_header(&sec[S_RFHD], name, m, err)) ||
        (rc = read_codes(&sec[S_RFQR], &sec[S_RFCD], name, m, err)) ||
        (sec[S_RFMP].present && (rc = read_map(&sec[S_RFMP], name, m, err))))
        return rc;
    return validate(m, name, BTF_E_FORMAT, err);
}

btf_status btf_rf_decode(const unsigned char *data, size_t size, const char *name,
                         btf_rf_model *out, btf_error *err)
{
    if (!name)
        name = "buffer";
    if (!out)
        return failn(err, BTF_E_ARG, name, "no output model");
    memset(out, 0, sizeof *out);
    btf_status rc = btf__box_input(&data, size, name, err);
    if (rc)
        return rc;
    btf_box_payload pl;
    unsigned char *owned = NULL;
    unsigned major = 0;
    rc = open_payload(data, size, name, &pl, &owned, &major, err);
    if (rc == BTF_OK)
        rc = decode_payload(&pl, name, major, out, err);
    free(owned);
    if (rc)
        btf_rf_model_free(out);
    return rc;
}

btf_status btf__rf_read(const char *path, btf_rf_model *out, btf_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out)
        return btf__fail(err, BTF_E_ARG, "btf_rf_read: no path or no output model");
    unsigned char *data;
    size_t n;
    btf_status rc = btf__read_file(path, MAX_BYTES, &data, &n, err);
    if (rc)
        return rc;
    rc = btf_rf_decode(data, n, path, out, err);
    free(data);
    return rc;
}
