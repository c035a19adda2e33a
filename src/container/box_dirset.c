/*
 * box_dirset.c — the direction sets both model files store, VIEW and LGHT
 * (docs/model-format.md, "VIEW, LGHT: direction sets"; docs/rf.md,
 * "File"): a name of at most 31 printable ASCII bytes, 1..4096
 * directions, each f64 theta and phi so that a model keeps a dataset's
 * directions exactly. The families ask different things of a set (a
 * CAR model's directions distinct, a reflectance field's ring by ring),
 * so the rules are offered one by one and each family words its own.
 */
#include "container/container.h"

#include <string.h>

void btf__box_put_dirset(btf_box_writer *w, const char *tag, const btf_dirset *s,
                         unsigned part)
{
    size_t body = btf__box_section_begin(w, tag);
    btf__box_part(w, part);
    size_t len = strnlen(s->name, sizeof s->name);
    btf__box_put_u8(w, (unsigned)len);
    btf__box_put_bytes(w, s->name, len);
    btf__box_put_u16(w, (unsigned)s->count);
    for (int i = 0; i < s->count; i++) {
        btf__box_put_f64(w, s->dirs[i].theta);
        btf__box_put_f64(w, s->dirs[i].phi);
    }
    btf__box_section_end(w, body);
}

void btf__box_dirset_head_of(const unsigned char *p, size_t n, btf_box_dirset_head *h)
{
    h->name_len = n >= 1 ? p[0] : 0;
    h->name = n >= 1 ? p + 1 : p;
    h->head = 1 + h->name_len + 2;
    h->count = n >= h->head ? btf__box_load_u16(p + 1 + h->name_len) : 0;
}

void btf__box_dirset_fill(const unsigned char *p, const btf_box_dirset_head *h, btf_dirset *s)
{
    memcpy(s->name, h->name, h->name_len);
    s->name[h->name_len] = 0;
    s->count = (int)h->count;
    const unsigned char *q = p + h->head;
    for (size_t i = 0; i < h->count; i++) {
        s->dirs[i].theta = btf__box_load_f64(q + BTF_BOX_DIR_BYTES * i);
        s->dirs[i].phi = btf__box_load_f64(q + BTF_BOX_DIR_BYTES * i + 8);
    }
}

/* A NUL inside would shorten the name written back. */
size_t btf__box_name_unprintable(const char *name, size_t len)
{
    for (size_t i = 0; i < len; i++)
        if (name[i] < 0x20 || name[i] > 0x7e)
            return i;
    return len;
}

int btf__box_dir_in_range(btf_dir d)
{
    return d.theta >= 0.0 && d.theta <= 90.0 && d.phi >= 0.0 && d.phi < 360.0;
}

int btf__box_dir_follows(btf_dir prev, btf_dir d)
{
    return d.theta > prev.theta || (d.theta == prev.theta && d.phi > prev.phi);
}

/* The same direction twice would give one direction two rows of the index
 * table; the renderer could not triangulate it either. */
int btf__box_dirs_repeat(const btf_dirset *s, int *j)
{
    for (int i = 0; i < s->count; i++)
        for (*j = i + 1; *j < s->count; (*j)++)
            if (s->dirs[i].theta == s->dirs[*j].theta && s->dirs[i].phi == s->dirs[*j].phi)
                return i;
    return -1;
}
