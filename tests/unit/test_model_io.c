/*
 * test_model_io.c — the model file MODEL.btfcar (src/model/model_file.c,
 * model_check.c, docs/model-format.md): bit-exact round trips, rejection of truncated,
 * corrupt, foreign and future files, every validation rule (each bad file
 * built with a correct CRC by an independent writer of the documented
 * layout), atomic writing, the encoded size of a realistic model, the EXR
 * provenance of a model's subspace, and `btfcar info MODEL [--json]`.
 */
#include "testutil.h"
#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <zlib.h>


/* ------------------------------------------------------- building models */

static float urand(btf_rng *r, float lo, float hi)
{
    return lo + (hi - lo) * (float)btf__rng_uniform(r);
}

static int irand(btf_rng *r, int lo, int hi) /* [lo, hi] */
{
    return lo + (int)(btf__rng_next(r) % (uint64_t)(hi - lo + 1));
}

/* Causal offsets in the order a neighbourhood search would grow them. */
static const btf_offset FAMILY[] = {{0, -1}, {-1, 0},  {-1, -1}, {-1, 1}, {0, -2}, {-2, 0},
                                    {-2, -1}, {-2, 1}, {-1, -2}, {-1, 2}, {0, -3}, {-3, 0}};

/* A random rotation (Gram-Schmidt on random vectors, in double), so the
 * float basis is orthonormal to rounding. */
static void random_basis(btf_rng *r, float basis[9])
{
    double v[3][3];
    for (int i = 0; i < 3; i++) {
        for (;;) {
            for (int k = 0; k < 3; k++)
                v[i][k] = btf__rng_uniform(r) * 2.0 - 1.0;
            for (int j = 0; j < i; j++) {
                double d = v[i][0] * v[j][0] + v[i][1] * v[j][1] + v[i][2] * v[j][2];
                for (int k = 0; k < 3; k++)
                    v[i][k] -= d * v[j][k];
            }
            double len = sqrt(v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2]);
            if (len > 0.1) {
                for (int k = 0; k < 3; k++)
                    v[i][k] /= len;
                break;
            }
        }
    }
    for (int i = 0; i < 9; i++)
        basis[i] = (float)v[i / 3][i % 3];
}

static void make_subspace(btf_subspace_model *sm, btf_rng *r, int view, int light, int levels,
                          int nmin, int nmax)
{
    memset(sm, 0, sizeof *sm);
    sm->view = view;
    sm->light = light;
    sm->width = 256;
    sm->height = 192;
    for (int c = 0; c < 3; c++)
        sm->mean[c] = urand(r, 0.0f, 1.0f);
    random_basis(r, sm->basis);
    sm->levels = levels;
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < levels; l++) {
            btf_car_band *cb = &sm->bands[b][l];
            cb->n = irand(r, nmin, nmax);
            double sum = 0.0;
            for (int i = 0; i < cb->n; i++) {
                cb->offsets[i] = FAMILY[i];
                cb->gamma[i] = urand(r, -0.3f, 0.3f);
                sum += fabs(cb->gamma[i]);
            }
            /* Stable, as fitting makes them (the validator checks): sum |gamma| < 1. */
            for (int i = 0; i < cb->n && sum >= 0.95; i++)
                cb->gamma[i] = (float)(cb->gamma[i] * 0.95 / sum);
            cb->sigma = urand(r, 0.0f, 0.05f);
            cb->mean = b == 0 ? urand(r, -0.01f, 0.01f) : 0.0f;
        }
}

/* Smooth periodic heights: a few random low-frequency waves, in texels. */
static void smooth_heights(float *h, int w, int ht, btf_rng *r)
{
    const double pi = 3.14159265358979323846;
    double amp[6], ph[6];
    int fx[6], fy[6];
    for (int i = 0; i < 6; i++) {
        amp[i] = btf__rng_uniform(r) * 2.0;
        ph[i] = btf__rng_uniform(r) * 2.0 * pi;
        fx[i] = irand(r, 0, 3);
        fy[i] = irand(r, 0, 3);
    }
    for (int y = 0; y < ht; y++)
        for (int x = 0; x < w; x++) {
            double v = 0.0;
            for (int i = 0; i < 6; i++)
                v += amp[i] * sin(2.0 * pi * (fx[i] * x / (double)w + fy[i] * y / (double)ht) + ph[i]);
            h[(size_t)y * w + x] = (float)v;
        }
}

typedef struct model_spec {
    int subspaces, levels, nmin, nmax;
    int directions;      /* 0: a texture; 1: ubo81; 2: tiny custom sets */
    int range_w, range_h;
    uint64_t seed;
} model_spec;

static void tiny_dirsets(btf_model *m)
{
    btf_error e = {0};
    btf_dir v[3] = {{0, 0}, {30, 0}, {30, 180}}, l[2] = {{0, 0}, {45, 90}};
    TU_OK(btf_dirset_from_list(&m->views, v, 3, &e), &e);
    TU_OK(btf_dirset_from_list(&m->lights, l, 2, &e), &e);
    snprintf(m->lights.name, sizeof m->lights.name, "tiny");
}

/* The index of a segmentation: subspaces follow the rings of both
 * directions and their azimuth difference, as k-means clusters do. */
static void plausible_index(btf_model *m)
{
    int nv = m->views.count, nl = m->lights.count;
    m->index = malloc((size_t)nv * nl);
    assert_non_null(m->index);
    for (int v = 0; v < nv; v++)
        for (int l = 0; l < nl; l++) {
            btf_dir dv = m->views.dirs[v], dl = m->lights.dirs[l];
            double dphi = fabs(fmod(dv.phi - dl.phi + 540.0, 360.0) - 180.0);
            int id = (int)(dv.theta / 15) * 3 + (int)(dl.theta / 30) + (dphi > 90.0) * 7;
            m->index[(size_t)v * nl + l] = (uint8_t)(id % m->n_subspaces);
        }
}

static void make_model(btf_model *m, const model_spec *s)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    btf_rng r;
    btf__rng_seed(&r, s->seed);
    if (s->directions == 1) {
        TU_OK(btf_dirset_ubo81(&m->views, &e), &e);
        TU_OK(btf_dirset_ubo81(&m->lights, &e), &e);
    } else if (s->directions == 2) {
        tiny_dirsets(m);
    }
    m->n_subspaces = s->subspaces;
    if (s->directions)
        plausible_index(m);
    m->subspaces = calloc((size_t)s->subspaces, sizeof *m->subspaces);
    assert_non_null(m->subspaces);
    for (int i = 0; i < s->subspaces; i++) {
        int v = s->directions ? irand(&r, 0, m->views.count - 1) : -1;
        int l = s->directions ? irand(&r, 0, m->lights.count - 1) : -1;
        make_subspace(&m->subspaces[i], &r, v, l, s->levels, s->nmin, s->nmax);
    }
    if (s->range_w) {
        m->range_width = s->range_w;
        m->range_height = s->range_h;
        m->range_texel = 4.0f;
        m->range = malloc(sizeof(float) * (size_t)s->range_w * s->range_h);
        assert_non_null(m->range);
        smooth_heights(m->range, s->range_w, s->range_h, &r);
    }
}

static const model_spec SMALL = {2, 2, 2, 4, 0, 0, 0, 11};
static const model_spec RICH = {5, 4, 0, 12, 2, 9, 7, 12};

static void assert_dirsets_equal(const btf_dirset *a, const btf_dirset *b)
{
    assert_int_equal(a->count, b->count);
    assert_string_equal(a->name, b->name);
    for (int i = 0; i < a->count; i++) {
        assert_true(a->dirs[i].theta == b->dirs[i].theta);
        assert_true(a->dirs[i].phi == b->dirs[i].phi);
    }
}

static void assert_bands_equal(const btf_car_band *a, const btf_car_band *b)
{
    assert_int_equal(a->n, b->n);
    for (int i = 0; i < a->n; i++) {
        assert_int_equal(a->offsets[i].row, b->offsets[i].row);
        assert_int_equal(a->offsets[i].col, b->offsets[i].col);
        assert_memory_equal(&a->gamma[i], &b->gamma[i], sizeof(float));
    }
    assert_memory_equal(&a->sigma, &b->sigma, sizeof(float));
    assert_memory_equal(&a->mean, &b->mean, sizeof(float));
}

/* Every field equal; the range heights exactly (range_tol 0) or within a
 * tolerance (the first encoding quantises them). */
