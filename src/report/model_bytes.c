/*
 * model_bytes.c — what the bytes of a model file hold (the report's
 * compression accounting): the file is encoded by the real encoder
 * (src/model/model_file.c, which labels every payload byte with the part of
 * the model it stores), and the deflated payload's bits are given back to
 * the bytes they code (report/deflate_cost.c). The parts add up to the
 * file's size exactly. docs/report-compression.md.
 */
#include "model/model.h"
#include "report/report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The container (docs/model-format.md): header_size at 15, compression at
 * 17, stored_size at 22; the file ends with a 4-byte CRC-32. */
#define CRC_BYTES 4

static const char *const PART_NAMES[BTF_MODEL_PART_COUNT] = {
    "container",  "deflate", "framing", "directions", "index",      "spectral", "levels",
    "neighbourhoods", "gammas", "sigmas", "band means", "marginals", "range",
    "structure", "pair gains", "periodic cells"};

const char *btf__model_part_name(int part)
{
    return part >= 0 && part < BTF_MODEL_PART_COUNT ? PART_NAMES[part] : "?";
}

/* Whole parts as close to the shares v as possible: floor(v) or one more,
 * the extra bytes to the largest remainders (ties to the lower index), the
 * whole adding up to total. */
static void round_shares(const double *v, int n, uint64_t total, uint64_t *out)
{
    uint64_t sum = 0;
    double rem[BTF_MODEL_PART_COUNT];
    for (int i = 0; i < n; i++) {
        double f = v[i] > 0 ? floor(v[i]) : 0;
        out[i] = (uint64_t)f;
        rem[i] = v[i] > 0 ? v[i] - f : 0;
        sum += out[i];
    }
    while (sum < total) {
        int best = 0;
        for (int i = 1; i < n; i++)
            if (rem[i] > rem[best])
                best = i;
        out[best]++;
        rem[best] = -1;
        sum++;
    }
    /* Only a share that rounding pushed over could leave sum > total. */
    for (int i = n - 1; i >= 0 && sum > total; i--)
        while (out[i] > 0 && sum > total)
            out[i]--, sum--;
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

btf_status btf__model_byte_breakdown(const btf_model *m, btf_model_bytes *out, btf_error *err)
{
    if (!out)
        return btf__fail(err, BTF_E_ARG, "model: no breakdown to fill");
    memset(out, 0, sizeof *out);
    if (!m)
        return btf__fail(err, BTF_E_ARG, "model: no model to account for");
    unsigned char *data = NULL;
    size_t size = 0;
    btf_model_payload_parts pp;
    btf_status rc = btf__model_encode_parts(m, &data, &size, &pp, err);
    if (rc)
        return rc;
    unsigned hdr = data[15] | (unsigned)data[16] << 8;
    unsigned comp = data[17];
    size_t stored = le32(data + 22);
    if (hdr + stored + CRC_BYTES != size || le32(data + 18) != pp.n) {
        rc = btf__fail(err, BTF_E_DATA,
                       "model: encoded file of %zu bytes does not match its header (header %u, "
                       "stored %zu, payload %zu)", size, hdr, stored, pp.n);
        goto done;
    }
    for (size_t i = 0; i < pp.n; i++)
        out->raw[pp.part[i] < BTF_MODEL_PART_COUNT ? pp.part[i] : BTF_MODEL_PART_FRAMING]++;
    double share[BTF_MODEL_PART_COUNT] = {0};
    if (comp == 0) {
        for (int p = 0; p < BTF_MODEL_PART_COUNT; p++)
            share[p] = (double)out->raw[p];
    } else {
        double bits[BTF_MODEL_PART_COUNT] = {0}, overhead = 0;
        rc = btf__deflate_cost(data + hdr, stored, pp.payload, pp.part, pp.n,
                               BTF_MODEL_PART_COUNT, bits, &overhead, "model", err);
        if (rc)
            goto done;
        for (int p = 0; p < BTF_MODEL_PART_COUNT; p++)
            share[p] = bits[p] / 8.0;
        share[BTF_MODEL_PART_DEFLATE] += overhead / 8.0;
    }
    round_shares(share, BTF_MODEL_PART_COUNT, stored, out->file);
    out->file[BTF_MODEL_PART_CONTAINER] += hdr + CRC_BYTES;
    out->total = size;
    out->payload = pp.n;
    out->deflated = comp != 0;
done:
    BTF_FREE_ALL(data, pp.payload, pp.part);
    if (rc) {
        btf_status keep = rc;
        memset(out, 0, sizeof *out);
        rc = keep;
    }
    return rc;
}
