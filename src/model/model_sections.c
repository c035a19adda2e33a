/*
 * model_sections.c — the sections of MODEL.btfcar that hold the model's
 * tables and per-subspace records (docs/model-format.md): the direction
 * sets (VIEW, LGHT) and the index table (INDX), the subspaces' spectral
 * bases and CAR bands of paper section II.C (SUBS), the marginal
 * transfers (MARG, version 1.2), the exemplars' Lab histograms (LABQ,
 * 1.3) and the pair gains (GAIN, 1.5), each encoded and decoded. Decoding
 * is for hostile input: every read is bounds-checked (container/), every
 * count that sizes a loop or an allocation is checked here, the rest by
 * btf__model_validate (model/model_check.c) once the model is whole.
 */
#include "car/car.h"
#include "model/model_file.h"
#include "synth/synth.h"

#include <stdlib.h>
#include <string.h>

const char btf__model_tags[S_COUNT][5] = {"VIEW", "LGHT", "INDX", "SUBS", "RANG",
                                         "MARG", "LABQ", "STRC", "GAIN", "CELL"};

void *btf__model_alloc(size_t count, size_t size, int zero, const char *name, btf_error *err)
{
    void *p = zero ? btf__calloc(count, size, NULL) : btf__alloc(count, size, NULL);
    if (!p)
        failf(err, BTF_E_NOMEM, name, "out of memory allocating %zu x %zu bytes", count, size);
    return p;
}

btf_status btf__model_short(int tag, const char *name, btf_error *err)
{
    return failf(err, BTF_E_FORMAT, name, "section %s is truncated (expected more bytes)",
                 btf__model_tags[tag]);
}

/* ------------------------------------------------ directions and index */

void btf__model_put_tables(btf_box_writer *w, const btf_model *m)
{
    if (m->views.count < 1)
        return; /* a model of a single texture (docs/model-format.md) */
    btf__box_put_dirset(w, btf__model_tags[S_VIEW], &m->views, BTF_MODEL_PART_DIRECTIONS);
    btf__box_put_dirset(w, btf__model_tags[S_LGHT], &m->lights, BTF_MODEL_PART_DIRECTIONS);
    size_t body = btf__box_section_begin(w, btf__model_tags[S_INDX]);
    btf__box_part(w, BTF_MODEL_PART_INDEX);
    btf__box_put_bytes(w, m->index, (size_t)m->views.count * m->lights.count);
    btf__box_section_end(w, body);
}

/* A body may go on after the directions (a later minor version's
 * fields). The name's bytes are checked here, as read: btf__model_validate
 * sees the name only up to a NUL, and a NUL inside would shorten the name
 * written back (docs/model-format.md: printable ASCII). */
static btf_status read_dirset(const btf_box_span *sp, int tag, btf_dirset *s, const char *name,
                              btf_error *err)
{
    btf_box_dirset_head h;
    btf__box_dirset_head_of(sp->p, sp->n, &h);
    if (h.name_len > BTF_MODEL_MAX_NAME)
        return failf(err, BTF_E_FORMAT, name,
                     "section %s: set name of %zu bytes (expected at most %d)",
                     btf__model_tags[tag], h.name_len, BTF_MODEL_MAX_NAME);
    if (sp->n < h.head)
        return btf__model_short(tag, name, err);
    size_t bad = btf__box_name_unprintable((const char *)h.name, h.name_len);
    if (bad < h.name_len)
        return failf(err, BTF_E_FORMAT, name,
                     "section %s: set name has byte 0x%02x at %zu (expected printable ASCII)",
                     btf__model_tags[tag], h.name[bad], bad);
    if (h.count < 1 || h.count > BTF_MODEL_MAX_DIRS)
        return failf(err, BTF_E_FORMAT, name, "section %s: %zu directions (expected 1..%d)",
                     btf__model_tags[tag], h.count, BTF_MODEL_MAX_DIRS);
    if (sp->n - h.head < h.count * BTF_BOX_DIR_BYTES)
        return btf__model_short(tag, name, err);
    s->dirs = btf__model_alloc(h.count, sizeof *s->dirs, 0, name, err);
    if (!s->dirs)
        return BTF_E_NOMEM;
    btf__box_dirset_fill(sp->p, &h, s);
    return BTF_OK;
}

