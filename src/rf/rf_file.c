/*
 * rf_file.c — the reflectance-field model file (docs/rf.md, "File"): the
 * container of MODEL.btfcar (docs/model-format.md: version, zlib, CRC-32
 * over everything before it) with its own signature "\x89BTFRFL\r\n\x1a\n",
 * so that neither reader mistakes the other's file, and its own sections:
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
#include "rf/rf.h"
#include "rf/rf_map.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#define SIG_LEN 11
#define SIG_STEM 7
static const unsigned char SIGNATURE[SIG_LEN] = {0x89, 'B', 'T', 'F', 'R', 'F',
                                                 'L',  '\r', '\n', 0x1a, '\n'};
#define FMT_MAJOR 1
#define FMT_MAJOR_MAP 2 /* an older reader must not skip RFMP: a new major */
#define FMT_MINOR 0
#define HEADER_BYTES 26
#define CRC_BYTES 4
#define COMP_STORED 0
#define COMP_ZLIB 1
#define ZLIB_MAX_RATIO 1032u
#define MAX_FILE_BYTES ((size_t)1 << 30)
#define MAX_PAYLOAD_BYTES ((size_t)1 << 30)
#define MAX_DIRS 4096
#define MAX_SIDE 65536
#define MAX_ABS_RANGE 1e30f

enum { S_VIEW, S_LGHT, S_RFHD, S_RFQR, S_RFCD, S_RFMP, S_COUNT };
#define S_REQUIRED S_RFMP /* the sections before it are in every file */
static const char TAGS[S_COUNT][5] = {"VIEW", "LGHT", "RFHD", "RFQR", "RFCD", "RFMP"};
#define RFHD_BYTES 17
#define RFMP_HEAD 17
#define RFMP_VERSION 1

static btf_status failn(btf_error *err, int code, const char *name, const char *fmt, ...)
    BTF_PRINTF(4, 5);
static btf_status failn(btf_error *err, int code, const char *name, const char *fmt, ...)
{
    char msg[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return btf_fail(err, code, "%s: %s", name, msg);
}

int btf_rf_sniff(const unsigned char *data, size_t size)
{
    return data && size >= SIG_STEM && memcmp(data, SIGNATURE, SIG_STEM) == 0;
}

/* ----------------------------------------------------------- validation */

static btf_status check_dirset(const btf_dirset *s, const char *what, const char *name,
                               int code, btf_error *err)
{
    if (s->count < 1 || s->count > MAX_DIRS || !s->dirs)
        return failn(err, code, name, "%s: %d directions (expected 1..%d)", what, s->count,
                     MAX_DIRS);
    size_t len = strnlen(s->name, sizeof s->name);
    if (len >= sizeof s->name)
        return failn(err, code, name, "%s: unterminated name", what);
    for (size_t i = 0; i < len; i++)
        if (s->name[i] < 0x20 || s->name[i] > 0x7e)
            return failn(err, code, name, "%s: name byte %zu is 0x%02x (expected printable "
                         "ASCII)", what, i, (unsigned char)s->name[i]);
    for (int i = 0; i < s->count; i++) {
        btf_dir d = s->dirs[i];
        if (!(d.theta >= 0 && d.theta <= 90) || !(d.phi >= 0 && d.phi < 360))
            return failn(err, code, name, "%s: direction %d is (%g, %g) (expected theta in "
                         "[0, 90], phi in [0, 360))", what, i, d.theta, d.phi);
        if (i > 0) {
            btf_dir p = s->dirs[i - 1];
            int same_ring = p.theta == d.theta;
            if (d.theta < p.theta || (same_ring && !(d.phi > p.phi)))
                return failn(err, code, name, "%s: direction %d (%g, %g) after (%g, %g) "
                             "(expected ring by ring, theta ascending, phi ascending in a "
                             "ring)", what, i, d.theta, d.phi, p.theta, p.phi);
        }
    }
    return BTF_OK;
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
    int params = btf_rf_param_count(m->fit, m->fit == BTF_RF_PTM ? 2 : m->lobes);
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

typedef struct wbuf {
    unsigned char *p;
    size_t n, cap;
    int failed;
} wbuf;

static unsigned char *w_reserve(wbuf *b, size_t n)
{
    if (b->failed)
        return NULL;
    if (b->cap - b->n < n) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap - b->n < n)
            cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (!p) {
            b->failed = 1;
            return NULL;
        }
        b->p = p, b->cap = cap;
    }
    unsigned char *at = b->p + b->n;
    b->n += n;
    return at;
}
static void put_u16(unsigned char *p, unsigned v) { p[0] = v & 255, p[1] = (v >> 8) & 255; }
static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (v >> (8 * i)) & 255;
}
static void w_bytes(wbuf *b, const void *src, size_t n)
{
    unsigned char *p = w_reserve(b, n);
    if (p)
        memcpy(p, src, n);
}
static void w_u8(wbuf *b, unsigned v) { unsigned char c = (unsigned char)v; w_bytes(b, &c, 1); }
static void w_u16(wbuf *b, unsigned v) { unsigned char c[2]; put_u16(c, v); w_bytes(b, c, 2); }
static void w_u32(wbuf *b, uint32_t v) { unsigned char c[4]; put_u32(c, v); w_bytes(b, c, 4); }
static void w_f32(wbuf *b, float f) { uint32_t u; memcpy(&u, &f, 4); w_u32(b, u); }
static void w_f64(wbuf *b, double f)
{
    uint64_t u;
    memcpy(&u, &f, 8);
    w_u32(b, (uint32_t)u);
    w_u32(b, (uint32_t)(u >> 32));
}
static size_t w_section(wbuf *b, int s)
{
    w_bytes(b, TAGS[s], 4);
    w_u32(b, 0);
    return b->n;
}
static void w_section_end(wbuf *b, size_t body)
{
    if (!b->failed)
        put_u32(b->p + body - 4, (uint32_t)(b->n - body));
}

