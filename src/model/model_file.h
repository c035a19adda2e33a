/*
 * model_file.h — what the files of MODEL.btfcar share (docs/model-format.md):
 * the section tags, and each section's encoder and decoder. The file level
 * (model/model_file.c: version, container, the order of the sections) calls
 * the sections of the model's tables and records (model/model_sections.c:
 * VIEW, LGHT, INDX, SUBS, MARG, LABQ, GAIN) and of its per-texel maps
 * (model/model_maps.c: RANG, STRC) and the periodic cells (model/model_cells.c:
 * CELL); the container itself is
 * container/container.h's. Private to src/model/.
 */
#ifndef BTF_MODEL_FILE_H
#define BTF_MODEL_FILE_H

#include "container/container.h"
#include "model/model.h"

/* The sections in the order the writer emits them (docs/model-format.md,
 * "Payload: sections") and the reader decodes them. */
enum { S_VIEW, S_LGHT, S_INDX, S_SUBS, S_RANG, S_MARG, S_LABQ, S_STRC, S_GAIN, S_CELL, S_COUNT };
extern const char btf__model_tags[S_COUNT][5];

/* Every message names the file or buffer. */
#define failf btf__box_fail

/* An allocation whose failure message names the file, like every other
 * (zero: calloc). */
void *btf__model_alloc(size_t count, size_t size, int zero, const char *name, btf_error *err);
/* "section TAG is truncated": a body that ends inside a field. */
btf_status btf__model_short(int tag, const char *name, btf_error *err);

/* Encoders, in the writer's order; those that allocate report it. */
void btf__model_put_tables(btf_box_writer *w, const btf_model *m);
void btf__model_put_subspaces(btf_box_writer *w, const btf_model *m);
int btf__model_has_marginals(const btf_model *m);
int btf__model_has_lab(const btf_model *m);
void btf__model_put_marginals(btf_box_writer *w, const btf_model *m);
void btf__model_put_lab(btf_box_writer *w, const btf_model *m);
typedef btf_status btf_model_section_writer(btf_box_writer *w, const btf_model *m,
                                            const char *name, btf_error *err);
btf_model_section_writer btf__model_put_range, btf__model_put_structure, btf__model_put_gains,
    btf__model_put_cells;

/* Decoders: each fills its part of m from its section's body, checking
 * the counts that size loops and allocations; btf__model_validate checks
 * the rest once the model is whole. The tables read VIEW, LGHT and INDX
 * of sec[]; the others their own section, in the order of the enum
 * (MARG and LABQ after SUBS, STRC after RANG, GAIN after INDX, CELL after
 * STRC). */
btf_status btf__model_read_tables(const btf_box_span *sec, btf_model *m, const char *name,
                                  btf_error *err);
typedef btf_status btf_model_section_reader(const btf_box_span *sp, btf_model *m,
                                            const char *name, btf_error *err);
btf_model_section_reader btf__model_read_subspaces, btf__model_read_range,
    btf__model_read_marginals, btf__model_read_lab, btf__model_read_structure,
    btf__model_read_gains, btf__model_read_cells;

#endif
