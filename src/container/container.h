/*
 * container.h — the file container both model families share
 * (docs/model-format.md, "Container" and "Payload: sections"; docs/rf.md,
 * "File"): an 11-byte PNG-style signature, a 26-byte header (version,
 * header size, compression, payload sizes), the payload of sections (a
 * 4-character tag, a u32 length, the body), stored or deflated, and a
 * CRC-32 of everything before it. MODEL.btfcar (src/model/) and the
 * reflectance-field file (src/rf/) differ only in their signature, their
 * versions, their limits and their sections.
 *
 * The container is only called: it knows no family, takes what differs as
 * a btf_box_format, and where the two readers word a failure differently
 * (the section framing, the direction sets) it reports what is wrong as
 * data and leaves the words to the family. Private to the library.
 */
#ifndef BTF_CONTAINER_H
#define BTF_CONTAINER_H

#include "core/core.h"

#include <stddef.h>
#include <stdint.h>

/* Layout (docs/model-format.md, "Container"). */
#define BTF_BOX_SIG_LEN 11
#define BTF_BOX_SIG_STEM 7 /* "\x89BTF" and 3 letters: what a text-mode transfer keeps */
#define BTF_BOX_AT_MAJOR 11
#define BTF_BOX_AT_MINOR 13
#define BTF_BOX_HEADER_BYTES 26 /* signature .. stored size, version 1.0 */
#define BTF_BOX_CRC_BYTES 4
#define BTF_BOX_SECTION_HEAD 8 /* tag and length */
#define BTF_BOX_COMP_STORED 0
#define BTF_BOX_COMP_ZLIB 1
/* Deflate cannot expand by more than about 1032:1 (docs/model-format.md,
 * "Validation"): a larger claimed payload is a lie that would only cost
 * an allocation. */
#define BTF_BOX_ZLIB_MAX_RATIO 1032u
/* Direction sets (docs/model-format.md, "VIEW, LGHT"). */
#define BTF_BOX_MAX_DIRS 4096
#define BTF_BOX_MAX_NAME 31
#define BTF_BOX_DIR_BYTES 16 /* f64 theta, f64 phi */

/* "NAME: message" with the given code: every container message names its
 * file or buffer. */
btf_status btf__box_fail(btf_error *err, btf_status code, const char *name, const char *fmt, ...)
    BTF_PRINTF(4, 5);

/* ------------------------------------------ little-endian bytes (box_bytes.c) */

unsigned btf__box_load_u16(const unsigned char *p);
uint32_t btf__box_load_u32(const unsigned char *p);
float btf__box_load_f32(const unsigned char *p);
double btf__box_load_f64(const unsigned char *p);
void btf__box_store_u16(unsigned char *p, unsigned v);
void btf__box_store_u32(unsigned char *p, uint32_t v);

/* A growing buffer. A failed allocation is sticky (later writes do
 * nothing; the caller checks `failed` once at the end). With `labelled`,
 * lab[i] is the `part` current when byte i was written (the report's
 * accounting of MODEL.btfcar, btf_model_part), and section framing is
 * labelled `frame_part`. Zero-initialised it is an empty, unlabelled
 * buffer; free p and lab with free(). */
typedef struct btf_box_writer {
    unsigned char *p;
    size_t n, cap;
    int failed;
    int labelled;
    unsigned char part, frame_part;
    unsigned char *lab;
} btf_box_writer;

void btf__box_part(btf_box_writer *w, unsigned part);
/* n bytes at the end, for the caller to fill; NULL when out of memory. */
unsigned char *btf__box_reserve(btf_box_writer *w, size_t n);
void btf__box_put_bytes(btf_box_writer *w, const void *src, size_t n);
void btf__box_put_u8(btf_box_writer *w, unsigned v);
void btf__box_put_u16(btf_box_writer *w, unsigned v);
void btf__box_put_u32(btf_box_writer *w, uint32_t v);
void btf__box_put_f32(btf_box_writer *w, float v);
void btf__box_put_f64(btf_box_writer *w, double v);

/* A bounds-checked cursor over a section body: a read past the end sets
 * the sticky short_read and gives 0 (NULL from btf__box_take), so a parser
 * reads a record and checks once. */
typedef struct btf_box_reader {
    const unsigned char *p;
    size_t n, pos;
    int short_read;
} btf_box_reader;

const unsigned char *btf__box_take(btf_box_reader *r, size_t k);
unsigned btf__box_read_u8(btf_box_reader *r);
unsigned btf__box_read_u16(btf_box_reader *r);
int btf__box_read_i16(btf_box_reader *r);
uint32_t btf__box_read_u32(btf_box_reader *r);
int32_t btf__box_read_i32(btf_box_reader *r);
float btf__box_read_f32(btf_box_reader *r);
double btf__box_read_f64(btf_box_reader *r);

/* -------------------------------- signature, header, CRC, zlib (box_frame.c) */

/* What a family's file needs of the container. */
typedef struct btf_box_format {
    const unsigned char *signature; /* BTF_BOX_SIG_LEN bytes */
    size_t max_bytes;               /* the largest file, and payload, accepted */
    int level;                      /* zlib level of the writer */
    const char *in_all;             /* the words after the expected size when bytes
                                       follow the file's end; the families word it
                                       apart: "bytes in all", "in all" */
} btf_box_format;

/* How data starts compared with a signature: all of it (WHOLE); a shorter
 * input that is its beginning (PREFIX, the empty input too); the stem
 * but not the rest (DAMAGED: line endings converted by a text-mode
 * transfer, docs/model-format.md, "Container"); anything else. */