static void w_dirset(wbuf *b, int s, const btf_dirset *d)
{
    size_t body = w_section(b, s);
    size_t len = strnlen(d->name, sizeof d->name);
    w_u8(b, (unsigned)len);
    w_bytes(b, d->name, len);
    w_u16(b, (unsigned)d->count);
    for (int i = 0; i < d->count; i++)
        w_f64(b, d->dirs[i].theta), w_f64(b, d->dirs[i].phi);
    w_section_end(b, body);
}

/* RFMP: u8 version, u32 surface width and height, u32 sample x and y,
 * then per surface texel the shift of its sample texel from the identity
 * (the texel's place less the sample's, wrapped into the sample) as byte
 * planes: x shifts' low bytes, their high bytes, y shifts' low, high. */
static void w_map(wbuf *b, const btf_rf_model *m)
{
    size_t body = w_section(b, S_RFMP);
    w_u8(b, RFMP_VERSION);
    w_u32(b, (uint32_t)m->surface_width), w_u32(b, (uint32_t)m->surface_height);
    w_u32(b, (uint32_t)m->sample_x), w_u32(b, (uint32_t)m->sample_y);
    size_t n = (size_t)m->surface_width * m->surface_height;
    unsigned char *p = w_reserve(b, 4 * n);
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
    w_section_end(b, body);
}

