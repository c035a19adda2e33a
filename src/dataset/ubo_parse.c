/*
 * ubo_parse.c — the header of a Bonn BTF database .btf file (UBO2014 and its
 * kin; docs/datasets.md, "UBO2014 .btf files"): the signature, chosen as
 * the longest one the file starts with (§1); the meta block and its size
 * self-check (§2a); the bidirectional sampling (§2b); width, height and
 * rotations (§2c); then the body of the variant: DFMF (§3), FMF (§4), PVF
 * (§5) or BDIF (§6). Nothing is copied: matrices are pointers into the
 * bytes, which the caller maps. Every count is checked against the bytes
 * that remain before it is used, so a truncated or lying file is one error
 * naming the file, the offset and the field; the file must end where the
 * parse ends (§8).
 */
#include <stdio.h>
#include "core/core.h"
#include "dataset/ubo2014.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A bounds-checked reader over the bytes. */
typedef struct cursor {
    const ubo_file *f;
    uint64_t pos;
    btf_error *err;
} cursor;

static btf_status truncated(cursor *c, const char *what, uint64_t need)
{
    return btf__fail(c->err, BTF_E_FORMAT,
                     "%s: truncated at byte %llu: %s needs %llu bytes, %llu remain (the file has "
                     "%llu)", c->f->name, (unsigned long long)c->pos, what,
                     (unsigned long long)need, (unsigned long long)(c->f->size - c->pos),
                     (unsigned long long)c->f->size);
}

static btf_status need(cursor *c, uint64_t n, const char *what)
{
    return n > c->f->size - c->pos ? truncated(c, what, n) : BTF_OK;
}

static btf_status get_u32(cursor *c, uint32_t *v, const char *what)
{
    btf_status rc = need(c, 4, what);
    if (rc)
        return rc;
    *v = ubo_rd32(c->f->data + c->pos);
    c->pos += 4;
    return BTF_OK;
}

static btf_status get_u8(cursor *c, uint32_t *v, const char *what)
{
    btf_status rc = need(c, 1, what);
    if (rc)
        return rc;
    *v = c->f->data[c->pos++];
    return BTF_OK;
}

static btf_status get_f32(cursor *c, float *v, int n, const char *what)
{
    btf_status rc = need(c, 4 * (uint64_t)n, what);
    if (rc)
        return rc;
    for (int i = 0; i < n; i++)
        v[i] = ubo_rdf32(c->f->data + c->pos + 4 * (uint64_t)i);
    c->pos += 4 * (uint64_t)n;
    return BTF_OK;
}

static btf_status skip(cursor *c, uint64_t n, const char *what)
{
    btf_status rc = need(c, n, what);
    if (rc == BTF_OK)
        c->pos += n;
    return rc;
}

/* §1: the signatures, longest first so that the first match is the longest. */
static const struct {
    const char *sig;
    int variant, rotations, extended;
} SIGS[] = {
    {"!DFMF08FCR", UBO_DFMF, 1, 0}, {"!FMF12FCER", UBO_FMF, 1, 1}, {"!BDIF06R2!", UBO_BDIF, 1, 0},
    {"!FMF06FCR", UBO_FMF, 1, 0},   {"!PVF06FCR", UBO_PVF, 1, 0},  {"!FMF06FC", UBO_FMF, 0, 0},
    {"!PVF06FC", UBO_PVF, 0, 0},
};

/* A text field of 80 bytes, NUL-padded, as a C string of printable bytes. */
static void text80(const unsigned char *p, char out[81])
{
    int n = 0;
    while (n < 80 && p[n])
        n++;
    for (int i = 0; i < n; i++)
        out[i] = (p[i] >= 32 && p[i] < 127) ? (char)p[i] : '?';
    out[n] = '\0';
}

