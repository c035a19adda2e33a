/*
 * report_json.c — report.json (issue 18, docs/report.md, "report.json"):
 * the page's numbers for programs, written with cJSON. Keys are stable and
 * documented; sizes in bytes, times in seconds, distances normalised
 * (1.0: as close as the material is to itself) unless a key says raw.
 */
#include "core/core.h"
#include "report/report_data.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

static void add_dir(cJSON *o, const char *key, btf_dir d)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "theta", d.theta);
    cJSON_AddNumberToObject(j, "phi", d.phi);
}

static void add_compression(cJSON *root, const btf_report_data *d)
{
    cJSON *c = cJSON_AddObjectToObject(root, "compression");
    cJSON_AddNumberToObject(c, "raw_bytes", (double)d->raw.raw);
    cJSON_AddNumberToObject(c, "on_disk_bytes", (double)d->raw.on_disk);
    cJSON_AddNumberToObject(c, "model_bytes", (double)d->bytes.total);
    cJSON_AddNumberToObject(c, "ratio", d->bytes.total ? (double)d->raw.raw / d->bytes.total : 0);
    cJSON_AddNumberToObject(c, "paper_ratio", BTF_REPORT_PAPER_RATIO);
    cJSON *parts = cJSON_AddObjectToObject(c, "model_parts");
    cJSON *raw = cJSON_AddObjectToObject(c, "model_parts_before_deflate");
    for (int p = 0; p < BTF_MODEL_PART_COUNT; p++) {
        cJSON_AddNumberToObject(parts, btf_model_part_name(p), (double)d->bytes.file[p]);
        cJSON_AddNumberToObject(raw, btf_model_part_name(p), (double)d->bytes.raw[p]);
    }
    cJSON *pca = cJSON_AddObjectToObject(c, "pca");
    if (d->pca.views == 0)
        cJSON_AddStringToObject(pca, "skipped", "a sparse set: no view under every light");
    cJSON_AddNumberToObject(pca, "bytes", (double)d->pca.bytes);
    cJSON_AddNumberToObject(pca, "ratio", d->pca.ratio);
    cJSON_AddNumberToObject(pca, "max_rms", d->o->pca.max_rms > 0 ? d->o->pca.max_rms : 2.0);
    cJSON_AddNumberToObject(pca, "rms", d->pca.rms);
    cJSON_AddNumberToObject(pca, "bits", d->o->pca.bits > 0 ? d->o->pca.bits : 16);
    cJSON_AddNumberToObject(pca, "mean_components", d->pca.mean_components);
    cJSON_AddNumberToObject(pca, "min_components", d->pca.min_components);
    cJSON_AddNumberToObject(pca, "max_components", d->pca.max_components);
    cJSON_AddNumberToObject(pca, "seconds", d->pca.seconds);
    cJSON *jp = cJSON_AddObjectToObject(c, "jpeg");
    cJSON_AddNumberToObject(jp, "quality", d->jpeg.quality);
    cJSON_AddNumberToObject(jp, "images", d->jpeg.images);
    cJSON_AddNumberToObject(jp, "jpeg_bytes", (double)d->jpeg.jpeg_bytes);
    cJSON_AddNumberToObject(jp, "index_bytes", (double)d->jpeg.index_bytes);
    cJSON_AddNumberToObject(jp, "bytes", (double)d->jpeg.bytes);
    cJSON_AddNumberToObject(jp, "ratio", d->jpeg.ratio);
    cJSON_AddNumberToObject(jp, "rms", d->jpeg.rms);
}

static void add_component(cJSON *o, const char *key, const btf_distance_component *c)
{
    cJSON *j = cJSON_AddObjectToObject(o, key);
    cJSON_AddNumberToObject(j, "raw", c->raw);
    cJSON_AddNumberToObject(j, "self", c->self);
    cJSON_AddNumberToObject(j, "normalised", c->normalised);
}

static void add_quality(cJSON *root, const btf_report_data *d)
{
    const btf_quality *q = &d->q;
    cJSON *o = cJSON_AddObjectToObject(root, "quality");
    cJSON_AddStringToObject(o, "sample", d->o->quality.all ? "all" : "spread");
    cJSON_AddNumberToObject(o, "pairs", q->n_pairs);
    cJSON_AddNumberToObject(o, "mean_combined", q->mean_combined);
    cJSON_AddNumberToObject(o, "held_out", q->n_held_out);
    cJSON_AddNumberToObject(o, "mean_held_out", q->mean_held_out);
    cJSON_AddNumberToObject(o, "median_combined", q->median_combined);
    cJSON_AddNumberToObject(o, "worst_combined", q->worst_combined);
    cJSON_AddNumberToObject(o, "mean_spectrum", q->mean_spectrum);
    cJSON_AddNumberToObject(o, "mean_first_order", q->mean_first_order);
    cJSON_AddNumberToObject(o, "mean_structure", q->mean_structure);
    cJSON_AddNumberToObject(o, "texture_size", q->texture_size);
    cJSON_AddNumberToObject(o, "relief", d->o->quality.relief < 0 ? 1.0 : d->o->quality.relief);
    cJSON_AddNumberToObject(o, "seed", (double)d->o->quality.seed);
    cJSON_AddNumberToObject(o, "seconds", q->seconds);
    cJSON *worst = cJSON_AddArrayToObject(o, "worst");
    for (int k = 0; k < d->n_worst; k++)
        cJSON_AddItemToArray(worst, cJSON_CreateNumber(d->worst[k]));
    cJSON *arr = cJSON_AddArrayToObject(o, "pairs_measured");
    for (int i = 0; i < q->n_pairs; i++) {
        const btf_pair_quality *p = &q->pairs[i];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddItemToArray(arr, j);
        cJSON_AddNumberToObject(j, "view", p->view);
        cJSON_AddNumberToObject(j, "light", p->light);
        add_dir(j, "view_dir", d->in->views->dirs[p->view]);
        add_dir(j, "light_dir", d->in->lights->dirs[p->light]);
        cJSON_AddNumberToObject(j, "subspace", p->subspace);
        cJSON_AddBoolToObject(j, "held_out", p->held_out);
        add_component(j, "spectrum", &p->d.spectrum);
        add_component(j, "first_order", &p->d.first_order);
        add_component(j, "structure", &p->d.structure);
        cJSON_AddNumberToObject(j, "combined", p->d.combined);
        if (d->pictured[i]) {
            char name[64];
            btf_report_pair_file(d, i, name, sizeof name);
            cJSON_AddStringToObject(j, "picture", name);
        } else {
            cJSON_AddNullToObject(j, "picture");
        }
    }
}