static void assert_models_equal(const btf_model *a, const btf_model *b, double range_tol)
{
    assert_dirsets_equal(&a->views, &b->views);
    assert_dirsets_equal(&a->lights, &b->lights);
    assert_int_equal(a->n_subspaces, b->n_subspaces);
    assert_int_equal(!a->index, !b->index);
    if (a->index)
        assert_memory_equal(a->index, b->index, (size_t)a->views.count * a->lights.count);
    for (int s = 0; s < a->n_subspaces; s++) {
        const btf_subspace_model *x = &a->subspaces[s], *y = &b->subspaces[s];
        assert_int_equal(x->view, y->view);
        assert_int_equal(x->light, y->light);
        assert_int_equal(x->width, y->width);
        assert_int_equal(x->height, y->height);
        assert_memory_equal(x->mean, y->mean, sizeof x->mean);
        assert_memory_equal(x->basis, y->basis, sizeof x->basis);
        assert_int_equal(x->levels, y->levels);
        for (int band = 0; band < 3; band++)
            for (int l = 0; l < x->levels; l++)
                assert_bands_equal(&x->bands[band][l], &y->bands[band][l]);
    }
    assert_int_equal(a->range_width, b->range_width);
    assert_int_equal(a->range_height, b->range_height);
    assert_int_equal(!a->range, !b->range);
    if (!a->range)
        return;
    assert_true(a->range_texel == b->range_texel);
    size_t n = (size_t)a->range_width * a->range_height;
    for (size_t i = 0; i < n; i++) {
        if (range_tol == 0.0)
            assert_memory_equal(&a->range[i], &b->range[i], sizeof(float));
        else
            assert_true(fabs((double)a->range[i] - b->range[i]) <= range_tol);
    }
}

static void range_bounds(const btf_model *m, float *lo, float *hi)
{
    size_t n = (size_t)m->range_width * m->range_height;
    *lo = *hi = m->range[0];
    for (size_t i = 1; i < n; i++) {
        *lo = m->range[i] < *lo ? m->range[i] : *lo;
        *hi = m->range[i] > *hi ? m->range[i] : *hi;
    }
}

/* ------------------------------------- an independent writer of the layout */

typedef struct tbuf {
    unsigned char *p;
    size_t n, cap;
} tbuf;