/* §2a: the meta block, whose first field is its own size. */
static btf_status parse_meta(cursor *c, ubo_file *f)
{
    uint64_t start = c->pos;
    uint32_t meta_size, version;
    btf_status rc = get_u32(c, &meta_size, "the meta block's size");
    if (!rc)
        rc = get_u32(c, &version, "the meta block's version");
    if (!rc)
        rc = need(c, 240 + 4 + 12, "the meta block");
    if (rc)
        return rc;
    f->info.meta_version = (int)version;
    text80(f->data + c->pos, f->info.measurement_setup);
    text80(f->data + c->pos + 80, f->info.image_sensor);
    text80(f->data + c->pos + 160, f->info.light_source);
    c->pos += 240;
    rc = get_f32(c, &f->info.ppmm, 1, "ppmm");
    if (!rc)
        rc = get_f32(c, f->info.rgb_scale, 3, "rgb_scale_factor");
    uint32_t v = 0;
    if (!rc && version > 1)
        rc = get_u32(c, &v, "cosine_flag");
    f->info.cosine_flag = v != 0;
    if (!rc && version > 2) {
        rc = get_u32(c, &v, "the XML length");
        if (!rc)
            rc = skip(c, v, "the XML text");
    }
    f->nc = 3;
    if (!rc && version > 3) {
        rc = get_u32(c, &f->nc, "num_channels");
        for (uint32_t i = 0; !rc && i < f->nc; i++) {
            rc = get_u32(c, &v, "a channel name's length");
            if (!rc)
                rc = skip(c, v, "a channel name");
        }
    }
    if (rc)
        return rc;
    if (c->pos - start != meta_size)
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: meta block of version %u is %llu bytes long but says meta_size %u "
                         "(the notes' §2a check)", f->name, version,
                         (unsigned long long)(c->pos - start), meta_size);
    f->info.n_channels = (int)f->nc;
    return BTF_OK;
}

static btf_status check_angles(cursor *c, const float *tp, const char *what, uint32_t i)
{
    /* theta in [0, pi/2] (a hair over for float rounding), phi finite. */
    if (!isfinite(tp[0]) || !isfinite(tp[1]) || tp[0] < 0.0f || tp[0] > 1.5708f ||
        fabsf(tp[1]) > 100.0f)
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: %s direction %u has theta %g, phi %g radians: expected theta in "
                         "[0, pi/2] and a finite phi", c->f->name, what, i, tp[0], tp[1]);
    return BTF_OK;
}

/* §2b: the views, each with its light list; the first view's lights are
 * kept, the others must have as many (all readers require it). */
static btf_status parse_sampling(cursor *c, ubo_file *f)
{
    btf_status rc = get_u32(c, &f->nv, "the number of views");
    if (rc)
        return rc;
    /* Each view takes at least 12 bytes: a bound before any allocation. */
    if (f->nv == 0 || f->nv > (f->size - c->pos) / 12)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %u views do not fit the file's %llu bytes",
                         f->name, f->nv, (unsigned long long)f->size);
    f->view_rad = btf__alloc(f->nv, 2 * sizeof(float), c->err);
    if (!f->view_rad)
        return BTF_E_NOMEM;
    for (uint32_t v = 0; v < f->nv; v++) {
        uint32_t nl;
        rc = get_f32(c, f->view_rad + 2 * v, 2, "a view direction");
        if (!rc)
            rc = check_angles(c, f->view_rad + 2 * v, "view", v);
        if (!rc)
            rc = get_u32(c, &nl, "a view's number of lights");
        if (rc)
            return rc;
        if (v == 0) {
            if (nl == 0 || nl > (f->size - c->pos) / 8)
                return btf__fail(c->err, BTF_E_FORMAT,
                                 "%s: %u lights do not fit the file's %llu bytes", f->name, nl,
                                 (unsigned long long)f->size);
            f->nl = nl;
            f->light_rad = btf__alloc(nl, 2 * sizeof(float), c->err);
            if (!f->light_rad)
                return BTF_E_NOMEM;
            rc = get_f32(c, f->light_rad, 2 * (int)nl, "the light directions");
            for (uint32_t l = 0; !rc && l < nl; l++)
                rc = check_angles(c, f->light_rad + 2 * l, "light", l);
        } else if (nl != f->nl) {
            return btf__fail(c->err, BTF_E_FORMAT,
                             "%s: view %u has %u lights, view 0 has %u (the light count must be "
                             "the same for every view)", f->name, v, nl, f->nl);
        } else {
            rc = skip(c, 8 * (uint64_t)nl, "a view's light directions");
        }
        if (rc)
            return rc;
    }
    return BTF_OK;
}

static btf_status parse_rotations(cursor *c, ubo_file *f)
{
    uint32_t n;
    btf_status rc = get_u32(c, &n, "num_rotations");
    if (!rc)
        rc = skip(c, 36 * (uint64_t)n, "the rotations");
    f->info.rotations = (int)n;
    return rc;
}

