/*
 * noise_stream.c -- writes the raw random words of one synthesis noise
 * stream to standard output, in the order CPU synthesis draws them, for
 * statistical test suites: `build/noise_stream | dieharder -a -g 200`
 * (docs/synthesis.md, "Noise").
 *
 * Usage: noise_stream [SEED [STREAM [BLOCKS]]] -- defaults 1, 0 and 136:
 * rows from 64 rows above the window down, each BLOCKS blocks of 4 words
 * from column -16 on (a level-0 field of 512 columns plus margins), the
 * words of a block in the order Box-Muller uses them. Runs until the reader
 * closes the pipe.
 */
#include "btf_shared.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Argument i as an unsigned number at most max, else a one-line error. */
static unsigned long long arg(int argc, char **argv, int i, unsigned long long def,
                              unsigned long long max, const char *name)
{
    if (argc <= i)
        return def;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(argv[i], &end, 0);
    if (errno || end == argv[i] || *end || argv[i][0] == '-' || v > max) {
        fprintf(stderr, "noise_stream: %s \"%s\": expected a number 0..%llu\n", name, argv[i],
                max);
        exit(2);
    }
    return v;
}

int main(int argc, char **argv)
{
    if (argc > 4 || (argc > 1 && (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")))) {
        fprintf(argc > 4 ? stderr : stdout, "usage: noise_stream [SEED [STREAM [BLOCKS]]]\n");
        return argc > 4 ? 2 : 0;
    }
    unsigned long long seed = arg(argc, argv, 1, 1, ULLONG_MAX, "SEED");
    uint32_t stream = (uint32_t)arg(argc, argv, 2, 0, UINT32_MAX, "STREAM");
    long blocks = (long)arg(argc, argv, 3, 136, 1 << 20, "BLOCKS");
    if (blocks < 1) {
        fprintf(stderr, "noise_stream: BLOCKS must be 1..1048576\n");
        return 2;
    }
    uint32_t *buf = malloc((size_t)blocks * 4 * sizeof *buf);
    if (!buf)
        return 1;
    uint32_t b0 = (uint32_t)(BTF_NOISE_ORIGIN - 16) >> 2;
    for (uint32_t row = (uint32_t)(BTF_NOISE_ORIGIN - 64);; row++) {
        for (long i = 0; i < blocks; i++) {
            btf_uvec4 w = btf_philox(BTF_UVEC4(b0 + (uint32_t)i, row, stream, BTF_NOISE_TAG),
                                     BTF_UVEC2((uint32_t)seed, (uint32_t)(seed >> 32)));
            buf[4 * i] = w.x, buf[4 * i + 1] = w.y, buf[4 * i + 2] = w.z, buf[4 * i + 3] = w.w;
        }
        if (fwrite(buf, sizeof *buf, (size_t)blocks * 4, stdout) != (size_t)blocks * 4)
            break; /* the reader is done */
    }
    free(buf);
    return 0;
}