static void tb_put(tbuf *b, const void *src, size_t n)
{
    if (b->cap - b->n < n) {
        b->cap = (b->cap + n) * 2;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
    memcpy(b->p + b->n, src, n);
    b->n += n;
}

static void tb_u8(tbuf *b, unsigned v)
{
    unsigned char c = (unsigned char)v;
    tb_put(b, &c, 1);
}

static void tb_u16(tbuf *b, unsigned v)
{
    tb_u8(b, v & 0xFF);
    tb_u8(b, (v >> 8) & 0xFF);
}

static void tb_u32(tbuf *b, uint32_t v)
{
    tb_u16(b, v & 0xFFFF);
    tb_u16(b, v >> 16);
}

static void tb_f32(tbuf *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    tb_u32(b, v);
}

static void tb_f64(tbuf *b, double f)
{
    uint64_t v;
    memcpy(&v, &f, 8);
    tb_u32(b, (uint32_t)v);
    tb_u32(b, (uint32_t)(v >> 32));
}

static size_t tb_section(tbuf *b, const char *tag)
{
    tb_put(b, tag, 4);
    tb_u32(b, 0);
    return b->n;
}

static void tb_end(tbuf *b, size_t body)
{
    uint32_t len = (uint32_t)(b->n - body);
    for (int i = 0; i < 4; i++)
        b->p[body - 4 + i] = (unsigned char)(len >> (8 * i));
}

static void tw_dirset(tbuf *b, const char *tag, const btf_dirset *s)
{
    size_t body = tb_section(b, tag);
    size_t len = strnlen(s->name, sizeof s->name);
    tb_u8(b, (unsigned)len);
    tb_put(b, s->name, len);
    tb_u16(b, (unsigned)s->count);
    for (int i = 0; i < s->count; i++) {
        tb_f64(b, s->dirs[i].theta);
        tb_f64(b, s->dirs[i].phi);
    }
    tb_end(b, body);
}

/* VIEW, LGHT, INDX and SUBS exactly as docs/model-format.md lays them out,
 * without any validation: the way to build bad files. */
static void tw_payload(tbuf *b, const btf_model *m)
{
    if (m->views.count || m->lights.count) {
        tw_dirset(b, "VIEW", &m->views);
        tw_dirset(b, "LGHT", &m->lights);
        size_t body = tb_section(b, "INDX");
        tb_put(b, m->index, (size_t)m->views.count * m->lights.count);
        tb_end(b, body);
    }
    size_t body = tb_section(b, "SUBS");
    tb_u16(b, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_subspace_model *sm = &m->subspaces[s];
        tb_u16(b, (unsigned)sm->view & 0xFFFF);
        tb_u16(b, (unsigned)sm->light & 0xFFFF);
        tb_u32(b, (uint32_t)sm->width);
        tb_u32(b, (uint32_t)sm->height);
        for (int c = 0; c < 3; c++)
            tb_f32(b, sm->mean[c]);
        for (int i = 0; i < 9; i++)
            tb_f32(b, sm->basis[i]);
        tb_u8(b, (unsigned)sm->levels & 0xFF);
        for (int band = 0; band < 3; band++)
            for (int l = 0; l < sm->levels && l < BTF_MAX_LEVELS; l++) {
                const btf_car_band *cb = &sm->bands[band][l];
                tb_u8(b, (unsigned)cb->n & 0xFF);
                for (int i = 0; i < cb->n && i < BTF_CAR_MAX_NEIGHBOURS; i++) {
                    tb_u8(b, (unsigned)(uint8_t)cb->offsets[i].row);
                    tb_u8(b, (unsigned)(uint8_t)cb->offsets[i].col);
                }
                for (int i = 0; i < cb->n && i < BTF_CAR_MAX_NEIGHBOURS; i++)
                    tb_f32(b, cb->gamma[i]);
                tb_f32(b, cb->sigma);
                tb_f32(b, cb->mean);
            }
    }
    tb_end(b, body);
}

/* A RANG section from quantised heights q (predictor residuals computed
 * here, as the format describes); flags -1: the 1.0 layout, which ends
 * before the flags byte, else the 1.1 layout with that flags byte. */
static void tw_range(tbuf *b, int w, int h, float texel, int e, int32_t k, const uint16_t *q,
                     int flags)
{
    size_t n = (size_t)w * h;
    unsigned char *planes = malloc(2 * n);
    assert_non_null(planes);
    for (size_t i = 0; i < n; i++) {
        int x = (int)(i % (size_t)w), y = (int)(i / (size_t)w);
        long p = 0;
        if (y == 0)
            p = x ? q[i - 1] : 0;
        else if (x == 0)
            p = q[i - w];
        else
            p = (long)q[i - 1] + q[i - w] - q[i - w - 1];
        p = p < 0 ? 0 : p > 65535 ? 65535 : p;
        long d = ((long)q[i] - p) & 0xFFFF;
        long s = d >= 0x8000 ? d - 0x10000 : d;
        unsigned z = (unsigned)(s >= 0 ? 2 * s : -2 * s - 1);
        planes[i] = (unsigned char)(z & 0xFF);
        planes[n + i] = (unsigned char)(z >> 8);
    }
    size_t body = tb_section(b, "RANG");
    tb_u16(b, (unsigned)w);
    tb_u16(b, (unsigned)h);
    tb_f32(b, texel);
    tb_u16(b, (unsigned)e & 0xFFFF);
    tb_u32(b, (uint32_t)k);
    tb_put(b, planes, 2 * n);
    if (flags >= 0) {
        unsigned char f = (unsigned char)flags;
        tb_put(b, &f, 1);
    }
    tb_end(b, body);
    free(planes);
}

static uint32_t crc_of(const unsigned char *p, size_t n)
{
    return (uint32_t)crc32(0L, p, (uInt)n);
}

static void fix_crc(unsigned char *file, size_t size)
{
    uint32_t c = crc_of(file, size - 4);
    for (int i = 0; i < 4; i++)
        file[size - 4 + i] = (unsigned char)(c >> (8 * i));
}

static const unsigned char SIG[11] = {0x89, 'B', 'T', 'F', 'C', 'A', 'R', '\r', '\n', 0x1a, '\n'};

/* Header, payload (stored, or deflated when comp is 1) and a correct CRC. */
static unsigned char *tw_wrap(const unsigned char *payload, size_t n, unsigned major,
                              unsigned minor, unsigned comp, size_t *size)
{
    uLongf zn = compressBound((uLong)n);
    unsigned char *f = malloc(26 + zn + 4);
    assert_non_null(f);
    if (comp == 1)
        assert_int_equal(compress2(f + 26, &zn, payload, (uLong)n, 9), Z_OK);
    else {
        memcpy(f + 26, payload, n);
        zn = (uLongf)n;
    }
    memcpy(f, SIG, 11);
    unsigned char hdr[15] = {(unsigned char)major, (unsigned char)(major >> 8), (unsigned char)minor,
                             (unsigned char)(minor >> 8), 26, 0, (unsigned char)comp};
    for (int i = 0; i < 4; i++) {
        hdr[7 + i] = (unsigned char)(n >> (8 * i));
        hdr[11 + i] = (unsigned char)(zn >> (8 * i));
    }
    memcpy(f + 11, hdr, 15);
    *size = 26 + zn + 4;
    fix_crc(f, *size);
    return f;
}

/* The payload of a file of size bytes (inflated if need be), for editing:
 * the container's 26-byte head and CRC lie around it. */
static unsigned char *payload_of_file(const unsigned char *f, size_t size, size_t *n)
{
    assert_true(size >= 30);
    return tu_model_payload(f, n);
}

static void free_model(btf_model *m)
{
    btf_model_free(m);
}

/* ------------------------------------------------------------ assertions */

/* A decode failure: BTF_E_FORMAT, one line "bad.btfcar: ... (expected ...)"
 * containing needle, and nothing left in the model. */
static void expect_format_error(const unsigned char *data, size_t n, const char *needle)
{
    btf_model m;
    btf_error e = {0};
    int rc = btf_model_decode(data, n, "bad.btfcar", &m, &e);
    if (rc != BTF_E_FORMAT || (needle && !strstr(e.msg, needle)))
        print_error("expected a format error with '%s', got %d: %s\n", needle ? needle : "",
                    rc, e.msg);
    assert_int_equal(rc, BTF_E_FORMAT);
    assert_int_equal(e.code, BTF_E_FORMAT);
    assert_int_equal(strncmp(e.msg, "bad.btfcar: ", 12), 0);
    assert_null(strchr(e.msg, '\n'));
    assert_non_null(strstr(e.msg, "(expected"));
    if (needle)
        assert_non_null(strstr(e.msg, needle));
    assert_null(m.subspaces);
    assert_null(m.index);
    assert_null(m.range);
    assert_null(m.views.dirs);
    assert_int_equal(m.n_subspaces, 0);
}

static unsigned char *encode_ok(const btf_model *m, size_t *n)
{
    unsigned char *d = NULL;
    btf_error e = {0};
    TU_OK(btf_model_encode(m, &d, n, &e), &e);
    return d;
}

static void decode_ok(const unsigned char *d, size_t n, btf_model *m)
{
    btf_error e = {0};
    TU_OK(btf_model_decode(d, n, "test", m, &e), &e);
}

/* ------------------------------------------------------------ round trips */

/* encode -> decode -> encode gives the same bytes; the second decode gives
 * the same model, bit for bit; the first keeps every field but the range
 * heights exactly, and those within the documented bound. */
static void check_round_trip(const model_spec *spec)
{
    btf_model m, d1, d2;
    make_model(&m, spec);
    size_t n1, n2;
    unsigned char *b1 = encode_ok(&m, &n1);
    decode_ok(b1, n1, &d1);
    double tol = 0.0;
    if (m.range) {
        float lo, hi;
        range_bounds(&m, &lo, &hi);
        tol = (hi - lo) / 65535.0;
    }
    assert_models_equal(&m, &d1, m.range ? tol : 0.0);
    unsigned char *b2 = encode_ok(&d1, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(b1, b2, n1);
    decode_ok(b2, n2, &d2);
    assert_models_equal(&d1, &d2, 0.0);
    /* The decoder fills unused slots with zeros: the structs compare whole. */
    assert_memory_equal(d1.subspaces, d2.subspaces, sizeof *d1.subspaces * d1.n_subspaces);
    free(b1);
    free(b2);
    free_model(&m);
    free_model(&d1);
    free_model(&d2);
}

static void round_trip_rich(void **state)
{
    (void)state;
    check_round_trip(&RICH);
    model_spec ubo = {7, 3, 1, 8, 1, 32, 32, 99};
    check_round_trip(&ubo);
}

static void round_trip_texture(void **state)
{
    (void)state;
    check_round_trip(&SMALL);
    btf_model m, d;
    make_model(&m, &SMALL);
    size_t n;
    unsigned char *b = encode_ok(&m, &n);
    decode_ok(b, n, &d);
    assert_int_equal(d.views.count, 0);
    assert_int_equal(d.lights.count, 0);
    assert_null(d.index);
    assert_null(d.range);
    assert_int_equal(d.subspaces[0].view, -1);
    assert_int_equal(d.subspaces[1].light, -1);
    free(b);
    free_model(&m);
    free_model(&d);
}

/* Heights on a grid round-trip exactly; a constant map, huge and tiny
 * magnitudes and single samples keep the documented error bound. */
static void range_quantisation(void **state)
{
    (void)state;
    const float cases[][4] = {
        {0.0f, 0.0f, 0.0f, 0.0f},          {1.0f, 1.0f, 1.0f, 1.0f},
        {-3.0f, 2.5f, 1e-3f, 0.25f},       {1e6f, 1e6f + 1.0f, 1e6f, 1e6f},
        {1e-30f, -1e-30f, 0.0f, 3e-31f},   {-1e30f, 1e30f, 0.0f, 5.0f},
        {100.0f, 100.5f, 100.25f, 100.125f}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        btf_model m, d, d2;
        make_model(&m, &SMALL);
        m.range_width = 2;
        m.range_height = 2;
        m.range_texel = 1.5f;
        m.range = malloc(4 * sizeof(float));
        memcpy(m.range, cases[c], sizeof cases[c]);
        size_t n;
        unsigned char *b = encode_ok(&m, &n);
        decode_ok(b, n, &d);
        float lo, hi;
        range_bounds(&m, &lo, &hi);
        double amax = fmax(fabs(lo), fabs(hi));
        double bound = fmax((hi - lo) / 65535.0, amax * ldexp(1.0, -22));
        bound = fmax(bound, ldexp(1.0, -149));
        for (int i = 0; i < 4; i++)
            if (!(fabs((double)d.range[i] - m.range[i]) <= bound))
                fail_msg("case %zu: %g -> %g (bound %g)", c, m.range[i], d.range[i], bound);
        size_t n2;
        unsigned char *b2 = encode_ok(&d, &n2);
        assert_int_equal(n, n2);
        assert_memory_equal(b, b2, n);
        decode_ok(b2, n2, &d2);
        assert_memory_equal(d.range, d2.range, 4 * sizeof(float));
        free(b);
        free(b2);
        free_model(&m);
        free_model(&d);
        free_model(&d2);
    }
}

/* The independent writer produces the library's payload byte for byte: the
 * documented layout is the implemented one. */
static void layout_matches_document(void **state)
{
    (void)state;
    model_spec spec = RICH;
    spec.range_w = 0;
    spec.range_h = 0;
    btf_model m;
    make_model(&m, &spec);
    size_t n, pn;
    unsigned char *b = encode_ok(&m, &n);
    assert_memory_equal(b, SIG, 11);
    assert_int_equal(b[11] | b[12] << 8, 1); /* major */
    assert_int_equal(b[13] | b[14] << 8, 0); /* minor */
    assert_int_equal(b[15] | b[16] << 8, 26);
    unsigned char *p = payload_of_file(b, n, &pn);
    tbuf t = {0};
    tw_payload(&t, &m);
    assert_int_equal(t.n, pn);
    assert_memory_equal(t.p, p, pn);
    free(t.p);
    free(p);
    free(b);
    free_model(&m);
}

/* ------------------------------------------------------ damaged and foreign */

static unsigned char *small_file(size_t *n)
{
    model_spec spec = {1, 1, 1, 2, 2, 3, 2, 5};
    btf_model m;
    make_model(&m, &spec);
    unsigned char *b = encode_ok(&m, n);
    free_model(&m);
    return b;
}

static void truncation_at_every_length(void **state)
{
    (void)state;
    size_t n;
    unsigned char *b = small_file(&n);
    for (size_t len = 0; len < n; len++) {
        /* A copy of exactly len bytes, so ASan sees any read past the end. */
        unsigned char *c = malloc(len ? len : 1);
        memcpy(c, b, len);
        expect_format_error(c, len, "truncated");
        free(c);
    }
    btf_model m;
    decode_ok(b, n, &m);
    free_model(&m);
    free(b);
}

static void bit_flips_fail_the_crc(void **state)
{
    (void)state;
    size_t n;
    unsigned char *b = small_file(&n);
    for (size_t i = 0; i < n; i++)
        for (int bit = 0; bit < 8; bit++) {
            b[i] ^= (unsigned char)(1u << bit);
            /* Flips in the signature, version or sizes are caught before the
             * CRC, by name; anywhere else the CRC names them. */
            int early = i < 13 || (i >= 15 && i < 17) || (i >= 22 && i < 26);
            expect_format_error(b, n, early ? NULL : "CRC-32 mismatch");
            b[i] ^= (unsigned char)(1u << bit);
        }
    free(b);
}

static void foreign_files(void **state)
{
    (void)state;
    const unsigned char png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13,
                                 'I',  'H', 'D', 'R', 0,    0,    0,    1,    0, 0, 0, 1};
    expect_format_error(png, sizeof png, "not a btfcar model");
    const char *text = "hello, this is a text file\n";
    expect_format_error((const unsigned char *)text, strlen(text), "not a btfcar model");
    expect_format_error((const unsigned char *)"", 0, "truncated");
    /* A text-mode transfer turned CR LF into LF. */
    size_t n;
    unsigned char *b = small_file(&n);
    unsigned char *t = malloc(n);
    memcpy(t, b, 7);
    memcpy(t + 7, b + 8, n - 8);
    expect_format_error(t, n - 1, "text-mode");
    free(t);
    /* Trailing bytes after the CRC. */
    unsigned char *longer = malloc(n + 3);
    memcpy(longer, b, n);
    memset(longer + n, 0, 3);
    expect_format_error(longer, n + 3, "after the end");
    free(longer);
    free(b);
}

static void versions(void **state)
{
    (void)state;
    size_t n, pn, fn;
    unsigned char *b = small_file(&n);
    unsigned char *p = payload_of_file(b, n, &pn);
    /* A future major version: rejected with a clear message, even though
     * the CRC is right. */
    unsigned char *f = tw_wrap(p, pn, 2, 0, 0, &fn);
    expect_format_error(f, fn, "newer than this reader");
    free(f);
    f = tw_wrap(p, pn, 0, 9, 0, &fn);
    expect_format_error(f, fn, "major version 1");
    free(f);
    /* A newer minor version that appended a header field, a field at the end
     * of SUBS and a section of its own: read, the additions ignored. */
    btf_model ref, m;
    decode_ok(b, n, &ref);
    tbuf t = {0};
    tb_put(&t, p, pn);
    size_t body = tb_section(&t, "NEWS");
    tb_put(&t, "future", 6);
    tb_end(&t, body);
    f = tw_wrap(t.p, t.n, 1, 7, 1, &fn);
    decode_ok(f, fn, &m);
    assert_models_equal(&ref, &m, 0.0);
    free_model(&m);
    free(f);
    /* The header grew by 2 bytes in "1.1". */
    f = tw_wrap(p, pn, 1, 1, 0, &fn);
    unsigned char *g = malloc(fn + 2);
    memcpy(g, f, 26);
    g[15] = 28;
    g[26] = 0xAB;
    g[27] = 0xCD;
    memcpy(g + 28, f + 26, fn - 26);
    fix_crc(g, fn + 2);
    decode_ok(g, fn + 2, &m);
    assert_models_equal(&ref, &m, 0.0);
    free_model(&m);
    free(g);
    free(f);
    free(t.p);
    free_model(&ref);
    free(p);
    free(b);
}

static void container_rules(void **state)
{
    (void)state;
    size_t n, pn, fn;
    unsigned char *b = small_file(&n);
    unsigned char *p = payload_of_file(b, n, &pn);
    unsigned char *f = tw_wrap(p, pn, 1, 0, 0, &fn);
    /* Unknown compression method. */
    f[17] = 7;
    fix_crc(f, fn);
    expect_format_error(f, fn, "compression method 7");
    /* Stored payload whose declared size differs. */
    f[17] = 0;
    f[18] ^= 1;
    fix_crc(f, fn);
    expect_format_error(f, fn, "stored payload");
    f[18] ^= 1;
    /* A header shorter than version 1.0's. */
    f[15] = 20;
    fix_crc(f, fn);
    expect_format_error(f, fn, "header of 20 bytes");
    free(f);
    /* A corrupt zlib stream under a correct CRC. */
    f = tw_wrap(p, pn, 1, 0, 1, &fn);
    f[30] ^= 0x55;
    f[31] ^= 0x55;
    fix_crc(f, fn);
    expect_format_error(f, fn, "compressed payload");
    free(f);
    /* A zlib stream that inflates to more, or less, than declared. */
    f = tw_wrap(p, pn, 1, 0, 1, &fn);
    f[18] = (unsigned char)(f[18] - 1);
    fix_crc(f, fn);
    expect_format_error(f, fn, "compressed payload");
    f[18] = (unsigned char)(f[18] + 2);
    fix_crc(f, fn);
    expect_format_error(f, fn, "compressed payload");
    /* A claimed payload far beyond what deflate can produce. */
    f[21] = 0x03;
    fix_crc(f, fn);
    expect_format_error(f, fn, NULL);
    free(f);
    free(p);
    free(b);
}

/* ------------------------------------------------------- validation rules */

typedef void (*mutator)(btf_model *m);

/* The small model with views, lights and index, mutated, written by the
 * independent writer with a correct CRC: the decoder must refuse it, naming
 * the problem; the encoder must refuse the model in memory. */
static void expect_rejected(mutator f, const char *needle)
{
    model_spec spec = {2, 2, 2, 4, 2, 0, 0, 21};
    btf_model m;
    make_model(&m, &spec);
    f(&m);
    tbuf t = {0};
    tw_payload(&t, &m);
    size_t fn;
    unsigned char *file = tw_wrap(t.p, t.n, 1, 0, 1, &fn);
    expect_format_error(file, fn, needle);
    unsigned char *d = NULL;
    size_t dn = 0;
    btf_error e = {0};
    int rc = btf_model_encode(&m, &d, &dn, &e);
    assert_int_equal(rc, BTF_E_DATA);
    assert_null(d);
    assert_non_null(strstr(e.msg, needle));
    free(file);
    free(t.p);
    free_model(&m);
}

static void m_noncausal(btf_model *m) { m->subspaces[1].bands[2][1].offsets[0] = (btf_offset){0, 1}; }
static void m_centre(btf_model *m) { m->subspaces[0].bands[0][0].offsets[1] = (btf_offset){0, 0}; }
static void m_below(btf_model *m) { m->subspaces[0].bands[1][0].offsets[0] = (btf_offset){1, -1}; }
static void m_duplicate(btf_model *m)
{
    m->subspaces[0].bands[0][1].offsets[1] = m->subspaces[0].bands[0][1].offsets[0];
}
static void m_too_many(btf_model *m) { m->subspaces[0].bands[0][0].n = BTF_CAR_MAX_NEIGHBOURS + 1; }

static void offsets_and_neighbourhoods(void **state)
{
    (void)state;
    expect_rejected(m_noncausal, "offset 0:1 is not causal");
    expect_rejected(m_centre, "offset 0:0 is not causal");
    expect_rejected(m_below, "offset 1:-1 is not causal");
    expect_rejected(m_duplicate, "appears twice");
    expect_rejected(m_too_many, "25 neighbours");
}

static void m_nan_gamma(btf_model *m) { m->subspaces[1].bands[1][1].gamma[1] = NAN; }
static void m_inf_sigma(btf_model *m) { m->subspaces[0].bands[2][0].sigma = INFINITY; }
static void m_neg_sigma(btf_model *m) { m->subspaces[0].bands[2][0].sigma = -0.5f; }
static void m_nan_band_mean(btf_model *m) { m->subspaces[1].bands[0][0].mean = NAN; }
static void m_nan_mean(btf_model *m) { m->subspaces[0].mean[2] = NAN; }
static void m_inf_basis(btf_model *m) { m->subspaces[0].basis[4] = -INFINITY; }
static void m_skew_basis(btf_model *m) { m->subspaces[1].basis[0] += 0.1f; }
/* Finite, but beyond BTF_MODEL_MAX_VALUE: synthesis would overflow float. */
static void m_huge_sigma(btf_model *m) { m->subspaces[0].bands[2][0].sigma = 1e37f; }
static void m_huge_band_mean(btf_model *m) { m->subspaces[1].bands[0][1].mean = -3e38f; }
static void m_huge_mean(btf_model *m) { m->subspaces[1].mean[1] = 2e30f; }

/* The bound itself is a model: sigma, band mean and colour mean of 1e30
 * encode and decode to the same values. */
static void values_at_the_bound_accepted(void)
{
    model_spec spec = {2, 2, 2, 4, 2, 0, 0, 21};
    btf_model m, back;
    make_model(&m, &spec);
    m.subspaces[0].bands[2][0].sigma = BTF_MODEL_MAX_VALUE;
    m.subspaces[1].bands[0][1].mean = -BTF_MODEL_MAX_VALUE;
    m.subspaces[1].mean[1] = BTF_MODEL_MAX_VALUE;
    size_t n;
    unsigned char *b = encode_ok(&m, &n);
    decode_ok(b, n, &back);
    assert_true(back.subspaces[0].bands[2][0].sigma == BTF_MODEL_MAX_VALUE);
    assert_true(back.subspaces[1].bands[0][1].mean == -BTF_MODEL_MAX_VALUE);
    assert_true(back.subspaces[1].mean[1] == BTF_MODEL_MAX_VALUE);
    free(b);
    btf_model_free(&back);
    free_model(&m);
}

static void floats(void **state)
{
    (void)state;
    expect_rejected(m_nan_gamma, "gamma[1] is nan");
    expect_rejected(m_inf_sigma, "sigma is inf");
    expect_rejected(m_neg_sigma, "sigma is -0.5");
    expect_rejected(m_nan_band_mean, "mean is nan");
    expect_rejected(m_nan_mean, "mean[2] is nan");
    expect_rejected(m_inf_basis, "basis[4] is -inf");
    expect_rejected(m_skew_basis, "orthonormal");
    expect_rejected(m_huge_sigma, "subspace 0, band 2, level 0: sigma is 1e+37 (expected a "
                                  "number in 0..1e+30");
    expect_rejected(m_huge_band_mean, "subspace 1, band 0, level 1: mean is -3e+38 (expected a "
                                      "number of magnitude at most 1e+30");
    expect_rejected(m_huge_mean, "subspace 1: mean[1] is 2e+30");
    values_at_the_bound_accepted();
}

static void m_levels0(btf_model *m) { m->subspaces[1].levels = 0; }
static void m_levels9(btf_model *m) { m->subspaces[1].levels = BTF_MAX_LEVELS + 1; }
static void m_width0(btf_model *m) { m->subspaces[0].width = 0; }
static void m_huge(btf_model *m) { m->subspaces[0].height = (1 << 20) + 1; }
static void m_index(btf_model *m) { m->index[4] = 2; }
static void m_view(btf_model *m) { m->subspaces[0].view = 3; }
static void m_light(btf_model *m) { m->subspaces[1].light = -2; }
static void m_half_texture(btf_model *m) { m->subspaces[1].view = -1; }
static void m_subspaces0(btf_model *m) { m->n_subspaces = 0; }

static void counts_and_indices(void **state)
{
    (void)state;
    expect_rejected(m_levels0, "0 pyramid levels");
    expect_rejected(m_levels9, "9 pyramid levels");
    expect_rejected(m_width0, "size 0 x 192");
    expect_rejected(m_huge, "1..1048576");
    expect_rejected(m_index, "subspace 2 (expected < 2, or 255: not measured)");
    expect_rejected(m_view, "representative (view 3");
    expect_rejected(m_light, "light -2");
    expect_rejected(m_half_texture, "representative (view -1");
    expect_rejected(m_subspaces0, "0 subspaces");
}

static void m_theta(btf_model *m) { m->views.dirs[1].theta = 90.5; }
static void m_phi(btf_model *m) { m->lights.dirs[1].phi = 360.0; }
static void m_nan_dir(btf_model *m) { m->lights.dirs[0].theta = NAN; }
static void m_name(btf_model *m) { m->views.name[2] = '\t'; }

static void directions(void **state)
{
    (void)state;
    expect_rejected(m_theta, "theta 90.5");
    expect_rejected(m_phi, "phi 360");
    expect_rejected(m_nan_dir, "theta nan");
    expect_rejected(m_name, "byte 0x09");
}

/* Section-level damage with a correct CRC. */
static void sections(void **state)
{
    (void)state;
    model_spec spec = {2, 2, 2, 4, 2, 0, 0, 21};
    btf_model m;
    make_model(&m, &spec);
    tbuf full = {0};
    tw_payload(&full, &m);
    size_t fn;
    unsigned char *f;
    /* Each section's offset in the payload, from the layout. */
    size_t view = 0, lght = view + 8 + full.p[view + 4], indx = lght + 8 + full.p[lght + 4];
    size_t subs = indx + 8 + full.p[indx + 4];
    assert_memory_equal(full.p + subs, "SUBS", 4);
    /* Only VIEW and LGHT, no INDX. */
    f = tw_wrap(full.p, indx, 1, 0, 0, &fn);
    expect_format_error(f, fn, "INDX absent");
    free(f);
    /* No SUBS at all. */
    f = tw_wrap(full.p, subs, 1, 0, 0, &fn);
    expect_format_error(f, fn, "no SUBS section");
    free(f);
    /* SUBS twice. */
    tbuf t = {0};
    tb_put(&t, full.p, full.n);
    tb_put(&t, full.p + subs, full.n - subs);
    f = tw_wrap(t.p, t.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "SUBS appears twice");
    free(f);
    free(t.p);
    /* A section length past the end of the payload. */
    unsigned char saved = full.p[subs + 6];
    full.p[subs + 6] = 0x10;
    f = tw_wrap(full.p, full.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "section at payload offset");
    free(f);
    full.p[subs + 6] = saved;
    /* A section cut short: SUBS (the last one) loses its last 3 bytes. */
    uint32_t len = full.p[subs + 4] | full.p[subs + 5] << 8;
    t = (tbuf){0};
    tb_put(&t, full.p, full.n - 3);
    t.p[subs + 4] = (unsigned char)(len - 3);
    t.p[subs + 5] = (unsigned char)((len - 3) >> 8);
    f = tw_wrap(t.p, t.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "section SUBS is truncated");
    free(f);
    free(t.p);
    /* A dangling partial section header. */
    t = (tbuf){0};
    tb_put(&t, full.p, full.n);
    tb_put(&t, "RAN", 3);
    f = tw_wrap(t.p, t.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "truncated section header");
    free(f);
    free(t.p);
    /* A direction set of 0 directions; a set name of 40 bytes. */
    t = (tbuf){0};
    size_t body = tb_section(&t, "VIEW");
    tb_u8(&t, 1);
    tb_put(&t, "x", 1);
    tb_u16(&t, 0);
    tb_end(&t, body);
    tb_put(&t, full.p + lght, full.n - lght);
    f = tw_wrap(t.p, t.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "0 directions");
    free(f);
    t.p[8] = 40;
    f = tw_wrap(t.p, t.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "set name of 40 bytes");
    free(f);
    free(t.p);
    /* A NUL inside a set name ("t\0ny"): a name that would be written back
     * shorter, so not the one read (found by fuzz_model's round trip). */
    assert_int_equal(full.p[lght + 8], 4);
    assert_memory_equal(full.p + lght + 9, "tiny", 4);
    full.p[lght + 10] = 0;
    f = tw_wrap(full.p, full.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "section LGHT: set name has byte 0x00 at 1");
    free(f);
    full.p[lght + 10] = 0xc3;
    f = tw_wrap(full.p, full.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "set name has byte 0xc3 at 1 (expected printable ASCII)");
    free(f);
    full.p[lght + 10] = 'i';
    /* 257 subspaces. */
    full.p[subs + 8] = 1;
    full.p[subs + 9] = 1;
    f = tw_wrap(full.p, full.n, 1, 0, 0, &fn);
    expect_format_error(f, fn, "257 subspaces");
    free(f);
    free(full.p);
    free_model(&m);
}

/* A RANG section appended to a valid texture payload; q NULL: the section
 * stops after its fixed fields. */
static void expect_bad_range(int w, int h, float texel, int e, int32_t k, const uint16_t *q,
                             const char *needle)
{
    btf_model m;
    make_model(&m, &SMALL);
    tbuf t = {0};
    tw_payload(&t, &m);
    if (q) {
        tw_range(&t, w, h, texel, e, k, q, 1);
    } else {
        size_t body = tb_section(&t, "RANG");
        tb_u16(&t, (unsigned)w);
        tb_u16(&t, (unsigned)h);
        tb_f32(&t, texel);
        tb_u16(&t, (unsigned)e & 0xFFFF);
        tb_u32(&t, (uint32_t)k);
        tb_end(&t, body);
    }
    size_t fn;
    unsigned char *f = tw_wrap(t.p, t.n, 1, 0, 1, &fn);
    expect_format_error(f, fn, needle);
    free(f);
    free(t.p);
    free_model(&m);
}

static void range_rules(void **state)
{
    (void)state;
    const uint16_t ok[2] = {0, 40000}, coarse[2] = {0, 20000}, lifted[2] = {5, 40000};
    /* The valid case, for reference. */
    {
        btf_model m, d;
        make_model(&m, &SMALL);
        tbuf t = {0};
        tw_payload(&t, &m);
        tw_range(&t, 2, 1, 2.0f, 0, 0, ok, 1);
        size_t fn;
        unsigned char *f = tw_wrap(t.p, t.n, 1, 1, 1, &fn);
        decode_ok(f, fn, &d);
        assert_true(d.range[0] == 0.5f && d.range[1] == 40000.5f);
        free_model(&d);
        free(f);
        free(t.p);
        free_model(&m);
    }
    /* The same heights in the 1.0 layout: made periodic on reading. Two
     * samples side by side are a slope, which no periodic tile keeps
     * (btf_range_make_periodic removes the mean slope first): the tile
     * becomes flat at its mean. */
    {
        btf_model m, d;
        make_model(&m, &SMALL);
        tbuf t = {0};
        tw_payload(&t, &m);
        tw_range(&t, 2, 1, 2.0f, 0, 0, ok, -1);
        size_t fn;
        unsigned char *f = tw_wrap(t.p, t.n, 1, 0, 1, &fn);
        decode_ok(f, fn, &d);
        assert_float_equal(d.range[0], 20000.5f, 1e-2);
        assert_float_equal(d.range[1], 20000.5f, 1e-2);
        free_model(&d);
        free(f);
        free(t.p);
        free_model(&m);
    }
    expect_bad_range(2, 1, 2.0f, 0, 0, coarse, "not canonical");
    expect_bad_range(2, 1, 2.0f, 0, 0, lifted, "not canonical");
    expect_bad_range(2, 1, 2.0f, 1 - 150, 0, ok, "grid 2^-149");
    expect_bad_range(2, 1, 2.0f, 106, 0, ok, "grid 2^106");
    expect_bad_range(2, 1, 2.0f, 0, 1 << 23, ok, "offset 8388608");
    expect_bad_range(2, 1, 2.0f, 0, (1 << 23) - 100, ok, "exceeds 2^23");
    expect_bad_range(2, 1, NAN, 0, 0, ok, "texel nan");
    expect_bad_range(2, 1, 0.0f, 0, 0, ok, "texel 0");
    expect_bad_range(0, 1, 2.0f, 0, 0, ok, "size 0 x 1");
    expect_bad_range(4096, 4097, 2.0f, 0, 0, NULL, "at most 16777216 samples");
}

/* The mean jump across the tile's wrap-around edges (last column to first,
 * last row to first) over the mean step between neighbours inside: about 1
 * for a periodic tile, large for a tile with a trend. */
static double wrap_jump_ratio(const float *t, int w, int h)
{
    double wrap = 0.0, inside = 0.0;
    long nw = 0, ni = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double v = t[(size_t)y * w + x];
            double r = t[(size_t)y * w + (x + 1) % w], d = t[(size_t)((y + 1) % h) * w + x];
            if (x == w - 1)
                wrap += fabs(r - v), nw++;
            else
                inside += fabs(r - v), ni++;
            if (y == h - 1)
                wrap += fabs(d - v), nw++;
            else
                inside += fabs(d - v), ni++;
        }
    return (wrap / nw) / (inside / ni);
}