static btf_status read_index(const btf_box_span *sp, btf_model *m, const char *name,
                             btf_error *err)
{
    size_t n = (size_t)m->views.count * m->lights.count;
    if (sp->n < n)
        return btf__model_short(S_INDX, name, err);
    m->index = btf__model_alloc(n, 1, 0, name, err);
    if (!m->index)
        return BTF_E_NOMEM;
    memcpy(m->index, sp->p, n);
    return BTF_OK;
}

btf_status btf__model_read_tables(const btf_box_span *sec, btf_model *m, const char *name,
                                  btf_error *err)
{
    btf_status rc;
    if ((rc = read_dirset(&sec[S_VIEW], S_VIEW, &m->views, name, err)) ||
        (rc = read_dirset(&sec[S_LGHT], S_LGHT, &m->lights, name, err)))
        return rc;
    return read_index(&sec[S_INDX], m, name, err);
}

/* ----------------------------------------------------------- subspaces */

static void put_band(btf_box_writer *w, const btf_car_band *c)
{
    btf__box_part(w, BTF_MODEL_PART_NEIGHBOURHOODS);
    btf__box_put_u8(w, (unsigned)c->n);
    for (int i = 0; i < c->n; i++) {
        btf__box_put_u8(w, (unsigned)(uint8_t)c->offsets[i].row);
        btf__box_put_u8(w, (unsigned)(uint8_t)c->offsets[i].col);
    }
    btf__box_part(w, BTF_MODEL_PART_GAMMAS);
    for (int i = 0; i < c->n; i++)
        btf__box_put_f32(w, c->gamma[i]);
    btf__box_part(w, BTF_MODEL_PART_SIGMAS);
    btf__box_put_f32(w, c->sigma);
    btf__box_part(w, BTF_MODEL_PART_BAND_MEANS);
    btf__box_put_f32(w, c->mean);
}

void btf__model_put_subspaces(btf_box_writer *w, const btf_model *m)
{
    size_t body = btf__box_section_begin(w, btf__model_tags[S_SUBS]);
    btf__box_put_u16(w, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_subspace_model *sm = &m->subspaces[s];
        btf__box_part(w, BTF_MODEL_PART_FRAMING);
        btf__box_put_u16(w, (unsigned)sm->view & 0xFFFFu);
        btf__box_put_u16(w, (unsigned)sm->light & 0xFFFFu);
        btf__box_put_u32(w, (uint32_t)sm->width);
        btf__box_put_u32(w, (uint32_t)sm->height);
        btf__box_part(w, BTF_MODEL_PART_SPECTRAL);
        for (int c = 0; c < 3; c++)
            btf__box_put_f32(w, sm->mean[c]);
        for (int i = 0; i < 9; i++)
            btf__box_put_f32(w, sm->basis[i]);
        btf__box_part(w, BTF_MODEL_PART_LEVELS);
        btf__box_put_u8(w, (unsigned)sm->levels);
        for (int band = 0; band < 3; band++)
            for (int l = 0; l < sm->levels; l++)
                put_band(w, &sm->bands[band][l]);
    }
    btf__box_section_end(w, body);
}

static int8_t s8(unsigned char c)
{
    return (int8_t)(c >= 0x80 ? (int)c - 0x100 : (int)c);
}

static void read_band(btf_box_reader *r, btf_car_band *b)
{
    for (int i = 0; i < b->n; i++) {
        const unsigned char *c = btf__box_take(r, 2);
        b->offsets[i].row = c ? s8(c[0]) : 0;
        b->offsets[i].col = c ? s8(c[1]) : 0;
    }
    for (int i = 0; i < b->n; i++)
        b->gamma[i] = btf__box_read_f32(r);
    b->sigma = btf__box_read_f32(r);
    b->mean = btf__box_read_f32(r);
}

