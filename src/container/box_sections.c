/*
 * box_sections.c — the payload's framing (docs/model-format.md, "Payload:
 * sections"): each section a 4-character tag, a u32 body length and the
 * body. Writers emit the known tags in their order; readers accept any
 * order, skip unknown tags (a newer minor version may add sections,
 * "Versions"), refuse a known tag twice and a payload the sections do not
 * fill exactly.
 */
#include "container/container.h"

#include <string.h>

size_t btf__box_section_begin(btf_box_writer *w, const char *tag)
{
    btf__box_part(w, w->frame_part);
    btf__box_put_bytes(w, tag, 4);
    btf__box_put_u32(w, 0);
    return w->n;
}

/* The length is known once the body is written. */
void btf__box_section_end(btf_box_writer *w, size_t body)
{
    if (!w->failed)
        btf__box_store_u32(w->p + body - 4, (uint32_t)(w->n - body));
}

btf_box_split_fault btf__box_split(const unsigned char *p, size_t n, const char (*tags)[5],
                                   int count, btf_box_span *sec, btf_box_split_at *where)
{
    size_t at = 0;
    while (at < n) {
        *where = (btf_box_split_at){at, 0, n - at, -1};
        if (n - at < BTF_BOX_SECTION_HEAD)
            return BTF_BOX_SPLIT_SHORT_HEAD;
        size_t len = btf__box_load_u32(p + at + 4);
        where->len = len;
        where->room = n - at - BTF_BOX_SECTION_HEAD;
        if (len > where->room)
            return BTF_BOX_SPLIT_PAST_END;
        for (int t = 0; t < count; t++)
            if (memcmp(p + at, tags[t], 4) == 0) {
                where->tag = t;
                if (sec[t].present)
                    return BTF_BOX_SPLIT_TWICE;
                sec[t] = (btf_box_span){p + at + BTF_BOX_SECTION_HEAD, len, 1};
            }
        at += BTF_BOX_SECTION_HEAD + len;
    }
    return BTF_BOX_SPLIT_OK;
}

const char *btf__box_tag_text(const unsigned char *p, char buf[5])
{
    for (int i = 0; i < 4; i++)
        buf[i] = p[i] >= 0x20 && p[i] < 0x7f ? (char)p[i] : '?';
    buf[4] = 0;
    return buf;
}
