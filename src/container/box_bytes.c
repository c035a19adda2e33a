/*
 * box_bytes.c — the little-endian integers and IEEE floats of the model
 * files (docs/model-format.md, "Conventions": u8..u32, i16, i32, f32 and
 * f64 little-endian, floats bit for bit), a growing writer and a
 * bounds-checked reader. The reader is what makes hostile input safe
 * (tests/fuzz/fuzz_model.c): no read leaves the section it was given.
 */
#include "container/container.h"

#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ in memory */

unsigned btf__box_load_u16(const unsigned char *p)
{
    return (unsigned)p[0] | (unsigned)p[1] << 8;
}

uint32_t btf__box_load_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

float btf__box_load_f32(const unsigned char *p)
{
    uint32_t v = btf__box_load_u32(p);
    float f;
    memcpy(&f, &v, 4);
    return f;
}

double btf__box_load_f64(const unsigned char *p)
{
    uint64_t v = btf__box_load_u32(p) | (uint64_t)btf__box_load_u32(p + 4) << 32;
    double f;
    memcpy(&f, &v, 8);
    return f;
}

void btf__box_store_u16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}

void btf__box_store_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

/* --------------------------------------------------------------- writer */

void btf__box_part(btf_box_writer *w, unsigned part)
{
    w->part = (unsigned char)part;
}

/* Doubles the capacity (from 4096) until n more bytes fit; the labels
 * grow with the bytes. 0 when out of memory. */
static int grow(btf_box_writer *w, size_t n)
{
    size_t cap = w->cap ? w->cap : 4096;
    while (cap - w->n < n)
        cap *= 2;
    unsigned char *p = realloc(w->p, cap);
    if (p)
        w->p = p;
    unsigned char *lab = p && w->labelled ? realloc(w->lab, cap) : NULL;
    if (lab)
        w->lab = lab;
    if (!p || (w->labelled && !lab))
        return 0;
    w->cap = cap;
    return 1;
}

unsigned char *btf__box_reserve(btf_box_writer *w, size_t n)
{
    if (w->failed)
        return NULL;
    if (w->cap - w->n < n && !grow(w, n)) {
        w->failed = 1;
        return NULL;
    }
    unsigned char *at = w->p + w->n;
    if (w->labelled)
        memset(w->lab + w->n, w->part, n);
    w->n += n;
    return at;
}

void btf__box_put_bytes(btf_box_writer *w, const void *src, size_t n)
{
    unsigned char *at = btf__box_reserve(w, n);
    if (at && n)
        memcpy(at, src, n);
}

void btf__box_put_u8(btf_box_writer *w, unsigned v)
{
    unsigned char c = (unsigned char)v;
    btf__box_put_bytes(w, &c, 1);
}

void btf__box_put_u16(btf_box_writer *w, unsigned v)
{
    unsigned char c[2];
    btf__box_store_u16(c, v);
    btf__box_put_bytes(w, c, 2);
}

void btf__box_put_u32(btf_box_writer *w, uint32_t v)
{
    unsigned char c[4];
    btf__box_store_u32(c, v);
    btf__box_put_bytes(w, c, 4);
}

void btf__box_put_f32(btf_box_writer *w, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    btf__box_put_u32(w, u);
}

void btf__box_put_f64(btf_box_writer *w, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    btf__box_put_u32(w, (uint32_t)u);
    btf__box_put_u32(w, (uint32_t)(u >> 32));
}

/* --------------------------------------------------------------- reader */

const unsigned char *btf__box_take(btf_box_reader *r, size_t k)
{
    if (r->short_read || r->n - r->pos < k) {
        r->short_read = 1;
        return NULL;
    }
    const unsigned char *p = r->p + r->pos;
    r->pos += k;
    return p;
}

unsigned btf__box_read_u8(btf_box_reader *r)
{
    const unsigned char *c = btf__box_take(r, 1);
    return c ? c[0] : 0;
}

unsigned btf__box_read_u16(btf_box_reader *r)
{
    const unsigned char *c = btf__box_take(r, 2);
    return c ? btf__box_load_u16(c) : 0;
}

int btf__box_read_i16(btf_box_reader *r)
{
    unsigned v = btf__box_read_u16(r);
    return v >= 0x8000u ? (int)v - 0x10000 : (int)v;
}

uint32_t btf__box_read_u32(btf_box_reader *r)
{
    const unsigned char *c = btf__box_take(r, 4);
    return c ? btf__box_load_u32(c) : 0;
}

int32_t btf__box_read_i32(btf_box_reader *r)
{
    uint32_t v = btf__box_read_u32(r);
    return v >= 0x80000000u ? (int32_t)(v - 0x80000000u) - INT32_MAX - 1 : (int32_t)v;
}

float btf__box_read_f32(btf_box_reader *r)
{
    const unsigned char *c = btf__box_take(r, 4);
    return c ? btf__box_load_f32(c) : 0.0f;
}

double btf__box_read_f64(btf_box_reader *r)
{
    const unsigned char *c = btf__box_take(r, 8);
    return c ? btf__box_load_f64(c) : 0.0;
}