btf_status btf_rf_encode(const btf_rf_model *m, unsigned char **data, size_t *size,
                         btf_error *err)
{
    const char *name = "reflectance-field model";
    if (!data || !size)
        return failn(err, BTF_E_ARG, name, "no output buffer");
    *data = NULL, *size = 0;
    if (!m)
        return failn(err, BTF_E_ARG, name, "no model");
    btf_status rc = validate(m, name, BTF_E_DATA, err);
    if (rc)
        return rc;
    size_t texels = (size_t)m->width * m->height;
    size_t planes = (size_t)m->fields * m->slots;
    size_t map_bytes = m->map ? RFMP_HEAD + 4 * (size_t)m->surface_width * m->surface_height : 0;
    if (planes * texels * 2 + map_bytes >
        MAX_PAYLOAD_BYTES - 65536 - 32 * (size_t)MAX_DIRS - planes * 8)
        return failn(err, BTF_E_DATA, name, "%zu parameter codes and %zu bytes of coordinate "
                     "map (expected a payload of at most %zu bytes)", planes * texels,
                     map_bytes, MAX_PAYLOAD_BYTES);
    wbuf b = {0};
    w_dirset(&b, S_VIEW, &m->views);
    w_dirset(&b, S_LGHT, &m->lights);
    size_t body = w_section(&b, S_RFHD);
    w_u8(&b, (unsigned)m->fit), w_u8(&b, (unsigned)m->lobes);
    w_u16(&b, (unsigned)m->params), w_u16(&b, (unsigned)m->slots);
    w_u32(&b, (uint32_t)m->width), w_u32(&b, (uint32_t)m->height), w_u32(&b, (uint32_t)m->fields);
    w_section_end(&b, body);
    body = w_section(&b, S_RFQR);
    for (size_t i = 0; i < planes; i++)
        w_f32(&b, m->lo[i]), w_f32(&b, m->hi[i]);
    w_section_end(&b, body);
    body = w_section(&b, S_RFCD);
    unsigned char *cd = w_reserve(&b, planes * texels * 2);
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
    w_section_end(&b, body);
    if (m->map)
        w_map(&b, m);
    if (b.failed) {
        free(b.p);
        return failn(err, BTF_E_NOMEM, name, "out of memory encoding the model");
    }
    uLongf zlen = compressBound((uLong)b.n);
    unsigned char *out = btf_alloc(HEADER_BYTES + (size_t)zlen + CRC_BYTES, 1, NULL);
    if (!out) {
        free(b.p);
        return failn(err, BTF_E_NOMEM, name, "out of memory encoding the model");
    }
    unsigned comp = COMP_ZLIB;
    if (compress2(out + HEADER_BYTES, &zlen, b.p, (uLong)b.n, 6) != Z_OK || zlen >= b.n) {
        comp = COMP_STORED;
        zlen = (uLongf)b.n;
        memcpy(out + HEADER_BYTES, b.p, b.n);
    }
    memcpy(out, SIGNATURE, SIG_LEN);
    put_u16(out + 11, m->map ? FMT_MAJOR_MAP : FMT_MAJOR);
    put_u16(out + 13, FMT_MINOR);
    put_u16(out + 15, HEADER_BYTES);
    out[17] = (unsigned char)comp;
    put_u32(out + 18, (uint32_t)b.n);
    put_u32(out + 22, (uint32_t)zlen);
    size_t end = HEADER_BYTES + (size_t)zlen;
    put_u32(out + end, (uint32_t)crc32(0L, out, (uInt)end));
    free(b.p);
    *data = out;
    *size = end + CRC_BYTES;
    return BTF_OK;
}

btf_status btf_rf_write(const char *path, const btf_rf_model *m, btf_error *err)
{
    if (!path)
        return btf_fail(err, BTF_E_ARG, "btf_rf_write: no path");
    unsigned char *data;
    size_t n;
    btf_status rc = btf_rf_encode(m, &data, &n, err);
    if (rc) {
        btf_error_name(err, path);
        return rc;
    }
    rc = btf_write_file_atomic(path, data, n, err);
    free(data);
    return rc;
}

/* ------------------------------------------------------------- reading */