static void add_sweep(cJSON *root, const btf_report_data *d)
{
    if (!d->have_sweep) {
        cJSON_AddNullToObject(root, "sweep");
        return;
    }
    const btf_sweep *s = &d->sweep;
    cJSON *o = cJSON_AddObjectToObject(root, "sweep");
    cJSON_AddNumberToObject(o, "shared_seconds", s->shared_s);
    cJSON_AddNumberToObject(o, "seconds", s->seconds);
    cJSON_AddNumberToObject(o, "resumed", s->resumed);
    cJSON_AddNumberToObject(o, "synth_size", d->o->sweep_opts.synth_size);
    cJSON_AddNumberToObject(o, "render_size", d->o->sweep_opts.render_size);
    cJSON_AddNumberToObject(o, "seeds", s->seeds);
    cJSON *arr = cJSON_AddArrayToObject(o, "points");
    for (int i = 0; i < s->n_points; i++) {
        const btf_sweep_point *p = &s->points[i];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddItemToArray(arr, j);
        cJSON_AddNumberToObject(j, "subspaces", p->setting.subspaces);
        cJSON_AddNumberToObject(j, "levels", p->setting.levels);
        cJSON_AddNumberToObject(j, "neighbours", p->setting.neighbours);
        cJSON_AddBoolToObject(j, "structure", !p->setting.plain);
        cJSON_AddNumberToObject(j, "range_size", p->setting.range_size);
        cJSON_AddNumberToObject(j, "k", p->k);
        cJSON_AddNumberToObject(j, "analyse_seconds", p->analyse_s);
        cJSON_AddNumberToObject(j, "synth_seconds", p->synth_s);
        if (p->gpu_synth_s >= 0)
            cJSON_AddNumberToObject(j, "gpu_synth_seconds", p->gpu_synth_s);
        else
            cJSON_AddNullToObject(j, "gpu_synth_seconds");
        cJSON_AddNumberToObject(j, "render_seconds", p->render_s);
        cJSON_AddNumberToObject(j, "bytes", (double)p->bytes);
        cJSON_AddNumberToObject(j, "mean_combined", p->mean_combined);
        cJSON_AddNumberToObject(j, "worst_combined", p->worst_combined);
        cJSON_AddNumberToObject(j, "seed_spread", p->seed_spread);
        cJSON_AddBoolToObject(j, "default", p->is_default);
        cJSON_AddBoolToObject(j, "pareto_bytes", p->pareto_bytes);
        cJSON_AddBoolToObject(j, "pareto_time", p->pareto_time);
        cJSON_AddBoolToObject(j, "resumed", p->resumed);
    }
}

btf_status btf_report_json(const btf_report_data *d, const char *dir, btf_error *err)
{
    cJSON *root = cJSON_CreateObject();
    if (!root)
        return btf_fail(err, BTF_E_NOMEM, "report.json: out of memory");
    cJSON_AddStringToObject(root, "format", "btfcar-report");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON_AddStringToObject(root, "btfcar", BTF_VERSION_STRING);
    cJSON_AddStringToObject(root, "date", d->date);
    cJSON_AddStringToObject(root, "dataset", d->dataset_name);
    cJSON_AddStringToObject(root, "model", d->model_name);
    cJSON *ds = cJSON_AddObjectToObject(root, "dataset_info");
    cJSON_AddStringToObject(ds, "layout", btf_layout_name(d->in->layout));
    cJSON_AddNumberToObject(ds, "views", d->in->n_views);
    cJSON_AddNumberToObject(ds, "lights", d->in->n_lights);
    cJSON_AddNumberToObject(ds, "width", d->in->width);
    cJSON_AddNumberToObject(ds, "height", d->in->height);
    cJSON_AddNumberToObject(root, "subspaces", d->m->n_subspaces);
    cJSON_AddNumberToObject(root, "seconds", d->seconds);
    add_compression(root, d);
    add_quality(root, d);
    cJSON *pv = cJSON_AddObjectToObject(root, "preview");
    cJSON_AddStringToObject(pv, "picture", "sphere.png");
    add_dir(pv, "light", d->o->sphere_light);
    cJSON_AddNumberToObject(pv, "size", d->o->sphere_size);
    cJSON_AddNumberToObject(pv, "seconds", d->sphere_s);
    cJSON_AddNumberToObject(pv, "subspaces_needed", d->sphere_info.needed);
    add_sweep(root, d);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text)
        return btf_fail(err, BTF_E_NOMEM, "report.json: out of memory");
    char path[4096];
    btf_status rc = btf_path_join(path, sizeof path, dir, "report.json", err);
    if (rc == BTF_OK)
        rc = btf_write_file_atomic(path, text, strlen(text), err);
    cJSON_free(text);
    return rc;
}