/* The levels and each band's neighbour count size loops: checked at once. */
static btf_status read_bands(btf_box_reader *r, btf_subspace_model *sm, int s, const char *name,
                             btf_error *err)
{
    if (sm->levels < 1 || sm->levels > BTF_MAX_LEVELS)
        return failf(err, BTF_E_FORMAT, name, "subspace %d: %d pyramid levels (expected 1..%d)", s,
                     sm->levels, BTF_MAX_LEVELS);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < sm->levels; l++) {
            btf_car_band *cb = &sm->bands[b][l];
            cb->n = (int)btf__box_read_u8(r);
            if (cb->n > BTF_CAR_MAX_NEIGHBOURS)
                return failf(err, BTF_E_FORMAT, name,
                             "subspace %d, band %d, level %d: %d neighbours (expected 0..%d)", s, b,
                             l, cb->n, BTF_CAR_MAX_NEIGHBOURS);
            read_band(r, cb);
            if (r->short_read)
                return btf__model_short(S_SUBS, name, err);
        }
    return BTF_OK;
}

/* One subspace record; the image size is checked at once, the basis and
 * the numbers by btf__model_validate. */
static btf_status read_subspace(btf_box_reader *r, btf_subspace_model *sm, int s,
                                const char *name, btf_error *err)
{
    sm->view = btf__box_read_i16(r);
    sm->light = btf__box_read_i16(r);
    uint32_t w = btf__box_read_u32(r), h = btf__box_read_u32(r);
    if (!r->short_read && (w < 1 || w > BTF_MODEL_MAX_IMAGE_SIDE || h < 1 ||
                           h > BTF_MODEL_MAX_IMAGE_SIDE))
        return failf(err, BTF_E_FORMAT, name,
                     "subspace %d: size %lu x %lu (expected 1..%d on each side)", s,
                     (unsigned long)w, (unsigned long)h, BTF_MODEL_MAX_IMAGE_SIDE);
    sm->width = (int)w;
    sm->height = (int)h;
    for (int c = 0; c < 3; c++)
        sm->mean[c] = btf__box_read_f32(r);
    for (int i = 0; i < 9; i++)
        sm->basis[i] = btf__box_read_f32(r);
    sm->levels = (int)btf__box_read_u8(r);
    if (r->short_read)
        return btf__model_short(S_SUBS, name, err);
    return read_bands(r, sm, s, name, err);
}