static unsigned get_u16(const unsigned char *p) { return p[0] | (unsigned)p[1] << 8; }
static uint32_t get_u32(const unsigned char *p)
{
    return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static float get_f32(const unsigned char *p)
{
    uint32_t u = get_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static double get_f64(const unsigned char *p)
{
    uint64_t u = get_u32(p) | (uint64_t)get_u32(p + 4) << 32;
    double f;
    memcpy(&f, &u, 8);
    return f;
}

static btf_status open_container(const unsigned char *data, size_t size, const char *name,
                                 const unsigned char **payload, size_t *payload_n,
                                 unsigned char **owned, unsigned *major_out, btf_error *err)
{
    if (size < SIG_STEM || memcmp(data, SIGNATURE, SIG_STEM) != 0)
        return failn(err, BTF_E_FORMAT, name, "not a reflectance-field model (expected the "
                     "signature \\x89BTFRFL)");
    if (size < SIG_LEN || memcmp(data, SIGNATURE, SIG_LEN) != 0)
        return failn(err, BTF_E_FORMAT, name, "damaged signature: the file went through a "
                     "text-mode transfer (expected \\x89BTFRFL\\r\\n\\x1a\\n; line endings "
                     "converted)");
    if (size < HEADER_BYTES + CRC_BYTES)
        return failn(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)",
                     size, HEADER_BYTES + CRC_BYTES);
    unsigned major = get_u16(data + 11), minor = get_u16(data + 13);
    if (major != FMT_MAJOR && major != FMT_MAJOR_MAP)
        return failn(err, BTF_E_FORMAT, name, "format version %u.%u (expected major version %d "
                     "or %d%s)", major, minor, FMT_MAJOR, FMT_MAJOR_MAP,
                     major > FMT_MAJOR_MAP ? "; a newer btfcar reads it" : "");
    *major_out = major;
    if (size > MAX_FILE_BYTES)
        return failn(err, BTF_E_FORMAT, name, "%zu bytes (expected at most %zu)", size,
                     MAX_FILE_BYTES);
    size_t hdr = get_u16(data + 15);
    unsigned comp = data[17];
    size_t raw_n = get_u32(data + 18), stored_n = get_u32(data + 22);
    if (hdr < HEADER_BYTES)
        return failn(err, BTF_E_FORMAT, name, "header of %zu bytes (expected at least %d)", hdr,
                     HEADER_BYTES);
    uint64_t total = (uint64_t)hdr + stored_n + CRC_BYTES;
    if ((uint64_t)size < total)
        return failn(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected %llu)", size,
                     (unsigned long long)total);
    if ((uint64_t)size > total)
        return failn(err, BTF_E_FORMAT, name, "%llu bytes after the end (expected %llu in all)",
                     (unsigned long long)(size - total), (unsigned long long)total);
    uint32_t want = get_u32(data + size - CRC_BYTES);
    uint32_t got = (uint32_t)crc32(0L, data, (uInt)(size - CRC_BYTES));
    if (want != got)
        return failn(err, BTF_E_FORMAT, name, "CRC-32 mismatch, the file is corrupt (expected "
                     "%08x, computed %08x)", (unsigned)want, (unsigned)got);
    if (raw_n > MAX_PAYLOAD_BYTES)
        return failn(err, BTF_E_FORMAT, name, "payload of %zu bytes (expected at most %zu)",
                     raw_n, MAX_PAYLOAD_BYTES);
    if (comp == COMP_STORED) {
        if (raw_n != stored_n)
            return failn(err, BTF_E_FORMAT, name, "stored payload of %zu bytes declared as %zu "
                         "(expected equal sizes)", stored_n, raw_n);
        *payload = data + hdr, *payload_n = raw_n;
        return BTF_OK;
    }
    if (comp != COMP_ZLIB)
        return failn(err, BTF_E_FORMAT, name, "compression method %u (expected 0 stored or 1 "
                     "zlib)", comp);
    if ((uint64_t)raw_n > (uint64_t)stored_n * ZLIB_MAX_RATIO + 64)
        return failn(err, BTF_E_FORMAT, name, "payload of %zu bytes from %zu compressed "
                     "(expected at most %u:1)", raw_n, stored_n, ZLIB_MAX_RATIO);
    unsigned char *p = btf_alloc(raw_n ? raw_n : 1, 1, NULL);
    if (!p)
        return failn(err, BTF_E_NOMEM, name, "out of memory inflating %zu bytes", raw_n);
    uLongf out_n = (uLongf)raw_n;
    uLong used = (uLong)stored_n;
    int zr = uncompress2(p, &out_n, data + hdr, &used);
    if (zr != Z_OK || out_n != raw_n || used != stored_n) {
        free(p);
        return zr == Z_MEM_ERROR
                   ? failn(err, BTF_E_NOMEM, name, "out of memory inflating the payload")
                   : failn(err, BTF_E_FORMAT, name, "corrupt compressed payload (expected a "
                           "zlib stream of %zu bytes giving %zu)", stored_n, raw_n);
    }
    *owned = p, *payload = p, *payload_n = raw_n;
    return BTF_OK;
}

typedef struct span {
    const unsigned char *p;
    size_t n;
    int present;
} span;

static btf_status read_dirset(const span *s, const char *what, const char *name, btf_dirset *d,
                              btf_error *err)
{
    if (s->n < 3)
        return failn(err, BTF_E_FORMAT, name, "%s section of %zu bytes (expected at least 3)",
                     what, s->n);
    size_t len = s->p[0];
    if (len > 31 || s->n < 1 + len + 2)
        return failn(err, BTF_E_FORMAT, name, "%s: name of %zu bytes in a section of %zu "
                     "(expected at most 31)", what, len, s->n);
    for (size_t i = 0; i < len; i++) /* a NUL inside would shorten the name written back */
        if (s->p[1 + i] < 0x20 || s->p[1 + i] > 0x7e)
            return failn(err, BTF_E_FORMAT, name, "%s: name byte %zu is 0x%02x (expected "
                         "printable ASCII)", what, i, s->p[1 + i]);
    memcpy(d->name, s->p + 1, len);
    d->name[len] = 0;
    size_t count = get_u16(s->p + 1 + len);
    if (count < 1 || count > MAX_DIRS || s->n != 1 + len + 2 + 16 * count)
        return failn(err, BTF_E_FORMAT, name, "%s: %zu directions in %zu bytes (expected 1..%d "
                     "directions of 16 bytes)", what, count, s->n, MAX_DIRS);
    d->dirs = btf_alloc(count, sizeof(btf_dir), NULL);
    if (!d->dirs)
        return failn(err, BTF_E_NOMEM, name, "out of memory reading the %s", what);
    d->count = (int)count;
    const unsigned char *q = s->p + 1 + len + 2;
    for (size_t i = 0; i < count; i++)
        d->dirs[i].theta = get_f64(q + 16 * i), d->dirs[i].phi = get_f64(q + 16 * i + 8);
    return BTF_OK;
}