/* A model file of format 1.0 (tests/data/model-v1.0.btfcar, written by the
 * 1.0 writer from `btfcar analyse` of a 32-pixel leather) reads, its range
 * tile converted to a periodic one; written again it is a 1.1 file that
 * reads back to the same model, bit for bit. */
static void old_version_file(void **state)
{
    (void)state;
    const char *path = "tests/data/model-v1.0.btfcar";
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("%s: not found (run the test from the repository root)", path);
    unsigned char hdr[15];
    assert_int_equal(fread(hdr, 1, sizeof hdr, f), sizeof hdr);
    fclose(f);
    assert_int_equal(hdr[11] | hdr[12] << 8, 1);
    assert_int_equal(hdr[13] | hdr[14] << 8, 0); /* the old version indeed */
    btf_model m, d;
    btf_error e = {0};
    TU_OK(btf_model_read(path, &m, &e), &e);
    assert_non_null(m.range);
    assert_int_equal(m.range_width, 16);
    assert_int_equal(m.range_height, 16);
    double ratio = wrap_jump_ratio(m.range, m.range_width, m.range_height);
    print_message("format 1.0 tile after conversion: wrap jump / inside step = %.3f\n", ratio);
    assert_true(ratio <= 1.5);
    /* Written again: quantised once more (within the documented bound),
     * then a fixed point, bytes and model. */
    float lo, hi;
    range_bounds(&m, &lo, &hi);
    size_t n, n2;
    unsigned char *b = encode_ok(&m, &n);
    assert_int_equal(b[13] | b[14] << 8, 1);
    decode_ok(b, n, &d);
    assert_models_equal(&m, &d, (hi - lo) / 65535.0);
    btf_model d2;
    unsigned char *b2 = encode_ok(&d, &n2);
    assert_int_equal(n, n2);
    assert_memory_equal(b, b2, n);
    decode_ok(b2, n2, &d2);
    assert_models_equal(&d, &d2, 0.0);
    free(b);
    free(b2);
    free_model(&m);
    free_model(&d);
    free_model(&d2);
}

