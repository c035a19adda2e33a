/*
 * model_file.c — the model file MODEL.btfcar: everything synthesis and
 * rendering need (direction sets, index table, per-subspace spectral basis
 * and CAR parameters of paper section II.C, the range-map tile of section
 * II.B) in a few kilobytes. The layout, the limits and the range-map
 * quantisation are specified in docs/model-format.md; this file is its
 * reference implementation at the file level: the signature and versions,
 * the sections in order inside the shared container (container/), and
 * the file forms as thin wrappers (an atomic write, a whole-file read).
 * Each section's coding is model/model_sections.c's or, for the per-texel
 * maps, model/model_maps.c's.
 *
 * The validator (model/model_check.c) serves both directions: the encoder
 * refuses any model the decoder would reject, so whatever btfcar writes it
 * can read, and the decoder trusts nothing it has not checked. Decoding is
 * designed for hostile input (it runs under libFuzzer, tests/fuzz/fuzz_model.c):
 * every count is bounded before it sizes an allocation, every read is
 * bounds-checked, and a failure frees whatever was built.
 */
#include "model/model_file.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ constants */

/* PNG-style signature (docs/model-format.md, "Container"): the high byte
 * catches 7-bit channels, CR LF and the lone LF catch line-ending
 * conversion, ^Z stops DOS `type`. */
static const unsigned char SIGNATURE[BTF_BOX_SIG_LEN] = {0x89, 'B',  'T',  'F',  'C', 'A',
                                                         'R',  '\r', '\n', 0x1a, '\n'};
#define MAX_BYTES ((size_t)64 << 20) /* file and payload */
static const btf_box_format FORMAT = {SIGNATURE, MAX_BYTES, 9, "bytes in all"};

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
 * shading casts shadows; the colour layer follows); a model without either
 * is written as 1.4 or older. */
#define FMT_MINOR_GAINS 5
/* 1.6 lets INDX hold 255 (BTF_PAIR_NONE): a pair a sparse set did not
 * measure. Only such a model is written as 1.6; an older reader refuses
 * it (an index beyond the subspaces), never misreads it. */
#define FMT_MINOR_SPARSE 6
/* 1.7 added the CELL section (the remainders' periodic cells, docs/model.md
 * "Periodic cells"); an older reader skips it and synthesises the fields
 * without the cells. Only a model with cells is written as 1.7. */
#define FMT_MINOR_CELLS 7

/* -------------------------------------------------------------- encoding */

/* Whether the index table marks a pair not measured (format 1.6). */
static int has_unmeasured(const btf_model *m)
{
    size_t n = m->index ? (size_t)m->views.count * (size_t)m->lights.count : 0;
    for (size_t i = 0; i < n; i++)
        if (m->index[i] == BTF_PAIR_NONE)
            return 1;
    return 0;
}

/* The lowest version that holds the model (docs/model-format.md,
 * "Versions"). */
static unsigned minor_version(const btf_model *m)
{
    return btf__cells_any(btf__model_cells(m))    ? FMT_MINOR_CELLS
           : has_unmeasured(m)                    ? FMT_MINOR_SPARSE
           : m->gain || m->shadows || m->chroma   ? FMT_MINOR_GAINS
           : m->albedo                            ? FMT_MINOR_STRUCTURE
           : btf__model_has_lab(m)                 ? FMT_MINOR_LAB
           : btf__model_has_marginals(m)           ? FMT_MINOR_MARGINALS
           : m->range                             ? FMT_MINOR_RANGE_FLAGS
                                                  : 0;
}

/* The sections in the writer's order (docs/model-format.md, "Payload:
 * sections"). */
static btf_status build_payload(const btf_model *m, btf_box_writer *w, const char *name,
                                btf_error *err)
{
    btf__model_put_tables(w, m);
    btf__model_put_subspaces(w, m);
    btf_status rc = BTF_OK;
    if (m->range)
        rc = btf__model_put_range(w, m, name, err);
    if (rc == BTF_OK && btf__model_has_marginals(m))
        btf__model_put_marginals(w, m);
    if (rc == BTF_OK && btf__model_has_lab(m))
        btf__model_put_lab(w, m);
    if (rc == BTF_OK && m->albedo)
        rc = btf__model_put_structure(w, m, name, err);
    if (rc == BTF_OK && m->gain)
        rc = btf__model_put_gains(w, m, name, err);
    if (rc == BTF_OK && btf__cells_any(btf__model_cells(m)))
        rc = btf__model_put_cells(w, m, name, err);
    if (rc == BTF_OK && w->failed)
        rc = failf(err, BTF_E_NOMEM, name, "out of memory encoding the model");
    return rc;
}

/* The container around the payload: header, deflated (or stored, when
 * deflate does not help) body, CRC-32 of everything before it. */