static btf_status parse_size(cursor *c, ubo_file *f)
{
    btf_status rc = get_u32(c, &f->width, "width");
    if (!rc)
        rc = get_u32(c, &f->height, "height");
    if (rc)
        return rc;
    if (f->width < 1 || f->height < 1 || f->width > BTF_MAX_SIDE || f->height > BTF_MAX_SIDE)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: image size %ux%u: expected sides in 1..%d",
                         f->name, f->width, f->height, BTF_MAX_SIDE);
    return BTF_OK;
}

/* A matrix of rows x k scalars at the cursor, checked against the bytes left. */
static btf_status take_matrix(cursor *c, ubo_matrix *m, uint64_t rows, uint32_t k, int scalar,
                              const char *what)
{
    if (rows > UINT32_MAX)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %s has %llu rows", c->f->name, what,
                         (unsigned long long)rows);
    /* rows < 2^32, k < 2^32, scalar <= 8: the product fits 2^67 only in
     * theory; divide instead of multiplying. */
    uint64_t left = c->f->size - c->pos;
    if (k && rows > left / k / (uint64_t)scalar)
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: truncated: %s of %llu x %u values of %d bytes does not fit the %llu "
                         "bytes left at byte %llu (the file has %llu)", c->f->name, what,
                         (unsigned long long)rows, k, scalar, (unsigned long long)left,
                         (unsigned long long)c->pos, (unsigned long long)c->f->size);
    m->p = c->f->data + c->pos;
    m->rows = (uint32_t)rows;
    m->k = k;
    m->scalar = scalar;
    c->pos += rows * k * (uint64_t)scalar;
    return BTF_OK;
}

static btf_status check_scalar(cursor *c, uint32_t s)
{
    if (s != 2 && s != 4 && s != 8)
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: scalar size %u at byte %llu: expected 2 (half), 4 or 8", c->f->name,
                         s, (unsigned long long)(c->pos - 1));
    return BTF_OK;
}

/* The S, U and SxV of k components of `scalar` bytes that follow at the
 * cursor (U of rows, SxV of cols rows: DFMF's channel, FMF's matrix),
 * checked against the bytes left as one block, so that a short file is
 * told the length its header implies: exactly when the block ends the
 * file (last), else at least. */
static btf_status factors_fit(cursor *c, const char *what, uint32_t k, uint32_t scalar,
                              uint32_t rows, uint32_t cols, int last)
{
    uint64_t per = (uint64_t)scalar * (1 + (uint64_t)rows + cols); /* < 2^37 */
    uint64_t pos = c->pos, size = c->f->size, left = size - pos;
    if (k <= left / per)
        return BTF_OK;
    if (k > (UINT64_MAX - pos) / per) /* beyond 2^64 bytes */
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: truncated: %s (%u components of %u bytes: S, U of %u rows, SxV of "
                         "%u rows) does not fit the %llu bytes left at byte %llu (the file has "
                         "%llu)", c->f->name, what, k, scalar, rows, cols,
                         (unsigned long long)left, (unsigned long long)pos,
                         (unsigned long long)size);
    uint64_t bytes = k * per;
    return btf__fail(c->err, BTF_E_FORMAT,
                     "%s: truncated: %s (%u components of %u bytes: S, U of %u rows, SxV of %u "
                     "rows; %llu bytes from byte %llu) does not fit: expected a file of %s%llu "
                     "bytes, the file has %llu", c->f->name, what, k, scalar, rows, cols,
                     (unsigned long long)bytes, (unsigned long long)pos, last ? "" : "at least ",
                     (unsigned long long)(pos + bytes), (unsigned long long)size);
}