/* A non-periodic tile (a ramp with ripples) in the 1.0 layout is read as
 * btf_range_make_periodic makes it; in the 1.1 layout (flag set) it is read
 * as it is. The conversion keeps the ripples: in the middle of the tile,
 * where the cross-fade keeps mostly the tile itself, the converted tile
 * correlates with the ramp-free ripples. */
static void format_1_0_tile_is_made_periodic(void **state)
{
    (void)state;
    enum { W = 12, H = 9 };
    uint16_t q[W * H];
    double ripple[W * H], v[W * H], lo = 1e300;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            ripple[y * W + x] = 300.0 * sin(1.3 * x + 0.4) * cos(0.9 * y);
            v[y * W + x] = 2500.0 * x + 1200.0 * y + ripple[y * W + x];
            lo = fmin(lo, v[y * W + x]);
        }
    /* min q 0 and a span over 2^15: the canonical grid is e = 0, k = 0 */
    for (int i = 0; i < W * H; i++)
        q[i] = (uint16_t)(v[i] - lo);
    for (int flags = -1; flags <= 1; flags += 2) {
        btf_model m, d;
        make_model(&m, &SMALL);
        tbuf t = {0};
        tw_payload(&t, &m);
        tw_range(&t, W, H, 2.0f, 0, 0, q, flags);
        size_t fn;
        unsigned char *f = tw_wrap(t.p, t.n, 1, flags < 0 ? 0 : 1, 1, &fn);
        decode_ok(f, fn, &d);
        float raw[W * H], want[W * H];
        for (int i = 0; i < W * H; i++)
            raw[i] = want[i] = (float)q[i] + 0.5f; /* the grid's values, e = k = 0 */
        btf_error e = {0};
        if (flags < 0)
            TU_OK(btf_range_make_periodic(want, W, H, &e), &e);
        assert_memory_equal(d.range, want, sizeof want);
        if (flags < 0) {
            assert_true(wrap_jump_ratio(raw, W, H) > 5.0);
            assert_true(wrap_jump_ratio(d.range, W, H) < 1.5);
            double sp = 0, sr = 0, spp = 0, srr = 0, spr = 0, mean_raw = 0, mean_p = 0;
            for (int i = 0; i < W * H; i++)
                mean_raw += raw[i], mean_p += d.range[i];
            assert_float_equal(mean_p / (W * H), mean_raw / (W * H), 1e-2);
            /* The middle half along both axes is mostly the tile itself (the
             * cross-fade's weight of the original is >= 0.7 there). */
            int cnt = 0;
            for (int y = H / 4; y < H - H / 4; y++)
                for (int x = W / 4; x < W - W / 4; x++) {
                    int i = y * W + x;
                    double a = d.range[i] - mean_p / (W * H), r = ripple[i];
                    sp += a, sr += r, spp += a * a, srr += r * r, spr += a * r;
                    cnt++;
                }
            double n = cnt, cov = spr / n - sp * sr / (n * n);
            double corr = cov / sqrt((spp / n - sp * sp / (n * n)) * (srr / n - sr * sr / (n * n)));
            print_message("converted tile vs its ripples: correlation %.3f\n", corr);
            assert_true(corr > 0.7);
        }
        free_model(&d);
        free(f);
        free(t.p);
        free_model(&m);
    }
}

