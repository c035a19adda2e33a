/*
 * box_frame.c — the outside of a model file (docs/model-format.md,
 * "Container"; docs/rf.md, "File"): the PNG-style signature, the 26-byte
 * header, the payload stored or deflated and the CRC-32 of everything
 * before it, so that the file ends exactly header_size + stored_size + 4
 * bytes after its start. Writing is deterministic (the same payload gives
 * the same bytes with the same zlib); reading checks, in the order of
 * docs/model-format.md, "Validation", the sizes, the CRC and the
 * compression, after the family has checked the signature and version.
 */
#include "container/container.h"

#include <string.h>
#include <zlib.h>

/* ------------------------------------------------------------ signature */

btf_box_sig btf__box_signature(const unsigned char *signature, const unsigned char *data,
                               size_t size)
{
    size_t k = size < BTF_BOX_SIG_LEN ? size : BTF_BOX_SIG_LEN;
    if (memcmp(data, signature, k) == 0)
        return size < BTF_BOX_SIG_LEN ? BTF_BOX_PREFIX : BTF_BOX_WHOLE;
    return btf__box_stem(signature, data, size) ? BTF_BOX_DAMAGED : BTF_BOX_FOREIGN;
}

int btf__box_stem(const unsigned char *signature, const unsigned char *data, size_t size)
{
    return data && size >= BTF_BOX_SIG_STEM && memcmp(data, signature, BTF_BOX_SIG_STEM) == 0;
}

/* -------------------------------------------------------------- writing */

btf_status btf__box_output(unsigned char **data, size_t *size, const char *name,
                           btf_error *err)
{
    if (!data || !size)
        return btf__box_fail(err, BTF_E_ARG, name, "no output buffer");
    *data = NULL;
    *size = 0;
    return BTF_OK;
}

size_t btf__box_bound(size_t n)
{
    return BTF_BOX_HEADER_BYTES + (size_t)compressBound((uLong)n) + BTF_BOX_CRC_BYTES;
}

/* The writer deflates the payload and stores it instead when deflating
 * does not make it smaller (docs/model-format.md, "Container"). */
size_t btf__box_seal(const btf_box_format *f, unsigned major, unsigned minor,
                     const unsigned char *payload, size_t n, unsigned char *out)
{
    uLongf zlen = compressBound((uLong)n);
    unsigned comp = BTF_BOX_COMP_ZLIB;
    if (compress2(out + BTF_BOX_HEADER_BYTES, &zlen, payload, (uLong)n, f->level) != Z_OK ||
        zlen >= n) {
        comp = BTF_BOX_COMP_STORED;
        zlen = (uLongf)n;
        memcpy(out + BTF_BOX_HEADER_BYTES, payload, n);
    }
    memcpy(out, f->signature, BTF_BOX_SIG_LEN);
    btf__box_store_u16(out + BTF_BOX_AT_MAJOR, major);
    btf__box_store_u16(out + BTF_BOX_AT_MINOR, minor);
    btf__box_store_u16(out + 15, BTF_BOX_HEADER_BYTES);
    out[17] = (unsigned char)comp;
    btf__box_store_u32(out + 18, (uint32_t)n);
    btf__box_store_u32(out + 22, (uint32_t)zlen);
    size_t body = BTF_BOX_HEADER_BYTES + (size_t)zlen;
    btf__box_store_u32(out + body, (uint32_t)crc32(0L, out, (uInt)body));
    return body + BTF_BOX_CRC_BYTES;
}

/* -------------------------------------------------------------- reading */

btf_status btf__box_input(const unsigned char **data, size_t size, const char *name,
                          btf_error *err)
{
    if (!*data && size)
        return btf__box_fail(err, BTF_E_ARG, name, "no data");
    if (!*data)
        *data = (const unsigned char *)"";
    return BTF_OK;
}

/* The file's size against its header: at least the 1.0 header, and
 * exactly header_size + stored_size + 4 bytes. */