static btf_status wrap_payload(const btf_box_writer *pl, unsigned minor, const char *name,
                               unsigned char **data, size_t *size, btf_error *err)
{
    unsigned char *out = btf__model_alloc(btf__box_bound(pl->n), 1, 0, name, err);
    if (!out)
        return BTF_E_NOMEM;
    *size = btf__box_seal(&FORMAT, FMT_MAJOR, minor, pl->p, pl->n, out);
    *data = out;
    return BTF_OK;
}

/* parts: NULL, or where the payload and its labels go (btf__model_encode_parts). */
static btf_status encode_named(const btf_model *m, const char *name, unsigned char **data,
                               size_t *size, btf_model_payload_parts *parts, btf_error *err)
{
    btf_status rc = btf__box_output(data, size, name, err);
    if (rc == BTF_OK && !m)
        rc = failf(err, BTF_E_ARG, name, "no model");
    if (rc || (rc = btf__model_validate(m, name, BTF_E_DATA, err)))
        return rc;
    btf_box_writer pl = {0};
    pl.labelled = parts != NULL;
    pl.frame_part = BTF_MODEL_PART_FRAMING;
    rc = build_payload(m, &pl, name, err);
    if (rc == BTF_OK && pl.n > MAX_BYTES)
        rc = failf(err, BTF_E_DATA, name, "model of %zu bytes (expected at most %zu)", pl.n,
                   MAX_BYTES);
    if (rc == BTF_OK)
        rc = wrap_payload(&pl, minor_version(m), name, data, size, err);
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

btf_status btf__model_encode_parts(const btf_model *m, unsigned char **data, size_t *size,
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
        return btf__fail(err, BTF_E_ARG, "model: no path to write to");
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

int btf__model_sniff(const unsigned char *data, size_t size)
{
    return btf__box_stem(SIGNATURE, data, size);
}

/* The signature comes first: a foreign file, a truncated one and one mangled
 * by a text-mode transfer each get their own message. */
static btf_status check_signature(const unsigned char *data, size_t size, const char *name,
                                  btf_error *err)
{
    switch (btf__box_signature(SIGNATURE, data, size)) {
    case BTF_BOX_WHOLE:
        return BTF_OK;
    case BTF_BOX_PREFIX:
        return failf(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)", size,
                     BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES);
    case BTF_BOX_DAMAGED:
        return failf(err, BTF_E_FORMAT, name,
                     "damaged signature, line endings converted by a text-mode transfer? "
                     "(expected bytes 89 42 54 46 43 41 52 0D 0A 1A 0A)");
    default:
        return failf(err, BTF_E_FORMAT, name,
                     "not a btfcar model (expected the signature \\x89BTFCAR\\r\\n\\x1a\\n)");
    }
}

/* Before anything else, CRC included, so that a future major version may
 * change everything after offset 15 (docs/model-format.md, "Versions"). */
static btf_status check_version(const unsigned char *data, size_t size, const char *name,
                                btf_error *err)
{
    if (size < BTF_BOX_AT_MINOR + 2)
        return failf(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)", size,
                     BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES);
    unsigned major = btf__box_load_u16(data + BTF_BOX_AT_MAJOR);
    unsigned minor = btf__box_load_u16(data + BTF_BOX_AT_MINOR);
    if (major > FMT_MAJOR)
        return failf(err, BTF_E_FORMAT, name,
                     "format version %u.%u is newer than this reader (expected major version %d; "
                     "a newer btfcar reads it)", major, minor, FMT_MAJOR);
    if (major != FMT_MAJOR)
        return failf(err, BTF_E_FORMAT, name, "format version %u.%u (expected major version %d)",
                     major, minor, FMT_MAJOR);
    return BTF_OK;
}

/* Checks the container and hands back the payload: a pointer into data
 * when stored, an inflated copy in *owned when deflated. */
static btf_status open_payload(const unsigned char *data, size_t size, const char *name,
                               btf_box_payload *pl, unsigned char **owned, btf_error *err)
{
    btf_status rc;
    if ((rc = check_signature(data, size, name, err)) ||
        (rc = check_version(data, size, name, err)) ||
        (rc = btf__box_open(&FORMAT, data, size, name, pl, err)) || !pl->deflated)
        return rc;
    *owned = btf__model_alloc(pl->size ? pl->size : 1, 1, 0, name, err);
    if (!*owned)
        return BTF_E_NOMEM;
    rc = btf__box_inflate(pl, *owned, name, err);
    pl->data = *owned;
    pl->n = pl->size;
    return rc;
}