/* The 1.1 layout as written: version 1.1 with a range map (1.0 without),
 * the RANG body ending in the flags byte 0x01 (periodic). */
static void range_layout_1_1(void **state)
{
    (void)state;
    model_spec spec = {1, 1, 1, 2, 0, 5, 3, 9};
    btf_model m;
    make_model(&m, &spec);
    size_t n, pn;
    unsigned char *b = encode_ok(&m, &n);
    assert_int_equal(b[13] | b[14] << 8, 1);
    unsigned char *p = payload_of_file(b, n, &pn);
    size_t pos = 0, found = 0;
    while (pos + 8 <= pn) {
        size_t len = p[pos + 4] | p[pos + 5] << 8 | p[pos + 6] << 16 | (size_t)p[pos + 7] << 24;
        if (!memcmp(p + pos, "RANG", 4)) {
            found = 1;
            assert_int_equal(len, 14 + 2 * 5 * 3 + 1);
            assert_int_equal(p[pos + 8 + len - 1], 0x01);
        }
        pos += 8 + len;
    }
    assert_true(found);
    free(p);
    free(b);
    free_model(&m);
}

/* The encoder refuses what the format cannot hold, writing nothing. */
static void encoder_rules(void **state)
{
    (void)state;
    btf_model m;
    make_model(&m, &SMALL);
    btf_error e = {0};
    unsigned char *d = (unsigned char *)1;
    size_t n = 1;
    /* A range map with a NaN, and one spanning nearly the float range. */
    float bad[2] = {0.0f, NAN};
    m.range_width = 2;
    m.range_height = 1;
    m.range_texel = 1.0f;
    m.range = bad;
    assert_int_equal(btf_model_encode(&m, &d, &n, &e), BTF_E_DATA);
    assert_null(d);
    assert_int_equal(n, 0);
    assert_non_null(strstr(e.msg, "height 1 is nan"));
    bad[0] = -3e38f;
    bad[1] = 3e38f;
    assert_int_equal(btf_model_encode(&m, &d, &n, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "span too much"));
    m.range = NULL;
    assert_int_equal(btf_model_encode(&m, &d, &n, &e), BTF_E_DATA);
    m.range_width = m.range_height = 0;
    /* An index table without directions; directions without a table. */
    uint8_t idx[1] = {0};
    m.index = idx;
    assert_int_equal(btf_model_encode(&m, &d, &n, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "without directions"));
    m.index = NULL;
    const char *path = tu_fmt("%s/refused.btfcar", tu_dir);
    m.subspaces[0].bands[0][0].gamma[0] = NAN;
    assert_int_equal(btf_model_write(path, &m, &e), BTF_E_DATA);
    assert_int_equal(strncmp(e.msg, path, strlen(path)), 0);
    struct stat st;
    assert_int_not_equal(stat(path, &st), 0);
    assert_int_equal(btf_model_encode(NULL, &d, &n, &e), BTF_E_ARG);
    free_model(&m);
}