static btf_status check_sizes(const btf_box_format *f, const unsigned char *data, size_t size,
                              const char *name, btf_error *err)
{
    if (size > f->max_bytes)
        return btf__box_fail(err, BTF_E_FORMAT, name, "%zu bytes (expected at most %zu)", size,
                             f->max_bytes);
    if (size < BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES)
        return btf__box_fail(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected at least %d)",
                             size, BTF_BOX_HEADER_BYTES + BTF_BOX_CRC_BYTES);
    size_t hdr = btf__box_load_u16(data + 15);
    if (hdr < BTF_BOX_HEADER_BYTES)
        return btf__box_fail(err, BTF_E_FORMAT, name, "header of %zu bytes (expected at least %d)",
                             hdr, BTF_BOX_HEADER_BYTES);
    /* 64-bit sums of 32-bit terms: no overflow even where size_t is 32-bit. */
    uint64_t total = (uint64_t)hdr + btf__box_load_u32(data + 22) + BTF_BOX_CRC_BYTES;
    if ((uint64_t)size < total)
        return btf__box_fail(err, BTF_E_FORMAT, name, "truncated: %zu bytes (expected %llu)", size,
                             (unsigned long long)total);
    if ((uint64_t)size > total)
        return btf__box_fail(err, BTF_E_FORMAT, name, "%llu bytes after the end (expected %llu %s)",
                             (unsigned long long)(size - total), (unsigned long long)total,
                             f->in_all);
    return BTF_OK;
}

static btf_status check_crc(const unsigned char *data, size_t size, const char *name,
                            btf_error *err)
{
    uint32_t want = btf__box_load_u32(data + size - BTF_BOX_CRC_BYTES);
    uint32_t got = (uint32_t)crc32(0L, data, (uInt)(size - BTF_BOX_CRC_BYTES));
    if (want != got)
        return btf__box_fail(err, BTF_E_FORMAT, name,
                             "CRC-32 mismatch, the file is corrupt (expected %08x, computed %08x)",
                             (unsigned)want, (unsigned)got);
    return BTF_OK;
}

/* Compression 0 with equal sizes, or 1 within deflate's ratio. */
static btf_status check_compression(const btf_box_format *f, const btf_box_payload *pl,
                                    unsigned comp, const char *name, btf_error *err)
{
    if (pl->size > f->max_bytes)
        return btf__box_fail(err, BTF_E_FORMAT, name, "payload of %zu bytes (expected at most %zu)",
                             pl->size, f->max_bytes);
    if (comp == BTF_BOX_COMP_STORED) {
        if (pl->size != pl->n)
            return btf__box_fail(err, BTF_E_FORMAT, name,
                                 "stored payload of %zu bytes declared as %zu (expected equal "
                                 "sizes)", pl->n, pl->size);
        return BTF_OK;
    }
    if (comp != BTF_BOX_COMP_ZLIB)
        return btf__box_fail(err, BTF_E_FORMAT, name,
                             "compression method %u (expected 0 stored or 1 zlib)", comp);
    if ((uint64_t)pl->size > (uint64_t)pl->n * BTF_BOX_ZLIB_MAX_RATIO + 64)
        return btf__box_fail(err, BTF_E_FORMAT, name,
                             "payload of %zu bytes from %zu compressed (expected at most %u:1)",
                             pl->size, pl->n, BTF_BOX_ZLIB_MAX_RATIO);
    return BTF_OK;
}

btf_status btf__box_open(const btf_box_format *f, const unsigned char *data, size_t size,
                         const char *name, btf_box_payload *out, btf_error *err)
{
    btf_status rc = check_sizes(f, data, size, name, err);
    if (rc || (rc = check_crc(data, size, name, err)))
        return rc;
    unsigned comp = data[17];
    *out = (btf_box_payload){data + btf__box_load_u16(data + 15), btf__box_load_u32(data + 22),
                             btf__box_load_u32(data + 18), comp != BTF_BOX_COMP_STORED};
    return check_compression(f, out, comp, name, err);
}

/* The stream must give exactly the declared size and use every stored
 * byte (docs/model-format.md, "Validation"). */
btf_status btf__box_inflate(const btf_box_payload *pl, unsigned char *dst, const char *name,
                            btf_error *err)
{
    uLongf got = (uLongf)pl->size;
    uLong used = (uLong)pl->n;
    int zr = uncompress2(dst, &got, pl->data, &used);
    if (zr == Z_OK && got == pl->size && used == pl->n)
        return BTF_OK;
    if (zr == Z_MEM_ERROR)
        return btf__box_fail(err, BTF_E_NOMEM, name, "out of memory inflating the payload");
    return btf__box_fail(err, BTF_E_FORMAT, name,
                         "corrupt compressed payload (expected a zlib stream of %zu bytes giving "
                         "%zu)", pl->n, pl->size);
}