typedef enum { BTF_BOX_WHOLE, BTF_BOX_PREFIX, BTF_BOX_DAMAGED, BTF_BOX_FOREIGN } btf_box_sig;
btf_box_sig btf__box_signature(const unsigned char *signature, const unsigned char *data,
                               size_t size);
/* Whether data starts with the signature's stem (a sniff: the family's
 * file, perhaps damaged). */
int btf__box_stem(const unsigned char *signature, const unsigned char *data, size_t size);

/* An encoder's output arguments: both given ("no output buffer"
 * otherwise), then cleared until a file is made. */
btf_status btf__box_output(unsigned char **data, size_t *size, const char *name,
                           btf_error *err);

/* Writing: the bytes to allocate for a payload of n bytes, then the file
 * in them (signature, version, the payload deflated, or stored when
 * deflate does not make it smaller, and the CRC-32); returns its size. */
size_t btf__box_bound(size_t n);
size_t btf__box_seal(const btf_box_format *f, unsigned major, unsigned minor,
                     const unsigned char *payload, size_t n, unsigned char *out);

/* A decoder's input: NULL data is refused ("no data") unless size is 0,
 * when it is the empty input (a truncated file, for the family to say). */
btf_status btf__box_input(const unsigned char **data, size_t size, const char *name,
                          btf_error *err);

/* Reading, after the family has checked the signature and the version
 * (readers check those first, docs/model-format.md, "Versions"): the
 * sizes, the CRC-32 and the compression. The payload is data..data + n as
 * stored; a deflated one inflates to `size` bytes (within the ratio cap)
 * with btf__box_inflate into a buffer of at least 1 byte the family
 * allocates. */
typedef struct btf_box_payload {
    const unsigned char *data;
    size_t n, size;
    int deflated;
} btf_box_payload;
btf_status btf__box_open(const btf_box_format *f, const unsigned char *data, size_t size,
                         const char *name, btf_box_payload *out, btf_error *err);
btf_status btf__box_inflate(const btf_box_payload *pl, unsigned char *dst, const char *name,
                            btf_error *err);

/* ----------------------------------------- section framing (box_sections.c) */

/* Begins a section (tag, a u32 length patched by btf__box_section_end);
 * returns where its body starts. */
size_t btf__box_section_begin(btf_box_writer *w, const char *tag);
void btf__box_section_end(btf_box_writer *w, size_t body);

typedef struct btf_box_span {
    const unsigned char *p;
    size_t n;
    int present;
} btf_box_span;

/* Why a payload does not split into sections: where, and what. */
typedef enum {
    BTF_BOX_SPLIT_OK,
    BTF_BOX_SPLIT_SHORT_HEAD, /* fewer than 8 bytes left at `at` */
    BTF_BOX_SPLIT_PAST_END,   /* the section at `at` claims len bytes, only room left */
    BTF_BOX_SPLIT_TWICE       /* a known tag, tags[tag], a second time */
} btf_box_split_fault;
typedef struct btf_box_split_at {
    size_t at, len, room;
    int tag;
} btf_box_split_at;

/* Splits a payload into sections: sec[i] is the body of tags[i] (4
 * characters each), present at most once; unknown tags are skipped (a
 * newer minor version may add sections) and the sections must fill the
 * payload exactly. */
btf_box_split_fault btf__box_split(const unsigned char *p, size_t n, const char (*tags)[5],
                                   int count, btf_box_span *sec, btf_box_split_at *where);
/* A tag for a message: printable ASCII, anything else '?'. */
const char *btf__box_tag_text(const unsigned char *p, char buf[5]);

/* ---------------------------------------------- direction sets (box_dirset.c) */

/* VIEW or LGHT (docs/model-format.md, "VIEW, LGHT"): u8 name length, the
 * name, u16 count, count x (f64 theta, f64 phi); the body labelled part. */
void btf__box_put_dirset(btf_box_writer *w, const char *tag, const btf_dirset *s,
                         unsigned part);

/* What a direction-set body begins with: its name (name_len bytes at
 * name, to be read only when the body holds head bytes) and count; a field
 * the body does not hold is 0. */
typedef struct btf_box_dirset_head {
    size_t name_len;
    const unsigned char *name;
    size_t count;
    size_t head; /* 1 + name_len + 2: the bytes before the directions */
} btf_box_dirset_head;
void btf__box_dirset_head_of(const unsigned char *p, size_t n, btf_box_dirset_head *h);
/* Copies the name and the count directions that follow the head into s,
 * whose dirs the family allocated; the body holds them (checked). */
void btf__box_dirset_fill(const unsigned char *p, const btf_box_dirset_head *h, btf_dirset *s);

/* The rules on a set (docs/model-format.md, "Validation"; docs/rf.md,
 * "File"). The first name byte that is not printable ASCII (len when
 * none); whether a direction is within theta [0, 90], phi [0, 360);
 * whether d follows prev ring by ring (theta ascending, phi ascending
 * within a ring); the first direction i that a later one, *j, repeats
 * (theta -0 is 0), -1 when all are distinct. */
size_t btf__box_name_unprintable(const char *name, size_t len);
int btf__box_dir_in_range(btf_dir d);
int btf__box_dir_follows(btf_dir prev, btf_dir d);
int btf__box_dirs_repeat(const btf_dirset *s, int *j);

#endif