/* ------------------------------------------------------------------ files */

static void write_is_atomic(void **state)
{
    (void)state;
    char *sub = strdup(tu_fmt("%s/atomic", tu_dir));
    assert_int_equal(mkdir(sub, 0777), 0);
    btf_model m, r;
    make_model(&m, &RICH);
    btf_error e = {0};
    const char *path = tu_fmt("%s/m.btfcar", sub);
    char *p = strdup(path);
    tu_write_file(p, "old contents", 12);
    TU_OK(btf_model_write(p, &m, &e), &e);
    assert_int_equal(tu_count_files(sub), 1); /* replaced, no temporary left */
    TU_OK(btf_model_read(p, &r, &e), &e);
    assert_models_equal(&m, &r, 1e-3);
    free_model(&r);
    /* A folder that does not exist: an I/O error, nothing left behind. */
    assert_int_equal(btf_model_write(tu_fmt("%s/missing/m.btfcar", sub), &m, &e), BTF_E_IO);
    assert_int_equal(tu_count_files(sub), 1);
    assert_int_equal(btf_model_read(tu_fmt("%s/none.btfcar", sub), &r, &e), BTF_E_IO);
    assert_null(r.subspaces);
    /* A foreign file read by path names the path. */
    tu_write_file(p, "old contents", 12);
    assert_int_equal(btf_model_read(p, &r, &e), BTF_E_FORMAT);
    assert_int_equal(strncmp(e.msg, p, strlen(p)), 0);
    free(p);
    free(sub);
    free_model(&m);
}

/* The size of a whole 81 x 81 material: printed, and bounded loosely. */
static void realistic_size(void **state)
{
    (void)state;
    model_spec spec = {20, 3, 4, 8, 1, 64, 64, 2024};
    btf_model m;
    make_model(&m, &spec);
    size_t n;
    unsigned char *b = encode_ok(&m, &n);
    size_t pn;
    unsigned char *p = payload_of_file(b, n, &pn);
    /* The part of the range map alone, for the record. */
    btf_model nr = m;
    nr.range = NULL;
    nr.range_width = nr.range_height = 0;
    size_t n_norange;
    unsigned char *b2 = encode_ok(&nr, &n_norange);
    printf("model size: 81x81 ubo81, 20 subspaces x 3 bands x 3 levels x 4..8 neighbours, "
           "64x64 range: %zu bytes (payload %zu before deflate; %zu without the range map)\n",
           n, pn, n_norange);
    assert_true(n < 64 * 1024);
    free(b2);
    free(p);
    free(b);
    free_model(&m);
}

/* --------------------------------------------------------- btfcar info */

/* Runs a command line and returns its stdout (malloc'd). */
static char *capture(const char *cmd, int *status)
{
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 1 << 16, n = 0;
    char *out = malloc(cap);
    for (;;) {
        if (cap - n < 4096) {
            cap *= 2;
            out = realloc(out, cap);
        }
        size_t r = fread(out + n, 1, cap - n - 1, p);
        if (r == 0)
            break;
        n += r;
    }
    out[n] = 0;
    int st = pclose(p);
    *status = WIFEXITED(st) ? WEXITSTATUS(st) : 128;
    return out;
}

/* A strict JSON checker (RFC 8259 grammar, no extensions): enough to know
 * that `info --json` prints one valid document, without python. */
static const char *js_value(const char *p, int depth);

static const char *js_ws(const char *p)
{
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
        p++;
    return p;
}

static const char *js_string(const char *p)
{
    if (*p++ != '"')
        return NULL;
    while (*p != '"') {
        if ((unsigned char)*p < 0x20)
            return NULL;
        if (*p == '\\') {
            p++;
            if (*p == 'u') {
                for (int i = 1; i <= 4; i++)
                    if (!strchr("0123456789abcdefABCDEF", p[i]) || !p[i])
                        return NULL;
                p += 4;
            } else if (!*p || !strchr("\"\\/bfnrt", *p)) {
                return NULL;
            }
        }
        p++;
    }
    return p + 1;
}

static const char *js_digits(const char *p)
{
    if (*p < '0' || *p > '9')
        return NULL;
    while (*p >= '0' && *p <= '9')
        p++;
    return p;
}

static const char *js_number(const char *p)
{
    if (*p == '-')
        p++;
    if (*p == '0')
        p++;
    else if (!(p = js_digits(p)))
        return NULL;
    if (*p == '.' && !(p = js_digits(p + 1)))
        return NULL;
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-')
            p++;
        if (!(p = js_digits(p)))
            return NULL;
    }
    return p;
}

static const char *js_list(const char *p, int depth, char close, int members)
{
    p = js_ws(p + 1);
    if (*p == close)
        return p + 1;
    for (;;) {
        if (members) {
            if (!(p = js_string(p)))
                return NULL;
            p = js_ws(p);
            if (*p++ != ':')
                return NULL;
        }
        if (!(p = js_value(js_ws(p), depth + 1)))
            return NULL;
        p = js_ws(p);
        if (*p == close)
            return p + 1;
        if (*p++ != ',')
            return NULL;
        p = js_ws(p);
    }
}