btf_status btf__model_read_subspaces(const btf_box_span *sp, btf_model *m, const char *name,
                                     btf_error *err)
{
    btf_box_reader r = {sp->p, sp->n, 0, 0};
    unsigned count = btf__box_read_u16(&r);
    if (r.short_read)
        return btf__model_short(S_SUBS, name, err);
    if (count < 1 || count > BTF_MODEL_MAX_SUBSPACES)
        return failf(err, BTF_E_FORMAT, name, "%u subspaces (expected 1..%d)", count,
                     BTF_MODEL_MAX_SUBSPACES);
    m->subspaces = btf__model_alloc(count, sizeof *m->subspaces, 1, name, err);
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

/* ------------------------------------------- marginals, Lab histograms */

int btf__model_has_marginals(const btf_model *m)
{
    for (int s = 0; s < m->n_subspaces; s++)
        if (m->subspaces[s].marginal.knots)
            return 1;
    return 0;
}

int btf__model_has_lab(const btf_model *m)
{
    for (int s = 0; s < m->n_subspaces; s++)
        if (m->subspaces[s].marginal.knots && m->subspaces[s].marginal.lab_knots)
            return 1;
    return 0;
}

/* MARG (version 1.2): per subspace a u8 knot count, 0 or 32; with 32, per
 * band its synthesised mean and sd and 32 quantiles, then the RGB box. */
void btf__model_put_marginals(btf_box_writer *w, const btf_model *m)
{
    size_t body = btf__box_section_begin(w, btf__model_tags[S_MARG]);
    btf__box_put_u16(w, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_marginal *mg = &m->subspaces[s].marginal;
        btf__box_part(w, BTF_MODEL_PART_MARGINALS);
        btf__box_put_u8(w, (unsigned)mg->knots);
        if (!mg->knots)
            continue;
        for (int band = 0; band < 3; band++) {
            btf__box_put_f32(w, mg->synth_mean[band]);
            btf__box_put_f32(w, mg->synth_sd[band]);
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                btf__box_put_f32(w, mg->quantile[band][j]);
        }
        for (int k = 0; k < 3; k++)
            btf__box_put_f32(w, mg->rgb_lo[k]);
        for (int k = 0; k < 3; k++)
            btf__box_put_f32(w, mg->rgb_hi[k]);
    }
    btf__box_section_end(w, body);
}

/* LABQ (version 1.3): per subspace a u8 knot count, 0 or 32 (0 where MARG
 * has none); with 32, per channel L*, a*, b* its 32 quantiles as u16 codes
 * over [0, 100] and [-128, 128] (synth/colour_lab.c). */
void btf__model_put_lab(btf_box_writer *w, const btf_model *m)
{
    size_t body = btf__box_section_begin(w, btf__model_tags[S_LABQ]);
    btf__box_put_u16(w, (unsigned)m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        const btf_marginal *mg = &m->subspaces[s].marginal;
        int knots = mg->knots ? mg->lab_knots : 0;
        btf__box_part(w, BTF_MODEL_PART_MARGINALS);
        btf__box_put_u8(w, (unsigned)knots);
        for (int c = 0; knots && c < 3; c++)
            for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
                btf__box_put_u16(w, btf__lab_code(c, mg->lab_quantile[c][j]));
    }
    btf__box_section_end(w, body);
}

/* One subspace's record of MARG or LABQ, which begins with its knot count;
 * a read past the body is the caller's to report. */
typedef btf_status (*knots_record)(btf_box_reader *r, btf_marginal *mg, int s, const char *name,
                                   btf_error *err);

/* MARG and LABQ alike: a u16 count, SUBS's, then a record per subspace. */
static btf_status read_per_subspace(const btf_box_span *sp, int tag, btf_model *m,
                                    knots_record record, const char *name, btf_error *err)
{
    btf_box_reader r = {sp->p, sp->n, 0, 0};
    unsigned count = btf__box_read_u16(&r);
    if (r.short_read)
        return btf__model_short(tag, name, err);
    if ((int)count != m->n_subspaces)
        return failf(err, BTF_E_FORMAT, name, "section %s: %u subspaces (expected %d, as SUBS)",
                     btf__model_tags[tag], count, m->n_subspaces);
    for (int s = 0; s < m->n_subspaces; s++) {
        btf_status rc = record(&r, &m->subspaces[s].marginal, s, name, err);
        if (rc)
            return rc;
        if (r.short_read)
            return btf__model_short(tag, name, err);
    }
    return BTF_OK;
}

/* The knot count is checked here, the numbers by btf__model_validate. */
static btf_status read_marginal(btf_box_reader *r, btf_marginal *mg, int s, const char *name,
                                btf_error *err)
{
    unsigned knots = btf__box_read_u8(r);
    if (knots != 0 && knots != BTF_MARGIN_KNOTS)
        return failf(err, BTF_E_FORMAT, name,
                     "section MARG: subspace %d has %u knots (expected 0 or %d)", s, knots,
                     BTF_MARGIN_KNOTS);
    mg->knots = (int)knots;
    for (int band = 0; knots && band < 3; band++) {
        mg->synth_mean[band] = btf__box_read_f32(r);
        mg->synth_sd[band] = btf__box_read_f32(r);
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            mg->quantile[band][j] = btf__box_read_f32(r);
    }
    for (int k = 0; knots && k < 3; k++)
        mg->rgb_lo[k] = btf__box_read_f32(r);
    for (int k = 0; knots && k < 3; k++)
        mg->rgb_hi[k] = btf__box_read_f32(r);
    return BTF_OK;
}

/* A model without MARG (format 1.0, 1.1) keeps knots 0: no transfer. */
btf_status btf__model_read_marginals(const btf_box_span *sp, btf_model *m, const char *name,
                                     btf_error *err)
{
    return read_per_subspace(sp, S_MARG, m, read_marginal, name, err);
}

/* A subspace without MARG knots has no histogram. */
static btf_status read_lab_record(btf_box_reader *r, btf_marginal *mg, int s, const char *name,
                                  btf_error *err)
{
    unsigned knots = btf__box_read_u8(r);
    if (knots != 0 && (knots != BTF_MARGIN_KNOTS || !mg->knots))
        return failf(err, BTF_E_FORMAT, name,
                     "section LABQ: subspace %d has %u knots (expected 0%s%s)", s, knots,
                     mg->knots ? " or " : ": it has no marginal transfer",
                     mg->knots ? "32" : "");
    mg->lab_knots = (int)knots;
    for (int c = 0; knots && c < 3; c++)
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++)
            mg->lab_quantile[c][j] = btf__lab_decode(c, btf__box_read_u16(r));
    return BTF_OK;
}

