/*
 * model.h — the model's rules shared by its files (src/model/): the limits
 * of docs/model-format.md, which a model in memory must meet to be written
 * and a file must meet to be read, the validator that checks them all, and
 * the synthesis margins a model keeps for its CAR bands (paper section
 * II.C). Private to the library.
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

/* The synthesis margins of a model's bands (model/model_margins.c; each
 * computed by btf_car_margin_within, car/car.h), kept in m->internal so that
 * synthesis need not compute them at every call: reading a model file
 * computes them all within a work budget (in the order subspace, band,
 * level), fitting one without (budget < 0). BTF_E_NOMEM when out of
 * memory. */
btf_status btf_model_keep_margins(btf_model *m, double budget);
void btf_model_internal_free(struct btf_model_internal *in);
/* The margin synthesis uses for band b, level l of subspace k: the kept
 * one while the band's neighbourhood and coefficients are those it was
 * computed for, else btf_car_margin; -1 when out of memory. */
int btf_model_margin(const btf_model *m, int k, int b, int l);

/* For the report's accounting (src/report/model_bytes.c): btf_model_encode
 * (the same file bytes in *data, *size), also handing out the payload
 * before deflate and, per payload byte, the btf_model_part it belongs to
 * (both malloc'd, n bytes each; the caller frees them with free). On
 * failure nothing is handed out. */
typedef struct btf_model_payload_parts {
    unsigned char *payload;
    unsigned char *part;
    size_t n;
} btf_model_payload_parts;
btf_status btf_model_encode_parts(const btf_model *m, unsigned char **data, size_t *size,
                                  btf_model_payload_parts *parts, btf_error *err);

#endif