static const char *js_value(const char *p, int depth)
{
    if (depth > 64)
        return NULL;
    if (*p == '{')
        return js_list(p, depth, '}', 1);
    if (*p == '[')
        return js_list(p, depth, ']', 0);
    if (*p == '"')
        return js_string(p);
    if (!strncmp(p, "true", 4))
        return p + 4;
    if (!strncmp(p, "false", 5))
        return p + 5;
    if (!strncmp(p, "null", 4))
        return p + 4;
    return js_number(p);
}

static int json_valid(const char *text)
{
    const char *p = js_value(js_ws(text), 0);
    return p && *js_ws(p) == '\0';
}

static int count_of(const char *text, const char *needle)
{
    int n = 0;
    for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

static void json_checker_works(void **state)
{
    (void)state;
    assert_true(json_valid("{\"a\":[1,-2.5e+3,0.25,true,null,\"x\\n\\u00e9\"],\"b\":{}}"));
    assert_false(json_valid("{\"a\":nan}"));
    assert_false(json_valid("{\"a\":[1,2}"));
    assert_false(json_valid("{\"a\":01}"));
    assert_false(json_valid("{\"a\":1}}"));
    assert_false(json_valid("{\"a\":\"x\ny\"}"));
    assert_false(json_valid("[1,]"));
}

static void info_model(void **state)
{
    (void)state;
    model_spec spec = {3, 2, 2, 4, 1, 16, 8, 77};
    btf_model m;
    make_model(&m, &spec);
    m.subspaces[1].bands[0][0].n = 2; /* FAMILY[0..1]: "0:-1,-1:0" */
    btf_error e = {0};
    char *path = strdup(tu_fmt("%s/info.btfcar", tu_dir));
    TU_OK(btf_model_write(path, &m, &e), &e);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    int status;
    char *out = capture(tu_fmt("%s info %s", tu_cli(), path), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "ubo81"));
    assert_non_null(strstr(out, "81 directions"));
    assert_non_null(strstr(out, "0:-1,-1:0"));
    assert_non_null(strstr(out, "16 x 8"));
    assert_non_null(strstr(out, tu_fmt("%lld bytes", (long long)st.st_size)));
    assert_non_null(strstr(out, "subspace 2"));
    free(out);
    out = capture(tu_fmt("%s info --json %s", tu_cli(), path), &status);
    assert_int_equal(status, 0);
    if (!json_valid(out))
        fail_msg("invalid JSON:\n%s", out);
    assert_non_null(strstr(out, "\"format\": \"btfcar-model\""));
    assert_non_null(strstr(out, "\"version\": [1, 1]")); /* 1.1: it has a range map */
    assert_non_null(strstr(out, tu_fmt("\"file_bytes\": %lld", (long long)st.st_size)));
    assert_int_equal(count_of(out, "\"name\": \"ubo81\""), 2);
    assert_int_equal(count_of(out, "\"count\": 81"), 2);
    assert_int_equal(count_of(out, "\"levels\":"), 3);
    assert_int_equal(count_of(out, "\"neighbourhood\":"), 3 * 3 * 2);
    assert_non_null(strstr(out, "\"neighbourhood\": \"0:-1,-1:0\""));
    assert_non_null(strstr(out, "\"offsets\": [[0, -1], [-1, 0]]"));
    assert_non_null(strstr(out, "\"range\": {\"width\": 16, \"height\": 8"));
    /* Floats print with enough digits to round-trip float32. */
    char g[64];
    snprintf(g, sizeof g, "\"sigma\": %.9g", (double)m.subspaces[0].bands[0][0].sigma);
    assert_non_null(strstr(out, g));
    free(out);
    /* A texture model: no directions, index or range map. */
    btf_model t;
    make_model(&t, &SMALL);
    TU_OK(btf_model_write(path, &t, &e), &e);
    out = capture(tu_fmt("%s info --json %s", tu_cli(), path), &status);
    assert_int_equal(status, 0);
    assert_true(json_valid(out));
    assert_non_null(strstr(out, "\"views\": null"));
    assert_non_null(strstr(out, "\"index\": null"));
    assert_non_null(strstr(out, "\"range\": null"));
    assert_int_equal(count_of(out, "\"levels\":"), 2);
    free(out);
    out = capture(tu_fmt("%s info %s", tu_cli(), path), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "texture"));
    free(out);
    /* A corrupt model: exit 1 and one line naming the file and the CRC. */
    unsigned char *data;
    size_t n;
    TU_OK(btf_model_encode(&t, &data, &n, &e), &e);
    data[n / 2] ^= 0x10;
    tu_write_file(path, data, n);
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s info %s >/dev/null", tu_cli(), path), &err), 1);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, "CRC-32"));
    assert_int_equal(count_of(err, "\n"), 1);
    free(err);
    out = capture(tu_fmt("%s info --help", tu_cli()), &status);
    assert_int_equal(status, 0);
    assert_non_null(strstr(out, "--json"));
    assert_non_null(strstr(out, "MODEL"));
    free(out);
    free(data);
    free(path);
    free_model(&t);
    free_model(&m);
}

/* `info --json` on a dataset: a summary document. */
static void info_dataset_json(void **state)
{
    (void)state;
    char *ds = strdup(tu_fmt("%s/tinyds", tu_dir));
    char *err = NULL;
    assert_int_equal(tu_run(tu_fmt("%s generate --quiet --material fabric --size 8 %s", tu_cli(),
                                   ds), &err), 0);
    free(err);
    int status;
    char *out = capture(tu_fmt("%s info --json --quiet %s", tu_cli(), ds), &status);
    assert_int_equal(status, 0);
    if (!json_valid(out))
        fail_msg("invalid JSON:\n%s", out);
    assert_non_null(strstr(out, "\"format\": \"btfcar-dataset\""));
    assert_non_null(strstr(out, "\"images\": 6561"));
    assert_non_null(strstr(out, "\"layout\": \"UBO2003\""));
    assert_int_equal(count_of(out, "\"count\": 81"), 2);
    free(out);
    tu_rmtree(ds);
    free(ds);
}

/* btf_model_exr_meta: a subspace's representative directions, none for a
 * texture or a subspace out of range. */
static void exr_meta_of_subspace(void **state)
{
    (void)state;
    btf_model m;
    make_model(&m, &RICH);
    for (int k = 0; k < m.n_subspaces; k++) {
        btf_exr_meta meta = btf_model_exr_meta(&m, "rich.btfcar", k, 99);
        assert_string_equal(meta.model, "rich.btfcar");
        assert_true(meta.seed == 99);
        assert_int_equal(meta.subspace, k);
        assert_int_equal(meta.has_dirs, 1);
        const btf_subspace_model *sm = &m.subspaces[k];
        assert_true(meta.view.theta == m.views.dirs[sm->view].theta);
        assert_true(meta.view.phi == m.views.dirs[sm->view].phi);
        assert_true(meta.light.theta == m.lights.dirs[sm->light].theta);
        assert_true(meta.light.phi == m.lights.dirs[sm->light].phi);
    }
    assert_int_equal(btf_model_exr_meta(&m, "x", m.n_subspaces, 1).has_dirs, 0);
    assert_int_equal(btf_model_exr_meta(&m, "x", -1, 1).has_dirs, 0);
    free_model(&m);
    make_model(&m, &SMALL);
    btf_exr_meta t = btf_model_exr_meta(&m, "tex.btfcar", 0, 5);
    assert_int_equal(t.has_dirs, 0);
    assert_string_equal(t.model, "tex.btfcar");
    free_model(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(round_trip_rich),
        cmocka_unit_test(round_trip_texture),
        cmocka_unit_test(range_quantisation),
        cmocka_unit_test(layout_matches_document),
        cmocka_unit_test(truncation_at_every_length),
        cmocka_unit_test(bit_flips_fail_the_crc),
        cmocka_unit_test(foreign_files),
        cmocka_unit_test(versions),
        cmocka_unit_test(container_rules),
        cmocka_unit_test(offsets_and_neighbourhoods),
        cmocka_unit_test(floats),
        cmocka_unit_test(counts_and_indices),
        cmocka_unit_test(directions),
        cmocka_unit_test(sections),
        cmocka_unit_test(range_rules),
        cmocka_unit_test(old_version_file),
        cmocka_unit_test(format_1_0_tile_is_made_periodic),
        cmocka_unit_test(range_layout_1_1),
        cmocka_unit_test(encoder_rules),
        cmocka_unit_test(write_is_atomic),
        cmocka_unit_test(realistic_size),
        cmocka_unit_test(json_checker_works),
        cmocka_unit_test(info_model),
        cmocka_unit_test(info_dataset_json),
        cmocka_unit_test(exr_meta_of_subspace),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
