/*
 * report_json.c — report.json's shared keys (report_base.h, docs/report.md,
 * "report.json"): the page's numbers for programs, written with cJSON. Keys
 * are stable and documented; sizes in bytes, times in seconds, distances
 * normalised (1.0: as close as the material is to itself) unless a key
 * says raw. Here: the document's head, the common keys of the compression,
 * the quality and its pairs, and the preview; a family's sections add
 * theirs.
 */
#include "core/core.h"
#include "report/report_base.h"

#include <stdlib.h>
#include <string.h>

void btf__report_json_dir(cJSON *o, const char *key, btf_dir d)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "theta", d.theta);
    cJSON_AddNumberToObject(j, "phi", d.phi);
}

cJSON *btf__report_json_compression(cJSON *root, const btf_report_base *r)
{
    cJSON *c = cJSON_AddObjectToObject(root, "compression");
    cJSON_AddNumberToObject(c, "raw_bytes", (double)r->raw.raw);
    cJSON_AddNumberToObject(c, "on_disk_bytes", (double)r->raw.on_disk);
    cJSON_AddNumberToObject(c, "model_bytes", (double)r->model_bytes);
    cJSON_AddNumberToObject(c, "ratio", btf__report_ratio(r->raw.raw, r->model_bytes));
    return c;
}

cJSON *btf__report_json_quality(cJSON *root, const btf_report_base *r, double mean_combined)
{
    cJSON *q = cJSON_AddObjectToObject(root, "quality");
    cJSON_AddStringToObject(q, "sample", r->o->quality.all ? "all" : "spread");
    cJSON_AddNumberToObject(q, "pairs", r->n_pairs);
    cJSON_AddNumberToObject(q, "mean_combined", mean_combined);
    return q;
}

void btf__report_json_pairs(cJSON *quality, const btf_report_base *r, btf_report_pair_json keys,
                            int null_picture)
{
    cJSON *worst = cJSON_AddArrayToObject(quality, "worst");
    for (int k = 0; k < r->n_worst; k++)
        cJSON_AddItemToArray(worst, cJSON_CreateNumber(r->worst[k]));
    cJSON *arr = cJSON_AddArrayToObject(quality, "pairs_measured");
    for (int i = 0; i < r->n_pairs; i++) {
        const btf_report_pair *p = &r->pairs[i];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddItemToArray(arr, j);
        cJSON_AddNumberToObject(j, "view", p->view);
        cJSON_AddNumberToObject(j, "light", p->light);
        btf__report_json_dir(j, "view_dir", r->in->views->dirs[p->view]);
        btf__report_json_dir(j, "light_dir", r->in->lights->dirs[p->light]);
        keys(j, r, i);
        if (r->pictured[i]) {
            char name[64];
            btf__report_pair_file(p->view, p->light, name, sizeof name);
            cJSON_AddStringToObject(j, "picture", name);
        } else if (null_picture) {
            cJSON_AddNullToObject(j, "picture");
        }
    }
}

cJSON *btf__report_json_preview(cJSON *root, const btf_report_base *r)
{
    cJSON *pv = cJSON_AddObjectToObject(root, "preview");
    cJSON_AddStringToObject(pv, "picture", "sphere.png");
    btf__report_json_dir(pv, "light", r->o->sphere_light);
    cJSON_AddNumberToObject(pv, "size", r->o->sphere_size);
    cJSON_AddNumberToObject(pv, "seconds", r->sphere_s);
    return pv;
}

btf_status btf__report_json(const btf_report_base *r, const btf_report_family *f,
                            const char *dir, btf_error *err)
{
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return btf__fail(err, BTF_E_NOMEM, "report.json: out of memory");
    cJSON_AddStringToObject(root, "format", "btfcar-report");
    cJSON_AddNumberToObject(root, "format_version", 1);
    if (f->name)
        cJSON_AddStringToObject(root, "family", f->name);
    cJSON_AddStringToObject(root, "btfcar", BTF_VERSION_STRING);
    cJSON_AddStringToObject(root, "date", r->date);
    cJSON_AddStringToObject(root, "dataset", r->dataset_name);
    cJSON_AddStringToObject(root, "model", r->model_name);
    cJSON *ds = cJSON_AddObjectToObject(root, "dataset_info");
    cJSON_AddStringToObject(ds, "layout", btf_layout_name(r->in->layout));
    cJSON_AddNumberToObject(ds, "views", r->in->n_views);
    cJSON_AddNumberToObject(ds, "lights", r->in->n_lights);
    cJSON_AddNumberToObject(ds, "width", r->in->width);
    cJSON_AddNumberToObject(ds, "height", r->in->height);
    f->about->json(root, r);
    cJSON_AddNumberToObject(root, "seconds", r->seconds);
    for (int i = 0; i < f->n_sections; i++)
        if (f->sections[i]->json)
            f->sections[i]->json(root, r);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text)
        return btf__fail(err, BTF_E_NOMEM, "report.json: out of memory");
    char path[4096];
    btf_status rc = btf__path_join(path, sizeof path, dir, "report.json", err);
    if (rc == BTF_OK)
        rc = btf_write_file_atomic(path, text, strlen(text), err);
    cJSON_free(text);
    return rc;
}
