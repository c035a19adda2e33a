/*
 * family.h — what a model family gives the material interface
 * (btfcar/material.h): its signature test, its reader, its description, its
 * renders and its report, as one table of operations per family
 * (src/material/car.c, src/material/rf.c: the top layer, over the family's
 * own folder, the renderers, gpu/ and the report) that material.c lists. The table holds what differs between families; what
 * they share (reading the file's head, naming the file in messages, the
 * caller's options) stays in material.c. Private to the library.
 */
#ifndef BTF_MATERIAL_FAMILY_H
#define BTF_MATERIAL_FAMILY_H

#include "btfcar.h"
#include "btfcar/material.h"
#include "core/core.h"
#include "core/describe.h"

typedef struct btf_family_ops {
    btf_family family;
    const char *name;            /* "car", "rf" */
    unsigned caps;               /* BTF_MATERIAL_* */
    size_t model_size;           /* sizeof the family's model struct */
    /* 1 when the bytes start like the family's file */
    int (*sniff)(const unsigned char *data, size_t size);
    btf_status (*read)(const char *path, void *model, btf_error *err);
    void (*free)(void *model);
    void (*dirsets)(const void *model, const btf_dirset **views, const btf_dirset **lights);
    btf_status (*describe)(const void *model, const describe_file *file, FILE *out, int json,
                           btf_error *err);
    /* BTF_OK when the model can be rendered, else BTF_E_ARG naming path */
    btf_status (*renders)(const void *model, const char *path, btf_error *err);
    btf_status (*render_flat)(const void *model, btf_gpu *g, btf_dir view, btf_dir light,
                              const btf_render_opts *opts, btf_image *out,
                              btf_render_info *info, btf_error *err);
    btf_status (*render_scene)(const void *model, btf_gpu *g, const btf_scene *s,
                               const btf_render_opts *opts, btf_image *out,
                               btf_render_info *info, btf_error *err);
    void (*render_note)(const void *model, const btf_scene *s, btf_dir view,
                        const btf_render_info *info, char *buf, size_t n);
    btf_status (*report)(const btf_dataset *ds, const void *model, const char *dir,
                         const btf_report_opts *opts, btf_report_summary *summary,
                         btf_error *err);
} btf_family_ops;

/* btfcar info on a CAR model (car_describe.c): text, or the JSON document
 * of docs/model-format.md. */
void car_describe(const btf_model *m, const describe_file *file, FILE *f, int json);
/* The same for a reflectance-field model (rf_describe.c; "format":
 * "btfcar-rf-model"). */
btf_status rf_describe(const btf_rf_model *m, const describe_file *file, FILE *f, int json,
                       btf_error *err);

/* The families (src/material/car.c, src/material/rf.c). */
extern const btf_family_ops btf__car_family;
extern const btf_family_ops btf__rf_family;

#endif
