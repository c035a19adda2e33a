/*
 * deflate_cost.c — which bits of a zlib stream code which bytes: a deflate
 * decoder (RFC 1950/1951, in the manner of zlib's contrib/puff) that,
 * instead of only producing the output, hands the bits of every code to
 * the output bytes it produces. A literal's code (with nothing else) costs
 * its own byte; a match's length code, length extra bits, distance code and
 * distance extra bits are shared equally by the bytes it copies; a stored
 * block's bytes cost 8 bits each. What codes no byte (the zlib header and
 * Adler-32, block headers, the code-length tables of dynamic blocks, the
 * end-of-block codes, the padding to a whole byte) is overhead. This is how
 * the report says what the bytes of a deflated model file hold
 * (report/model_bytes.c, docs/report-compression.md). Speed is not a
 * concern (a model's payload is kilobytes): codes are decoded a bit at a
 * time.
 */
#include "report/report.h"

#include <string.h>

#define MAXBITS 15
#define MAXLCODES 286
#define MAXDCODES 30
#define FIXLCODES 288

typedef struct state {
    const unsigned char *in;
    size_t in_n, in_pos;
    unsigned bitbuf, bitcnt;
    uint64_t used;          /* bits consumed from the deflate data */
    const unsigned char *expect;
    const unsigned char *label;
    size_t out_n, out_pos;
    int nlabels;
    double *bits;
    uint64_t coded;         /* bits handed to bytes */
    int bad;                /* 1: ran out of input, or the stream is invalid */
} state;

typedef struct huffman {
    short count[MAXBITS + 1];
    short symbol[FIXLCODES];
} huffman;

static int getbits(state *s, unsigned need)
{
    unsigned long val = s->bitbuf;
    while (s->bitcnt < need) {
        if (s->in_pos >= s->in_n) {
            s->bad = 1;
            return 0;
        }
        val |= (unsigned long)s->in[s->in_pos++] << s->bitcnt;
        s->bitcnt += 8;
    }
    s->bitbuf = (unsigned)(val >> need);
    s->bitcnt -= need;
    s->used += need;
    return (int)(val & ((1UL << need) - 1));
}

/* One symbol of code h, a bit at a time (canonical codes, MSB first). */
static int decode(state *s, const huffman *h)
{
    int code = 0, first = 0, index = 0;
    for (int len = 1; len <= MAXBITS; len++) {
        code |= getbits(s, 1);
        if (s->bad)
            return -1;
        int count = h->count[len];
        if (code - count < first)
            return h->symbol[index + (code - first)];
        index += count;
        first += count;
        first <<= 1;
        code <<= 1;
    }
    s->bad = 1;
    return -1;
}

/* Builds a canonical code from code lengths; 0 when the code is complete
 * or (as deflate allows) incomplete, < 0 when over-subscribed. */
static int construct(huffman *h, const short *length, int n)
{
    short offs[MAXBITS + 1];
    memset(h->count, 0, sizeof h->count);
    for (int symbol = 0; symbol < n; symbol++)
        h->count[length[symbol]]++;
    if (h->count[0] == n)
        return 0;
    int left = 1;
    for (int len = 1; len <= MAXBITS; len++) {
        left <<= 1;
        left -= h->count[len];
        if (left < 0)
            return left;
    }
    offs[1] = 0;
    for (int len = 1; len < MAXBITS; len++)
        offs[len + 1] = (short)(offs[len] + h->count[len]);
    for (int symbol = 0; symbol < n; symbol++)
        if (length[symbol] != 0)
            h->symbol[offs[length[symbol]]++] = (short)symbol;
    return left;
}

/* Hands cost bits to the next len output bytes, checking that they are
 * what the stream produces (from: the distance back, 0 for a literal whose
 * value is lit). */
static void emit(state *s, size_t len, size_t dist, int lit, uint64_t cost)
{
    if (len > s->out_n - s->out_pos || dist > s->out_pos) {
        s->bad = 1;
        return;
    }
    double share = (double)cost / (double)len;
    for (size_t i = 0; i < len; i++) {
        size_t at = s->out_pos + i;
        int v = dist ? s->expect[at - dist] : lit;
        if (v != s->expect[at] || s->label[at] >= s->nlabels) {
            s->bad = 1;
            return;
        }
        s->bits[s->label[at]] += share;
    }
    s->out_pos += len;
    s->coded += cost;
}

static void stored(state *s)
{
    s->bitbuf = 0; /* the rest of the byte is padding */
    s->used += s->bitcnt;
    s->bitcnt = 0;
    if (s->in_n - s->in_pos < 4) {
        s->bad = 1;
        return;
    }
    const unsigned char *p = s->in + s->in_pos;
    unsigned len = p[0] | (unsigned)p[1] << 8;
    unsigned nlen = p[2] | (unsigned)p[3] << 8;
    s->in_pos += 4;
    s->used += 32;
    if (len != (~nlen & 0xffffu) || s->in_n - s->in_pos < len) {
        s->bad = 1;
        return;
    }
    for (unsigned i = 0; i < len && !s->bad; i++)
        emit(s, 1, 0, s->in[s->in_pos + i], 8);
    s->in_pos += len;
    s->used += 8u * len;
}

