/*
 * fuzz_container.h — the model file's outer container (docs/model-format.md)
 * around a fuzzed payload, with a correct CRC-32, so that the model fuzz
 * targets reach the payload's parser instead of stopping at the checksum.
 * Header-only: `make fuzz` builds every tests/fuzz/fuzz_*.c on its own.
 */
#ifndef BTF_FUZZ_CONTAINER_H
#define BTF_FUZZ_CONTAINER_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static const unsigned char SIG[11] = {0x89, 'B', 'T', 'F', 'C', 'A', 'R', '\r', '\n', 0x1a, '\n'};

static void put_u32(unsigned char *c, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        c[i] = (unsigned char)(v >> (8 * i));
}

/* A version 1.0 container around a payload, with a correct CRC-32. */
static unsigned char *wrap(const unsigned char *payload, size_t n, int deflate, size_t *size)
{
    uLongf zn = compressBound((uLong)n);
    unsigned char *f = malloc(26 + zn + 4);
    if (!f)
        abort();
    if (!deflate || compress2(f + 26, &zn, payload, (uLong)n, 1) != Z_OK) {
        deflate = 0;
        if (n)
            memcpy(f + 26, payload, n);
        zn = (uLongf)n;
    }
    memcpy(f, SIG, 11);
    f[11] = 1, f[12] = 0;  /* major */
    f[13] = 0, f[14] = 0;  /* minor */
    f[15] = 26, f[16] = 0; /* header bytes */
    f[17] = (unsigned char)deflate;
    put_u32(f + 18, (uint32_t)n);
    put_u32(f + 22, (uint32_t)zn);
    put_u32(f + 26 + zn, (uint32_t)crc32(0L, f, (uInt)(26 + zn)));
    *size = 26 + zn + 4;
    return f;
}

#endif