/* RFMP (format 2): the map, every shift checked against the sample. */
static btf_status read_map(const span *s, const char *name, btf_rf_model *m, btf_error *err)
{
    if (s->n < RFMP_HEAD || s->p[0] != RFMP_VERSION)
        return failn(err, BTF_E_FORMAT, name, "RFMP section of %zu bytes, version %d (expected "
                     "at least %d bytes, version %d)", s->n, s->n ? s->p[0] : -1, RFMP_HEAD,
                     RFMP_VERSION);
    uint32_t sw = get_u32(s->p + 1), sh = get_u32(s->p + 5);
    uint32_t x0 = get_u32(s->p + 9), y0 = get_u32(s->p + 13);
    if (sw < 1 || sw > BTF_RF_MAX_SURFACE_SIDE || sh < 1 || sh > BTF_RF_MAX_SURFACE_SIDE ||
        x0 > (uint32_t)(MAX_SIDE - m->width) || y0 > (uint32_t)(MAX_SIDE - m->height))
        return failn(err, BTF_E_FORMAT, name, "coordinate map of %ux%u texels, sample at (%u, "
                     "%u) (expected sides 1..%d, a place within %d texels)", sw, sh, x0, y0,
                     BTF_RF_MAX_SURFACE_SIDE, MAX_SIDE);
    size_t n = (size_t)sw * sh;
    if (s->n != RFMP_HEAD + 4 * n)
        return failn(err, BTF_E_FORMAT, name, "RFMP section of %zu bytes (expected %zu for a "
                     "%ux%u map)", s->n, RFMP_HEAD + 4 * n, sw, sh);
    m->map = btf_alloc(n, 2 * sizeof(uint16_t), NULL);
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

/* A section tag for a message: printable ASCII, anything else '?', so
 * that the message stays one line. */
static const char *tag_text(const unsigned char *p, char buf[5])
{
    for (int i = 0; i < 4; i++)
        buf[i] = p[i] >= 0x20 && p[i] < 0x7f ? (char)p[i] : '?';
    buf[4] = 0;
    return buf;
}

static btf_status decode_payload(const unsigned char *p, size_t n, const char *name,
                                 unsigned major, btf_rf_model *m, btf_error *err)
{
    char tag[5];
    span sec[S_COUNT];
    memset(sec, 0, sizeof sec);
    size_t at = 0;
    while (at < n) {
        if (n - at < 8)
            return failn(err, BTF_E_FORMAT, name, "truncated section header at payload byte %zu "
                         "(expected 8 bytes)", at);
        size_t len = get_u32(p + at + 4);
        if (len > n - at - 8)
            return failn(err, BTF_E_FORMAT, name, "section '%s' of %zu bytes at payload byte "
                         "%zu runs past the payload (expected at most %zu bytes)",
                         tag_text(p + at, tag), len, at, n - at - 8);
        for (int s = 0; s < S_COUNT; s++)
            if (!memcmp(p + at, TAGS[s], 4)) {
                if (sec[s].present)
                    return failn(err, BTF_E_FORMAT, name, "section %s twice (expected once)",
                                 TAGS[s]);
                sec[s] = (span){p + at + 8, len, 1};
            }
        at += 8 + len;
    }
    for (int s = 0; s < S_REQUIRED; s++)
        if (!sec[s].present)
            return failn(err, BTF_E_FORMAT, name, "no %s section (expected every one of VIEW, "
                         "LGHT, RFHD, RFQR, RFCD)", TAGS[s]);
    if (sec[S_RFMP].present != (major == FMT_MAJOR_MAP))
        return failn(err, BTF_E_FORMAT, name, "format %u %s an RFMP section (expected one in "
                     "format %d, a sampled model, and none in format %d)", major,
                     sec[S_RFMP].present ? "with" : "without", FMT_MAJOR_MAP, FMT_MAJOR);
    btf_status rc;
    if ((rc = read_dirset(&sec[S_VIEW], "views", name, &m->views, err)) ||
        (rc = read_dirset(&sec[S_LGHT], "lights", name, &m->lights, err)))
        return rc;
    const span *h = &sec[S_RFHD];
    if (h->n < RFHD_BYTES)
        return failn(err, BTF_E_FORMAT, name, "RFHD section of %zu bytes (expected %d)", h->n,
                     RFHD_BYTES);
    m->fit = h->p[0], m->lobes = h->p[1];
    m->params = (int)get_u16(h->p + 2), m->slots = (int)get_u16(h->p + 4);
    uint32_t w = get_u32(h->p + 6), ht = get_u32(h->p + 10), fields = get_u32(h->p + 14);
    if (w < 1 || w > MAX_SIDE || ht < 1 || ht > MAX_SIDE || fields < 1 || fields > MAX_DIRS ||
        m->slots < 1 || m->slots > BTF_RF_MAX_SLOTS)
        return failn(err, BTF_E_FORMAT, name, "%ux%u texels, %u fields, %d slots (expected sides "
                     "1..%d, 1..%d fields, 1..%d slots)", w, ht, fields, m->slots, MAX_SIDE,
                     MAX_DIRS, BTF_RF_MAX_SLOTS);
    m->width = (int)w, m->height = (int)ht, m->fields = (int)fields;
    size_t planes = (size_t)fields * m->slots, texels = (size_t)w * ht;
    if (sec[S_RFQR].n != planes * 8)
        return failn(err, BTF_E_FORMAT, name, "RFQR section of %zu bytes (expected %zu: %zu "
                     "ranges)", sec[S_RFQR].n, planes * 8, planes);
    /* planes <= 4096 x 23 and texels <= 2^32: the product fits 64 bits */
    if ((uint64_t)sec[S_RFCD].n != (uint64_t)planes * texels * 2)
        return failn(err, BTF_E_FORMAT, name, "RFCD section of %zu bytes (expected %llu: %zu "
                     "fields x %d slots x %ux%u texels x 2)", sec[S_RFCD].n,
                     (unsigned long long)planes * texels * 2, (size_t)fields, m->slots, w, ht);
    m->lo = btf_alloc(planes, sizeof(float), NULL);
    m->hi = btf_alloc(planes, sizeof(float), NULL);
    m->codes = btf_alloc(planes * texels, sizeof(uint16_t), NULL);
    if (!m->lo || !m->hi || !m->codes)
        return failn(err, BTF_E_NOMEM, name, "out of memory for %zu parameter codes",
                     planes * texels);
    for (size_t i = 0; i < planes; i++)
        m->lo[i] = get_f32(sec[S_RFQR].p + 8 * i), m->hi[i] = get_f32(sec[S_RFQR].p + 8 * i + 4);
    const unsigned char *cd = sec[S_RFCD].p;
    for (size_t pl = 0; pl < planes; pl++) {
        size_t f = pl / m->slots, s = pl % m->slots;
        uint16_t *q = m->codes + f * texels * m->slots + s;
        const unsigned char *lo = cd + pl * texels * 2, *hi = lo + texels;
        for (size_t t = 0; t < texels; t++)
            q[t * m->slots] = (uint16_t)(lo[t] | hi[t] << 8);
    }
    if (sec[S_RFMP].present && (rc = read_map(&sec[S_RFMP], name, m, err)))
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
    if (!data && size)
        return failn(err, BTF_E_ARG, name, "no data");
    const unsigned char *payload = NULL;
    size_t n = 0;
    unsigned char *owned = NULL;
    unsigned major = 0;
    btf_status rc = open_container(data ? data : (const unsigned char *)"", size, name,
                                   &payload, &n, &owned, &major, err);
    if (rc == BTF_OK)
        rc = decode_payload(payload, n, name, major, out, err);
    free(owned);
    if (rc)
        btf_rf_model_free(out);
    return rc;
}

btf_status btf_rf_read(const char *path, btf_rf_model *out, btf_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out)
        return btf_fail(err, BTF_E_ARG, "btf_rf_read: no path or no output model");
    unsigned char *data;
    size_t n;
    btf_status rc = btf_read_file(path, MAX_FILE_BYTES, &data, &n, err);
    if (rc)
        return rc;
    rc = btf_rf_decode(data, n, path, out, err);
    free(data);
    return rc;
}