static const short LBASE[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const short LEXT[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                               2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const short DBASE[30] = {1,    2,    3,    4,    5,    7,     9,     13,    17,  25,
                                33,   49,   65,   97,   129,  193,   257,   385,   513, 769,
                                1025, 1537, 2049, 3073, 4097, 6145,  8193,  12289, 16385, 24577};
static const short DEXT[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                               6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

static void codes(state *s, const huffman *lencode, const huffman *distcode)
{
    for (;;) {
        uint64_t start = s->used;
        int symbol = decode(s, lencode);
        if (s->bad || symbol == 256)
            return; /* the end-of-block code is overhead */
        if (symbol < 256) {
            emit(s, 1, 0, symbol, s->used - start);
        } else {
            symbol -= 257;
            if (symbol >= 29) {
                s->bad = 1;
                return;
            }
            int len = LBASE[symbol] + getbits(s, (unsigned)LEXT[symbol]);
            int d = decode(s, distcode);
            if (s->bad || d < 0 || d >= 30) {
                s->bad = 1;
                return;
            }
            int dist = DBASE[d] + getbits(s, (unsigned)DEXT[d]);
            if (s->bad)
                return;
            emit(s, (size_t)len, (size_t)dist, 0, s->used - start);
        }
        if (s->bad)
            return;
    }
}

static void fixed(state *s)
{
    huffman lencode, distcode;
    short lengths[FIXLCODES];
    int symbol = 0;
    for (; symbol < 144; symbol++)
        lengths[symbol] = 8;
    for (; symbol < 256; symbol++)
        lengths[symbol] = 9;
    for (; symbol < 280; symbol++)
        lengths[symbol] = 7;
    for (; symbol < FIXLCODES; symbol++)
        lengths[symbol] = 8;
    construct(&lencode, lengths, FIXLCODES);
    for (symbol = 0; symbol < MAXDCODES; symbol++)
        lengths[symbol] = 5;
    construct(&distcode, lengths, MAXDCODES);
    codes(s, &lencode, &distcode);
}

static void dynamic(state *s)
{
    static const short ORDER[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
    short lengths[MAXLCODES + MAXDCODES];
    huffman lencode, distcode;
    int nlen = getbits(s, 5) + 257;
    int ndist = getbits(s, 5) + 1;
    int ncode = getbits(s, 4) + 4;
    if (s->bad || nlen > MAXLCODES || ndist > MAXDCODES) {
        s->bad = 1;
        return;
    }
    int index = 0;
    for (; index < ncode; index++)
        lengths[ORDER[index]] = (short)getbits(s, 3);
    for (; index < 19; index++)
        lengths[ORDER[index]] = 0;
    if (s->bad || construct(&lencode, lengths, 19) != 0) {
        s->bad = 1;
        return;
    }
    index = 0;
    while (index < nlen + ndist) {
        int symbol = decode(s, &lencode);
        if (s->bad)
            return;
        if (symbol < 16) {
            lengths[index++] = (short)symbol;
            continue;
        }
        int len = 0, rep;
        if (symbol == 16) {
            if (index == 0) {
                s->bad = 1;
                return;
            }
            len = lengths[index - 1];
            rep = 3 + getbits(s, 2);
        } else if (symbol == 17) {
            rep = 3 + getbits(s, 3);
        } else {
            rep = 11 + getbits(s, 7);
        }
        if (s->bad || index + rep > nlen + ndist) {
            s->bad = 1;
            return;
        }
        while (rep--)
            lengths[index++] = (short)len;
    }
    if (lengths[256] == 0) {
        s->bad = 1;
        return;
    }
    int err = construct(&lencode, lengths, nlen);
    if (err < 0 || (err > 0 && nlen - lencode.count[0] != 1)) {
        s->bad = 1;
        return;
    }
    err = construct(&distcode, lengths + nlen, ndist);
    if (err < 0 || (err > 0 && ndist - distcode.count[0] != 1)) {
        s->bad = 1;
        return;
    }
    codes(s, &lencode, &distcode);
}

btf_status btf__deflate_cost(const unsigned char *z, size_t zn, const unsigned char *expect,
                             const unsigned char *label, size_t n, int nlabels, double *bits,
                             double *overhead_bits, const char *name, btf_error *err)
{
    /* 2 bytes of zlib header (deflate, no preset dictionary), 4 of Adler-32. */
    if (zn < 6 || (z[0] & 0x0f) != 8 || ((unsigned)z[0] << 8 | z[1]) % 31 != 0 || (z[1] & 0x20))
        return btf__fail(err, BTF_E_FORMAT, "%s: not a zlib stream (expected a deflate header)",
                         name);
    state s = {.in = z + 2, .in_n = zn - 6, .expect = expect, .label = label, .out_n = n,
               .nlabels = nlabels, .bits = bits};
    int last;
    do {
        last = getbits(&s, 1);
        int type = getbits(&s, 2);
        if (s.bad)
            break;
        if (type == 0)
            stored(&s);
        else if (type == 1)
            fixed(&s);
        else if (type == 2)
            dynamic(&s);
        else
            s.bad = 1;
    } while (!last && !s.bad);
    if (s.bad || s.out_pos != n)
        return btf__fail(err, BTF_E_FORMAT,
                         "%s: the deflate stream does not decode to the %zu payload bytes "
                         "(decoded %zu)", name, n, s.out_pos);
    *overhead_bits = 8.0 * (double)zn - (double)s.coded;
    return BTF_OK;
}
