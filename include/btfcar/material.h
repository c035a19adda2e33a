/*
 * btfcar/material.h — one interface over the model families: a material is
 * a model file of any family (the CAR model of Haindl & Filip 2007,
 * `analyse`; the per-view reflectance field of Meseth, Müller & Klein 2003,
 * `analyse --family rf`), read by one call that sniffs its signature, and
 * then described, rendered (CPU or GPU) and reported without the caller
 * naming its family. src/material/ dispatches to each family's table of
 * operations (src/material/family.h); a new family is one folder, its
 * table there and one line in the list. docs/design.md, "Materials".
 */
#ifndef BTFCAR_MATERIAL_H
#define BTFCAR_MATERIAL_H

#include "base.h"
#include "dataset.h"
#include "image.h"
#include "model.h"
#include "render.h"
#include "report.h"
#include "gpu.h"

#include <stdio.h>

#pragma GCC visibility push(default)
#ifdef __cplusplus
extern "C" {
#endif

/* A model file of any family, read whole and checked (opaque). */
typedef struct btf_material btf_material;

typedef enum btf_family {
    BTF_FAMILY_NONE = 0,
    BTF_FAMILY_CAR = 1, /* btf_model: subspace images synthesised by CAR fields */
    BTF_FAMILY_RF = 2   /* btf_rf_model: per-view reflectance fields, texel by texel */
} btf_family;

/* What a family's renders and reports take beyond size and threads. */
enum {
    /* the textures are synthesised: btf_render_opts' seed, relief,
       texture_size and all_subspaces apply, and the report's sweep of
       analysis settings */
    BTF_MATERIAL_SYNTHESISES = 1u << 0,
};

typedef struct btf_material_info {
    btf_family family;
    const char *family_name;     /* "car", "rf" */
    unsigned caps;               /* BTF_MATERIAL_* */
    unsigned major, minor;       /* the file's format version */
    long long file_bytes;        /* the file's size (-1: unknown) */
    const btf_dirset *views, *lights; /* count 0: a single texture */
} btf_material_info;

/* The family whose signature the bytes start with (a file's first 16 bytes
 * suffice), BTF_FAMILY_NONE for none. */
btf_family btf_material_sniff(const unsigned char *data, size_t size);

/* Reads and checks the model file at path, of whichever family its
 * signature names; a file of no family is read as a CAR model, whose reader
 * says what is wrong with it. Every message names the file. */
btf_status btf_material_read(const char *path, btf_material **out, btf_error *err);
void btf_material_free(btf_material *m);

void btf_material_get_info(const btf_material *m, btf_material_info *out);
/* The family's own model, NULL when m is of the other family. */
const btf_model *btf_material_car(const btf_material *m);
const btf_rf_model *btf_material_rf(const btf_material *m);

/* btfcar info: every part of the model as text, or one JSON document (the
 * family's schema: docs/model-format.md, docs/rf.md). */
btf_status btf_material_describe(const btf_material *m, FILE *out, int json, btf_error *err);

/* The flat (view, light) render of docs/render.md and the render of a scene
 * (btf_scene_load), on g's Vulkan device or on the CPU (g NULL), each by
 * its family's renderer (btf_render_flat / btf_gpu_render_flat and the
 * reflectance field's btf__rf_render_flat / btf__gpu_rf_render_flat, and the
 * same for scenes). opts: the frame (width, height 0: 512) and threads; the
 * rest as BTF_MATERIAL_SYNTHESISES says. A model that cannot be rendered (a
 * single texture, direction sets that cannot be triangulated) is BTF_E_ARG
 * naming its file. info (NULL: not wanted): what the render did. */
btf_status btf_material_render_flat(const btf_material *m, btf_gpu *g, btf_dir view,
                                    btf_dir light, const btf_render_opts *opts, btf_image *out,
                                    btf_render_info *info, btf_error *err);
btf_status btf_material_render_scene(const btf_material *m, btf_gpu *g, const btf_scene *s,
                                     const btf_render_opts *opts, btf_image *out,
                                     btf_render_info *info, btf_error *err);
/* One line saying what a render used (the subspaces synthesised; the views
 * blended), flat at view or of a scene (s non-NULL), into buf. */
void btf_material_render_note(const btf_material *m, const btf_scene *s, btf_dir view,
                              const btf_render_info *info, char *buf, size_t n);

/* The report of m, analysed from ds, into the folder dir (btf_report_write,
 * btf__rf_report_write: docs/report.md). summary may be NULL. */
btf_status btf_material_report_write(const btf_dataset *ds, const btf_material *m,
                                     const char *dir, const btf_report_opts *opts,
                                     btf_report_summary *summary, btf_error *err);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif /* BTFCAR_MATERIAL_H */