/* §3: DFMF, one U and one SxV per channel. */
static btf_status parse_dfmf(cursor *c, ubo_file *f)
{
    uint32_t kmax, model;
    btf_status rc = get_u32(c, &kmax, "num_components");
    if (!rc)
        rc = get_u32(c, &model, "color_model");
    if (!rc)
        rc = get_f32(c, f->colour_mean, 3, "color_mean");
    if (!rc)
        rc = get_f32(c, f->colour_transform, 9, "color_transform");
    if (rc)
        return rc;
    f->info.colour_model = (int)model;
    if (f->nc != 3)
        return btf__fail(c->err, BTF_E_UNSUPPORTED,
                         "%s: %u channels: only 3-channel (RGB) files are supported", f->name, f->nc);
    uint64_t lv = (uint64_t)f->nv * f->nl, px = (uint64_t)f->width * f->height;
    for (int ch = 0; ch < 3; ch++) {
        uint32_t s, k, rows, cols;
        rc = get_u8(c, &s, "a channel's scalar size");
        if (!rc)
            rc = check_scalar(c, s);
        if (!rc)
            rc = get_u32(c, &k, "a channel's components");
        if (!rc)
            rc = get_u32(c, &rows, "a channel's rows");
        if (!rc)
            rc = get_u32(c, &cols, "a channel's columns");
        if (rc)
            return rc;
        int tr = rows == px && cols == lv && !(rows == lv && cols == px);
        if (!tr && (rows != lv || cols != px))
            return btf__fail(c->err, BTF_E_FORMAT,
                             "%s: channel %d is %u x %u: expected %llu (views x lights) x %llu "
                             "(pixels) or the transpose", f->name, ch, rows, cols,
                             (unsigned long long)lv, (unsigned long long)px);
        if (k < 1)
            return btf__fail(c->err, BTF_E_FORMAT, "%s: channel %d has 0 components", f->name,
                             ch);
        if (ch > 0 && tr != f->transposed)
            return btf__fail(c->err, BTF_E_FORMAT,
                             "%s: channel %d's layout is transposed unlike channel 0's", f->name,
                             ch);
        f->transposed = tr;
        f->info.components[ch] = (int)k;
        if (ch == 0 || (int)s > f->info.scalar_size)
            f->info.scalar_size = (int)s;
        char what[24];
        snprintf(what, sizeof what, "DFMF channel %d", ch);
        rc = factors_fit(c, what, k, s, rows, cols, ch == 2);
        if (rc)
            return rc;
        ubo_matrix sv;
        rc = take_matrix(c, &sv, 1, k, (int)s, "the singular values");
        if (!rc)
            rc = take_matrix(c, &f->u[ch], rows, k, (int)s, "U");
        if (!rc)
            rc = take_matrix(c, &f->sxv[ch], cols, k, (int)s, "SxV");
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* §4: FMF, one matrix for all channels, rows (v*nL + l)*nC + c. */
static btf_status parse_fmf(cursor *c, ubo_file *f, int extended)
{
    btf_status rc = BTF_OK;
    if (extended) {
        uint32_t hv, drr = 0, a = 0, b = 0;
        rc = get_u8(c, &hv, "the FMF header version");
        if (!rc && hv >= 3)
            return btf__fail(c->err, BTF_E_UNSUPPORTED,
                             "%s: FMF header version %u is not supported (1 or 2)", f->name, hv);
        if (!rc && hv >= 1)
            rc = get_u32(c, &drr, "dynamic_range_reduction_method");
        if (!rc && hv >= 2) {
            rc = get_u32(c, &a, "the height map's first side");
            if (!rc)
                rc = get_u32(c, &b, "the height map's second side");
            if (!rc)
                rc = skip(c, 2 * (uint64_t)a * b, "the height map");
        }
        f->info.dynamic_range = drr != 0;
    }
    uint32_t kfile, s, k, rows, cols;
    if (!rc)
        rc = get_u32(c, &kfile, "num_components");
    if (!rc)
        rc = get_u8(c, &s, "the scalar size");
    if (!rc)
        rc = check_scalar(c, s);
    if (!rc)
        rc = get_u32(c, &k, "the components");
    if (!rc)
        rc = get_u32(c, &rows, "the rows");
    if (!rc)
        rc = get_u32(c, &cols, "the columns");
    if (rc)
        return rc;
    uint64_t lv = (uint64_t)f->nv * f->nl, px = (uint64_t)f->width * f->height;
    if (f->nc != 3)
        return btf__fail(c->err, BTF_E_UNSUPPORTED,
                         "%s: %u channels: only 3-channel (RGB) files are supported", f->name, f->nc);
    int tr = rows == 3 * px && cols == lv && !(rows == 3 * lv && cols == px);
    if (!tr && (rows != 3 * lv || cols != px))
        return btf__fail(c->err, BTF_E_FORMAT,
                         "%s: FMF matrix is %u x %u: expected %llu (3 x views x lights) x %llu "
                         "(pixels) or 3 x pixels x (views x lights)", f->name, rows, cols,
                         (unsigned long long)(3 * lv), (unsigned long long)px);
    if (k < 1)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: FMF matrix has 0 components", f->name);
    f->transposed = tr;
    f->info.scalar_size = (int)s;
    rc = factors_fit(c, "the FMF matrix", k, s, rows, cols, 1);
    if (rc)
        return rc;
    ubo_matrix sv;
    rc = take_matrix(c, &sv, 1, k, (int)s, "the singular values");
    if (!rc)
        rc = take_matrix(c, &f->u[0], rows, k, (int)s, "U");
    if (!rc)
        rc = take_matrix(c, &f->sxv[0], cols, k, (int)s, "SxV");
    /* §4: use min(K_file, K) components, at least 1. */
    uint32_t use = kfile < k ? kfile : k;
    f->info.components[0] = (int)(use < 1 ? 1 : use);
    return rc;
}

/* §5: PVF, one PCA per view slot. */
static btf_status parse_pvf_slots(cursor *c, ubo_file *f, uint32_t slots)
{
    if (slots != f->nv)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: %u PVF view slots for %u views", f->name,
                         slots, f->nv);
    f->slots = btf__calloc(slots, sizeof *f->slots, c->err);
    if (!f->slots)
        return BTF_E_NOMEM;
    f->num_slots = slots;
    uint64_t px = (uint64_t)f->width * f->height;
    for (uint32_t v = 0; v < slots; v++) {
        ubo_pvf_slot *sl = &f->slots[v];
        uint32_t s;
        btf_status rc = get_u8(c, &s, "a PVF slot's scalar size");
        if (!rc)
            rc = check_scalar(c, s);
        if (!rc)
            rc = get_u32(c, &sl->k, "a PVF slot's components");
        if (!rc)
            rc = get_u32(c, &sl->num_weights, "a PVF slot's weights");
        if (!rc)
            rc = get_u32(c, &sl->dim, "a PVF slot's dimension");
        if (rc)
            return rc;
        sl->scalar = (int)s;
        int per_pixel = sl->dim == 3 * f->nl && sl->num_weights == px;
        int per_light = (uint64_t)sl->dim == 3 * px && sl->num_weights == f->nl;
        if (!per_pixel && !per_light)
            return btf__fail(c->err, BTF_E_FORMAT,
                             "%s: PVF slot %u has dim %u and %u weights: expected 3 x lights and "
                             "pixels, or 3 x pixels and lights", f->name, v, sl->dim,
                             sl->num_weights);
        if (v == 0 || (int)s > f->info.scalar_size)
            f->info.scalar_size = (int)s;
        if ((int)sl->k > f->info.components[0])
            f->info.components[0] = (int)sl->k;
        ubo_matrix m;
        rc = take_matrix(c, &m, 1, sl->k, (int)s, "a PVF slot's eigenvalues");
        if (!rc)
            rc = take_matrix(c, &m, sl->dim, 1, (int)s, "a PVF slot's mean");
        sl->mean = m.p;
        if (!rc)
            rc = take_matrix(c, &m, sl->dim, sl->k, (int)s, "a PVF slot's C");
        sl->c = m.p;
        if (!rc)
            rc = take_matrix(c, &m, sl->num_weights, sl->k, (int)s, "a PVF slot's W");
        sl->w = m.p;
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* §6: BDIF's chunk size, compression byte, mask, rotations and chunks. */
static btf_status parse_bdif(cursor *c, ubo_file *f)
{
    uint32_t comp;
    btf_status rc = get_u32(c, &f->lines_per_chunk, "scan_lines_per_chunk");
    if (!rc)
        rc = get_u8(c, &comp, "the compression byte");
    if (rc)
        return rc;
    if (f->lines_per_chunk < 1)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: 0 scan lines per chunk", f->name);
    if (comp == 1)
        return btf__fail(c->err, BTF_E_UNSUPPORTED,
                         "%s: BDIF compression 1 (bzip2) is not supported (0 and 2 are)", f->name);
    if (comp != 0 && comp != 2)
        return btf__fail(c->err, BTF_E_FORMAT, "%s: BDIF compression %u: expected 0, 1 or 2",
                         f->name, comp);
    f->compression = (int)comp;
    f->info.scalar_size = 2;
    uint64_t px = (uint64_t)f->width * f->height;
    rc = need(c, px, "the texel mask");
    if (rc)
        return rc;
    f->mask = f->data + c->pos;
    c->pos += px;
    rc = parse_rotations(c, f);
    if (rc)
        return rc;
    f->stored = px;
    if (comp == 2) {
        f->rank = btf__alloc(px, sizeof *f->rank, c->err);
        if (!f->rank)
            return BTF_E_NOMEM;
        uint64_t n = 0;
        for (uint64_t i = 0; i < px; i++) /* the writer's order, x fastest (§6.4) */
            f->rank[i] = f->mask[i] ? (uint32_t)n++ : UINT32_MAX;
        f->stored = n;
    }
    uint64_t per_texel = (uint64_t)f->nv * f->nl * 3 * 2; /* < 2^66 only in theory: nv, nl fit the file */
    uint64_t a = (uint64_t)f->width * f->lines_per_chunk;
    if (per_texel > f->size || a > f->size / per_texel + 1)
        a = f->stored ? f->stored : 1; /* a chunk larger than the file: one chunk holds all */
    f->chunks = f->stored ? (f->stored + a - 1) / a : 0;
    f->chunk_stride = 4 + a * per_texel;
    f->chunk0 = f->data + c->pos;
    for (uint64_t i = 0; i < f->chunks; i++) {
        uint64_t texels = i + 1 < f->chunks ? a : f->stored - i * a;
        uint32_t bytes;
        rc = get_u32(c, &bytes, "a chunk's byte size");
        if (rc)
            return rc;
        if (bytes != texels * per_texel)
            return btf__fail(c->err, BTF_E_FORMAT,
                             "%s: chunk %llu says %u bytes: expected %llu (%llu texels of %llu "
                             "bytes)", f->name, (unsigned long long)i, bytes,
                             (unsigned long long)(texels * per_texel), (unsigned long long)texels,
                             (unsigned long long)per_texel);
        rc = skip(c, bytes, "a chunk");
        if (rc)
            return rc;
    }
    return BTF_OK;
}

/* Whether every scalar of the matrix is finite; the first bad index. */
static int matrix_finite(const ubo_matrix *m, uint64_t *bad)
{
    uint64_t n = (uint64_t)m->rows * m->k;
    const unsigned char *p = m->p;
    for (uint64_t i = 0; i < n; i++) {
        int ok;
        if (m->scalar == 2) {
            ok = ((p[2 * i + 1] >> 2) & 31) != 31;
        } else if (m->scalar == 4) {
            ok = ((ubo_rd32(p + 4 * i) >> 23) & 255) != 255;
        } else {
            ok = ((ubo_rd32(p + 8 * i + 4) >> 20) & 2047) != 2047;
        }
        if (!ok) {
            *bad = i;
            return 0;
        }
    }
    return 1;
}

/* §5: a PVF slot's mean, C and W (its eigenvalues are not used). */
static btf_status check_finite_pvf(const ubo_file *f, btf_error *err)
{
    for (uint32_t v = 0; v < f->num_slots; v++) {
        const ubo_pvf_slot *sl = &f->slots[v];
        const struct {
            const unsigned char *p;
            uint64_t rows;
            uint32_t k;
            const char *what;
        } m[3] = {{sl->mean, sl->dim, 1, "mean"},
                  {sl->c, sl->dim, sl->k, "C"},
                  {sl->w, sl->num_weights, sl->k, "W"}};
        for (int i = 0; i < 3; i++) {
            ubo_matrix x = {m[i].p, sl->scalar, (uint32_t)m[i].rows, m[i].k};
            uint64_t bad;
            if (!matrix_finite(&x, &bad))
                return btf__fail(err, BTF_E_DATA, "%s: %s of PVF view slot %u has a NaN or Inf at "
                                 "row %llu, component %llu", f->name, m[i].what, v,
                                 (unsigned long long)(bad / m[i].k),
                                 (unsigned long long)(bad % m[i].k));
        }
    }
    return BTF_OK;
}

static btf_status check_finite(const ubo_file *f, btf_error *err)
{
    /* DFMF: one matrix pair per channel; FMF: one for all channels (§4). */
    static const char *const names[4] = {" of channel R/0", " of channel G/1",
                                         " of channel B/2", ""};
    if (f->variant == UBO_PVF)
        return check_finite_pvf(f, err);
    int n = f->variant == UBO_DFMF ? 3 : f->variant == UBO_FMF ? 1 : 0;
    for (int ch = 0; ch < n; ch++) {
        const char *name = names[f->variant == UBO_FMF ? 3 : ch];
        uint64_t bad;
        if (!matrix_finite(&f->u[ch], &bad))
            return btf__fail(err, BTF_E_DATA, "%s: U%s has a NaN or Inf at row %llu, component "
                             "%llu", f->name, name, (unsigned long long)(bad / f->u[ch].k),
                             (unsigned long long)(bad % f->u[ch].k));
        if (!matrix_finite(&f->sxv[ch], &bad))
            return btf__fail(err, BTF_E_DATA, "%s: SxV%s has a NaN or Inf at row %llu, component "
                             "%llu", f->name, name, (unsigned long long)(bad / f->sxv[ch].k),
                             (unsigned long long)(bad % f->sxv[ch].k));
    }
    return BTF_OK;
}

/* Colour models this reader decodes (§3b): 2 needs MATLAB's Lab -> sRGB,
 * 5 and 6 are spectral. */
static int model_supported(int m)
{
    return m == 0 || m == 1 || m == 3 || m == 4 || m == 9 || m == 10 || m == 11 || m == 12;
}

void ubo_free(ubo_file *f)
{
    BTF_FREE_ALL(f->view_rad, f->light_rad, f->rank, f->slots);
    f->view_rad = f->light_rad = NULL;
    f->rank = NULL;
    f->slots = NULL;
}

/* §5: the PVF header, legacy (magic 301074, no meta block) or current. */
static btf_status parse_pvf(cursor *c, ubo_file *f, int rotations, uint64_t *start)
{
    uint32_t first, k = 0, slots = 0;
    btf_status rc = get_u32(c, &first, "the PVF header");
    if (!rc && first == 301074u) { /* the legacy header, no meta block */
        f->nc = 3;
        f->info.n_channels = 3;
        rc = get_u32(c, &k, "num_components");
        if (!rc)
            rc = parse_size(c, f);
        if (!rc)
            rc = get_u32(c, &slots, "num_view_slots");
        if (!rc)
            rc = parse_sampling(c, f);
    } else if (!rc) {
        c->pos -= 4;
        rc = parse_meta(c, f);
        if (!rc)
            rc = parse_sampling(c, f);
        if (!rc)
            rc = parse_size(c, f);
        if (!rc && rotations)
            rc = parse_rotations(c, f);
        if (!rc)
            rc = get_u32(c, &k, "num_components");
        if (!rc)
            rc = get_u32(c, &slots, "num_view_slots");
    }
    if (!rc && f->nc != 3)
        rc = btf__fail(c->err, BTF_E_UNSUPPORTED,
                       "%s: %u channels: only 3-channel (RGB) files are supported", f->name, f->nc);
    *start = c->pos;
    /* num_components (k) is informational: each slot has its own K. */
    return rc ? rc : parse_pvf_slots(c, f, slots);
}

/* The common header (§2) and the body of a DFMF, FMF or BDIF file. */
static btf_status parse_common(cursor *c, ubo_file *f, int sig)
{
    btf_status rc = parse_meta(c, f);
    if (!rc)
        rc = parse_sampling(c, f);
    if (!rc)
        rc = parse_size(c, f);
    if (!rc && f->variant == UBO_BDIF)
        return parse_bdif(c, f);
    if (!rc && SIGS[sig].rotations)
        rc = parse_rotations(c, f);
    if (!rc && f->variant == UBO_DFMF)
        return parse_dfmf(c, f);
    return rc ? rc : parse_fmf(c, f, SIGS[sig].extended);
}

/* The checks after the structure: the end of the file, the colour model,
 * the cosine rule's lights, finite factors; then the byte counts. */
static btf_status check_parsed(cursor *c, ubo_file *f, int skip_finite, uint64_t pvf_start)
{
    btf_error *err = c->err;
    btf_status rc = BTF_OK;
    if (c->pos != f->size)
        rc = btf__fail(err, BTF_E_FORMAT,
                       "%s: %llu byte%s after the end of the %s data at byte %llu: expected a "
                       "file of %llu bytes, the file has %llu", f->name,
                       (unsigned long long)(f->size - c->pos), f->size - c->pos == 1 ? "" : "s",
                       f->info.variant,
                       (unsigned long long)c->pos, (unsigned long long)c->pos,
                       (unsigned long long)f->size);
    if (!rc && f->variant == UBO_DFMF && !model_supported(f->info.colour_model))
        rc = btf__fail(err, BTF_E_UNSUPPORTED,
                       "%s: colour model %d not supported (0, 1, 3, 4, 9, 10, 11 and 12 are)",
                       f->name, f->info.colour_model);
    if (!rc && f->info.cosine_flag)
        for (uint32_t l = 0; l < f->nl && !rc; l++)
            if (cosf(f->light_rad[2 * l]) < 1e-3f)
                rc = btf__fail(err, BTF_E_DATA,
                               "%s: cosine_flag is set and light %u lies at theta %g degrees: "
                               "cannot divide by its cosine", f->name, l,
                               f->light_rad[2 * l] * 57.29577951308232);
    if (!rc && !skip_finite)
        rc = check_finite(f, err);
    if (rc)
        return rc;
    uint64_t mat = 0;
    for (int ch = 0; ch < 3; ch++)
        mat += (uint64_t)f->u[ch].rows * f->u[ch].k * f->u[ch].scalar +
               (uint64_t)f->sxv[ch].rows * f->sxv[ch].k * f->sxv[ch].scalar;
    if (f->variant == UBO_BDIF)
        mat = f->chunks ? f->size - (uint64_t)(f->chunk0 - f->data) : 0;
    if (f->variant == UBO_PVF)
        mat = f->size - pvf_start;
    f->info.data_bytes = mat;
    f->info.transposed = f->transposed;
    return BTF_OK;
}

/* The parse with the signature SIGS[sig]. */
static btf_status parse_as(const unsigned char *data, uint64_t size, const char *name,
                           int skip_finite, int sig, ubo_file *f, btf_error *err)
{
    memset(f, 0, sizeof *f);
    f->name = name ? name : "btf";
    f->data = data;
    f->size = size;
    f->info.colour_model = -1;
    f->variant = SIGS[sig].variant;
    f->sig_len = (int)strlen(SIGS[sig].sig);
    snprintf(f->info.signature, sizeof f->info.signature, "%s", SIGS[sig].sig);
    f->info.variant = f->variant == UBO_DFMF  ? "DFMF"
                      : f->variant == UBO_FMF ? "FMF"
                      : f->variant == UBO_PVF ? "PVF"
                                              : "BDIF";
    f->info.file_bytes = size;
    cursor c = {f, (uint64_t)f->sig_len, err};
    uint64_t pvf_start = 0;
    btf_status rc = f->variant == UBO_PVF ? parse_pvf(&c, f, SIGS[sig].rotations, &pvf_start)
                                          : parse_common(&c, f, sig);
    if (!rc)
        rc = check_parsed(&c, f, skip_finite, pvf_start);
    if (rc)
        ubo_free(f);
    return rc;
}

static btf_status unknown_signature(const unsigned char *data, uint64_t size, const char *name,
                                    btf_error *err)
{
    char shown[48];
    size_t n = size < 10 ? (size_t)size : 10, k = 0;
    for (size_t i = 0; i < n && k + 5 < sizeof shown; i++)
        k += (size_t)snprintf(shown + k, sizeof shown - k,
                              data[i] >= 33 && data[i] < 127 ? "%c" : "\\x%02x", data[i]);
    shown[k] = '\0';
    return btf__fail(err, BTF_E_FORMAT,
                     "%s: unknown signature \"%s\": expected a Bonn .btf file (!DFMF08FCR, "
                     "!FMF12FCER, !FMF06FCR, !FMF06FC, !PVF06FCR, !PVF06FC, !BDIF06R2!)",
                     name ? name : "btf", shown);
}

/* The signature is the longest one the file starts with (§1). "!FMF06FC"
 * and "!PVF06FC" followed by a meta_size whose low byte is 0x52 ('R') also
 * start like "!FMF06FCR" and "!PVF06FCR" (the notes' §1 hazard): when the
 * longer reading fails, the shorter one is tried, and kept if it parses;
 * else the longer reading's error stands. */
btf_status ubo_parse(const unsigned char *data, uint64_t size, const char *name, int skip_finite,
                     ubo_file *f, btf_error *err)
{
    int tried = 0;
    btf_error first = {0};
    btf_status first_rc = BTF_OK;
    for (size_t i = 0; i < sizeof SIGS / sizeof SIGS[0]; i++) {
        size_t n = strlen(SIGS[i].sig);
        if (size < n || memcmp(data, SIGS[i].sig, n) != 0)
            continue;
        btf_error e = {0};
        btf_status rc = parse_as(data, size, name, skip_finite, (int)i, f, &e);
        if (rc == BTF_OK)
            return BTF_OK;
        if (!tried++) {
            first = e;
            first_rc = rc;
        }
    }
    if (!tried) {
        memset(f, 0, sizeof *f);
        return unknown_signature(data, size, name, err);
    }
    if (err)
        *err = first;
    return first_rc;
}
