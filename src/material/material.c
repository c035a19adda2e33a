/*
 * material.c — the material interface (btfcar/material.h): one read that
 * sniffs the file's signature, then describe, render and report through the
 * family's table of operations (family.h). Nothing here names a family but
 * the list below: a new family adds one line to it.
 */
#include "material/family.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The families, in the order their signatures are tried; the first is also
 * the reader of a file of none, whose message says what is wrong. */
static const btf_family_ops *const FAMILIES[] = {&btf__car_family, &btf__rf_family};
#define N_FAMILIES (sizeof FAMILIES / sizeof FAMILIES[0])

/* Both families' files begin with an 11-byte signature and the format's
 * major and minor version, little-endian (docs/model-format.md). */
#define HEAD_BYTES 15

struct btf_material {
    const btf_family_ops *ops;
    void *model;                 /* the family's model struct */
    char *path;
    unsigned major, minor;
    long long bytes;
};

/* The family whose signature the bytes start with, NULL for none. */
static const btf_family_ops *sniffed(const unsigned char *data, size_t size)
{
    for (size_t i = 0; data && i < N_FAMILIES; i++)
        if (FAMILIES[i]->sniff(data, size))
            return FAMILIES[i];
    return NULL;
}

btf_family btf_material_sniff(const unsigned char *data, size_t size)
{
    const btf_family_ops *ops = sniffed(data, size);
    return ops ? ops->family : BTF_FAMILY_NONE;
}

/* The file's first bytes and size; n 0 when it cannot be read (the
 * family's reader then says why, naming the file). */
static size_t read_head(const char *path, unsigned char *head, long long *bytes)
{
    uint64_t size = 0;
    int fd = btf__open_regular(path, &size, NULL);
    *bytes = -1;
    if (fd < 0)
        return 0;
    ssize_t r = read(fd, head, HEAD_BYTES);
    close(fd);
    *bytes = (long long)size;
    return r > 0 ? (size_t)r : 0;
}

btf_status btf_material_read(const char *path, btf_material **out, btf_error *err)
{
    if (!path || !out)
        return btf__fail(err, BTF_E_ARG, "btf_material_read: NULL argument");
    *out = NULL;
    unsigned char head[HEAD_BYTES] = {0};
    long long bytes;
    size_t n = read_head(path, head, &bytes);
    const btf_family_ops *ops = sniffed(head, n);
    if (!ops) /* no family's: the first family's reader says what is wrong */
        ops = FAMILIES[0];
    btf_material *m = calloc(1, sizeof *m);
    void *model = m ? calloc(1, ops->model_size) : NULL;
    char *name = model ? strdup(path) : NULL;
    if (!name) {
        free(model);
        free(m);
        return btf__fail(err, BTF_E_NOMEM, "%s: out of memory", path);
    }
    btf_status rc = ops->read(path, model, err);
    if (rc) {
        BTF_FREE_ALL(name, model, m);
        return rc;
    }
    *m = (btf_material){.ops = ops, .model = model, .path = name, .bytes = bytes,
                        .major = n == HEAD_BYTES ? (unsigned)(head[11] | head[12] << 8) : 0,
                        .minor = n == HEAD_BYTES ? (unsigned)(head[13] | head[14] << 8) : 0};
    *out = m;
    return BTF_OK;
}

void btf_material_free(btf_material *m)
{
    if (!m)
        return;
    m->ops->free(m->model);
    BTF_FREE_ALL(m->model, m->path, m);
}

void btf_material_get_info(const btf_material *m, btf_material_info *out)
{
    memset(out, 0, sizeof *out);
    if (!m)
        return;
    out->family = m->ops->family;
    out->family_name = m->ops->name;
    out->caps = m->ops->caps;
    out->major = m->major;
    out->minor = m->minor;
    out->file_bytes = m->bytes;
    m->ops->dirsets(m->model, &out->views, &out->lights);
}

const btf_model *btf_material_car(const btf_material *m)
{
    return m && m->ops->family == BTF_FAMILY_CAR ? m->model : NULL;
}

const btf_rf_model *btf_material_rf(const btf_material *m)
{
    return m && m->ops->family == BTF_FAMILY_RF ? m->model : NULL;
}

btf_status btf_material_describe(const btf_material *m, FILE *out, int json, btf_error *err)
{
    if (!m || !out)
        return btf__fail(err, BTF_E_ARG, "btf_material_describe: NULL argument");
    describe_file file = {m->path, m->major, m->minor, m->bytes};
    btf_status rc = m->ops->describe(m->model, &file, out, json, err);
    if (rc == BTF_OK && fflush(out) != 0)
        rc = btf__fail(err, BTF_E_IO, "%s: cannot write its description", m->path);
    return rc;
}

btf_status btf_material_render_flat(const btf_material *m, btf_gpu *g, btf_dir view,
                                    btf_dir light, const btf_render_opts *opts, btf_image *out,
                                    btf_render_info *info, btf_error *err)
{
    if (!m || !opts || !out)
        return btf__fail(err, BTF_E_ARG, "btf_material_render_flat: NULL argument");
    btf_render_info none;
    btf_render_opts o, d = btf_render_defaults();
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_material_render_flat", err))
        return BTF_E_ARG;
    btf_status rc = m->ops->renders(m->model, m->path, err);
    return rc ? rc : m->ops->render_flat(m->model, g, view, light, &o, out,
                                         info ? info : &none, err);
}

btf_status btf_material_render_scene(const btf_material *m, btf_gpu *g, const btf_scene *s,
                                     const btf_render_opts *opts, btf_image *out,
                                     btf_render_info *info, btf_error *err)
{
    if (!m || !s || !opts || !out)
        return btf__fail(err, BTF_E_ARG, "btf_material_render_scene: NULL argument");
    btf_render_info none;
    btf_render_opts o, d = btf_render_defaults();
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_material_render_scene", err))
        return BTF_E_ARG;
    btf_status rc = m->ops->renders(m->model, m->path, err);
    return rc ? rc : m->ops->render_scene(m->model, g, s, &o, out, info ? info : &none, err);
}

void btf_material_render_note(const btf_material *m, const btf_scene *s, btf_dir view,
                              const btf_render_info *info, char *buf, size_t n)
{
    if (!buf || n == 0)
        return;
    buf[0] = '\0';
    if (m && info)
        m->ops->render_note(m->model, s, view, info, buf, n);
}

btf_status btf_material_report_write(const btf_dataset *ds, const btf_material *m,
                                     const char *dir, const btf_report_opts *opts,
                                     btf_report_summary *summary, btf_error *err)
{
    if (!ds || !m || !dir || !opts)
        return btf__fail(err, BTF_E_ARG, "btf_material_report_write: NULL argument");
    return m->ops->report(ds, m->model, dir, opts, summary, err);
}