/* A model without LABQ (format 1.2 or older) keeps lab_knots 0: no colour
 * matching. */
btf_status btf__model_read_lab(const btf_box_span *sp, btf_model *m, const char *name,
                               btf_error *err)
{
    return read_per_subspace(sp, S_LABQ, m, read_lab_record, name, err);
}

/* ---------------------------------------------------------- pair gains */

/* GAIN: per pair (views x lights, the index table's order) and channel
 * the gain's code (a signed byte, btf__gain_code) minus the previous
 * pair's code of that channel, modulo 256: neighbouring lights differ
 * little, so the residuals are near 0. */
btf_status btf__model_put_gains(btf_box_writer *w, const btf_model *m, const char *name,
                                btf_error *err)
{
    size_t n = (size_t)m->views.count * m->lights.count * 3;
    unsigned char *res = btf__model_alloc(n, 1, 0, name, err);
    if (!res)
        return BTF_E_NOMEM;
    int prev[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        int q = btf__gain_code(m->gain[i]);
        res[i] = (unsigned char)((q - prev[i % 3]) & 0xff);
        prev[i % 3] = q;
    }
    size_t body = btf__box_section_begin(w, btf__model_tags[S_GAIN]);
    btf__box_part(w, BTF_MODEL_PART_GAINS);
    btf__box_put_bytes(w, res, n);
    btf__box_section_end(w, body);
    free(res);
    return BTF_OK;
}

/* The codes rebuilt from their residuals; the index table gives the pair
 * count. */
btf_status btf__model_read_gains(const btf_box_span *sp, btf_model *m, const char *name,
                                 btf_error *err)
{
    if (m->views.count < 1)
        return failf(err, BTF_E_FORMAT, name, "section GAIN without directions (expected VIEW, "
                     "LGHT and INDX)");
    size_t n = (size_t)m->views.count * m->lights.count * 3;
    if (sp->n != n)
        return failf(err, BTF_E_FORMAT, name, "section GAIN: %zu bytes (expected %zu: 3 per "
                     "pair)", sp->n, n);
    m->gain = btf__model_alloc(n, sizeof(float), 0, name, err);
    if (!m->gain)
        return BTF_E_NOMEM;
    int prev[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        int q = (int)(signed char)(unsigned char)(sp->p[i] + prev[i % 3]);
        prev[i % 3] = q;
        m->gain[i] = btf__gain_value(q);
    }
    return BTF_OK;
}
