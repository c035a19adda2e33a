/*
 * model.h — the model's rules shared by its files (src/model/): the limits
 * of docs/model-format.md, which a model in memory must meet to be written
 * and a file must meet to be read, and the validator that checks them all.
 * Private to the library.
 */
#ifndef BTF_MODEL_H
#define BTF_MODEL_H

#include "core/core.h"

/* Limits (docs/model-format.md, "Validation"). */
#define BTF_MODEL_MAX_DIRS 4096
#define BTF_MODEL_MAX_SUBSPACES 256 /* the index table stores uint8 ids */
#define BTF_MODEL_MAX_IMAGE_SIDE (1 << 20)
#define BTF_MODEL_MAX_RANGE_SIDE 65535
#define BTF_MODEL_MAX_RANGE_SAMPLES (1L << 24)
#define BTF_MODEL_MAX_NAME 31       /* bytes of a direction set's name */

/* "NAME: message" with the given code (every model message names its file
 * or buffer). */
btf_status btf_model_fail(btf_error *err, btf_status code, const char *name, const char *fmt,
                          ...) BTF_PRINTF(4, 5);

/* Every rule of docs/model-format.md that a model in memory must meet. code
 * is BTF_E_DATA when writing (the caller's model is wrong) and BTF_E_FORMAT
 * when reading (the file is). One validator serves both directions, so
 * whatever btfcar writes it can read. */
btf_status btf_model_validate(const btf_model *m, const char *name, btf_status code,
                              btf_error *err);

#endif