/* Sections must fill the payload exactly; each known tag at most once. */
static btf_status split_payload(const btf_box_payload *pl, btf_box_span *sec, const char *name,
                                btf_error *err)
{
    btf_box_split_at at;
    switch (btf__box_split(pl->data, pl->size, btf__model_tags, S_COUNT, sec, &at)) {
    case BTF_BOX_SPLIT_OK:
        return BTF_OK;
    case BTF_BOX_SPLIT_SHORT_HEAD:
        return failf(err, BTF_E_FORMAT, name,
                     "truncated section header at payload offset %zu (expected 8 bytes)", at.at);
    case BTF_BOX_SPLIT_PAST_END:
        return failf(err, BTF_E_FORMAT, name,
                     "section at payload offset %zu: %zu bytes (expected at most %zu)", at.at,
                     at.len, at.room);
    default:
        return failf(err, BTF_E_FORMAT, name, "section %s appears twice (expected once)",
                     btf__model_tags[at.tag]);
    }
}

/* Which sections must be there (docs/model-format.md, "Payload:
 * sections"). */
static btf_status check_presence(const btf_box_span *sec, const char *name, btf_error *err)
{
    if (sec[S_VIEW].present != sec[S_LGHT].present ||
        sec[S_VIEW].present != sec[S_INDX].present)
        return failf(err, BTF_E_FORMAT, name,
                     "sections VIEW %s, LGHT %s, INDX %s (expected all three or none)",
                     sec[S_VIEW].present ? "present" : "absent",
                     sec[S_LGHT].present ? "present" : "absent",
                     sec[S_INDX].present ? "present" : "absent");
    if (!sec[S_SUBS].present)
        return failf(err, BTF_E_FORMAT, name, "no SUBS section (expected one)");
    return BTF_OK;
}

/* The readers of the sections after the tables, in the order their checks
 * need whatever their order in the file: STRC after RANG, MARG and LABQ
 * after SUBS, GAIN after INDX, CELL after STRC. */
static btf_model_section_reader *const READERS[S_COUNT] = {
    [S_SUBS] = btf__model_read_subspaces, [S_RANG] = btf__model_read_range,
    [S_MARG] = btf__model_read_marginals, [S_LABQ] = btf__model_read_lab,
    [S_STRC] = btf__model_read_structure, [S_GAIN] = btf__model_read_gains,
    [S_CELL] = btf__model_read_cells};

static btf_status read_payload(const btf_box_payload *pl, btf_model *m, const char *name,
                               btf_error *err)
{
    btf_box_span sec[S_COUNT] = {{0}};
    btf_status rc;
    if ((rc = split_payload(pl, sec, name, err)) || (rc = check_presence(sec, name, err)) ||
        (sec[S_VIEW].present && (rc = btf__model_read_tables(sec, m, name, err))))
        return rc;
    for (int s = S_SUBS; s < S_COUNT; s++)
        if (sec[s].present && (rc = READERS[s](&sec[s], m, name, err)))
            return rc;
    return btf__model_validate(m, name, BTF_E_FORMAT, err);
}

/* The model in data, its margins included. Margins are not stored: they
 * follow from the coefficients. A budget (about a second of work) keeps a
 * small crafted file of thousands of nearly unstable bands from costing
 * minutes; past it a band takes the largest margin, which is always
 * safe. Synthesis finds them in m->internal. */
static btf_status decode_model(const unsigned char *data, size_t size, const char *name,
                               btf_model *m, btf_error *err)
{
    btf_box_payload pl;
    unsigned char *owned = NULL;
    btf_status rc = open_payload(data, size, name, &pl, &owned, err);
    if (rc == BTF_OK)
        rc = read_payload(&pl, m, name, err);
    free(owned);
    if (rc == BTF_OK && btf__model_keep_margins(m, 1e9) != BTF_OK)
        rc = failf(err, BTF_E_NOMEM, name, "out of memory");
    return rc;
}

btf_status btf_model_decode(const unsigned char *data, size_t size, const char *name,
                            btf_model *m, btf_error *err)
{
    if (!name)
        name = "model";
    if (!m)
        return failf(err, BTF_E_ARG, name, "no model to decode into");
    memset(m, 0, sizeof *m);
    btf_status rc = btf__box_input(&data, size, name, err);
    if (rc == BTF_OK && (rc = decode_model(data, size, name, m, err)))
        btf_model_free(m);
    return rc;
}

btf_status btf_model_read(const char *path, btf_model *m, btf_error *err)
{
    if (!m)
        return btf__fail(err, BTF_E_ARG, "model: nothing to read into");
    memset(m, 0, sizeof *m);
    if (!path)
        return btf__fail(err, BTF_E_ARG, "model: no path to read");
    unsigned char *data;
    size_t n;
    btf_status rc = btf__read_file(path, MAX_BYTES, &data, &n, err);
    if (rc)
        return rc;
    rc = btf_model_decode(data, n, path, m, err);
    free(data);
    return rc;
}
