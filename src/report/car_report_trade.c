/*
 * car_report_trade.c — the CAR report's speed/accuracy trade
 * (docs/report.md, "The sweep"): with --sweep, the dataset analysed over a
 * grid of settings, each timed, sized and measured (btf__sweep_run), shown
 * as two Pareto plots, the front and a table, and in report.json's
 * "sweep"; without it, a note on how to measure it (and "sweep": null).
 */
#include "core/core.h"
#include "report/car_report_data.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void setting_text(const btf_sweep_setting *s, char *buf, size_t n)
{
    char k[16], l[16], nb[16];
    snprintf(k, sizeof k, s->subspaces ? "%d" : "auto", s->subspaces);
    snprintf(l, sizeof l, s->levels ? "%d" : "auto", s->levels);
    snprintf(nb, sizeof nb, s->neighbours ? "%d" : "auto", s->neighbours);
    char r[24] = "";
    if (s->range_size)
        snprintf(r, sizeof r, ", R %d", s->range_size);
    snprintf(buf, n, "K %s, L %s, N %s%s%s", k, l, nb, r, s->plain ? ", plain" : "");
}

static btf_status trade_files(const btf_report_base *r, const char *dir, btf_error *err)
{
    const btf_car_report *d = (const btf_car_report *)r;
    if (!d->have_sweep)
        return BTF_OK;
    const btf_sweep *s = &d->sweep;
    int n = s->n_points;
    double *x = btf__alloc((size_t)n * 3, sizeof(double), err);
    char (*labels)[48] = btf__alloc((size_t)n, 48, err);
    const char **lp = btf__alloc((size_t)n, sizeof(char *), err);
    btf_status rc = x && labels && lp ? BTF_OK : BTF_E_NOMEM;
    int marked = -1;
    for (int i = 0; rc == BTF_OK && i < n; i++) {
        x[i] = (double)s->points[i].bytes;
        x[n + i] = s->points[i].synth_s;
        x[2 * n + i] = s->points[i].mean_combined;
        setting_text(&s->points[i].setting, labels[i], 48);
        lp[i] = labels[i];
        if (s->points[i].is_default)
            marked = i;
    }
    for (int which = 0; rc == BTF_OK && which < 2; which++) {
        btf_scatter sc;
        memset(&sc, 0, sizeof sc);
        sc.n = n;
        sc.x = x + which * n;
        sc.y = x + 2 * n;
        sc.labels = lp;
        sc.title = which ? "Quality against synthesis time" : "Quality against model bytes";
        sc.x_title = which ? "CPU synthesis of every subspace image (s)" : "model file (bytes)";
        sc.y_title = "mean combined distance (lower is better)";
        sc.log_x = 1;
        sc.marked_label = marked >= 0 ? "default" : NULL;
        sc.marked = marked >= 0 ? marked : 0;
        char path[4096];
        rc = btf__path_join(path, sizeof path, dir, which ? "pareto-time.svg" : "pareto-bytes.svg",
                            err);
        if (rc == BTF_OK)
            rc = btf__svg_scatter_write(path, &sc, err);
    }
    BTF_FREE_ALL(x, labels, lp);
    return rc;
}

static void trade_html(btf_buf *b, const btf_report_base *r)
{
    const btf_car_report *d = (const btf_car_report *)r;
    btf__buf_puts(b, "<h2>The speed/accuracy trade</h2>\n");
    if (!d->have_sweep) {
        btf__buf_puts(b, "<p class=\"note\">Not measured: <code>btfcar report DATASET MODEL -o "
                        "DIR --sweep</code> analyses the dataset over a grid of settings and "
                        "shows here what each costs and gives. <code>btfcar analyse --preset "
                        "fast|balanced|accurate</code> picks a point measured on the "
                        "generated materials (docs/report.md).</p>\n");
        return;
    }
    const btf_sweep *s = &d->sweep;
    btf__buf_printf(b, "<p class=\"note\">The dataset analysed under %d settings: K subspace "
                      "images, L pyramid levels, N neighbours (a fixed neighbourhood of the "
                      "first N candidate offsets; auto: the Bayesian choice per band). The "
                      "features and the range map were computed once (" BTF_HTML_TIME("%.1f s") ") and shared; "
                      "settings ran in parallel, one thread each. Analysis: segmentation "
                      "and the CAR fits of that setting; synthesis: every subspace image at "
                      "%d² on the CPU, in one batch as btfcar synthesise makes them "
                      "(colour matching beside the fields); render: the sphere frame at "
                      "%d², one thread; "
                      "quality: the mean and worst combined distance over the pairs above, "
                      "each the mean over %d synthesis seeds (± : the standard deviation "
                      "of the mean between the seeds). "
                      "%d of %d points were read back from an earlier run.</p>\n",
                   s->n_points, s->shared_s, r->o->sweep_opts.synth_size,
                   r->o->sweep_opts.render_size, s->seeds, s->resumed, s->n_points);
    btf__buf_puts(b, "<figure><img class=\"plot\" src=\"pareto-bytes.svg\" alt=\"quality "
                    "against model bytes\"></figure>\n<figure><img class=\"plot\" "
                    "src=\"pareto-time.svg\" alt=\"quality against synthesis time\"></figure>"
                    "\n<p><b>Pareto-optimal</b> (no other setting is both smaller and "
                    "closer): ");
    int first = 1;
    for (int i = 0; i < s->n_points; i++)
        if (s->points[i].pareto_bytes || s->points[i].pareto_time) {
            char t[64];
            setting_text(&s->points[i].setting, t, sizeof t);
            btf__buf_printf(b, "%s%s (%s)", first ? "" : "; ", t,
                            s->points[i].pareto_bytes && s->points[i].pareto_time
                               ? "bytes and time"
                               : s->points[i].pareto_bytes ? "bytes" : "time");
            first = 0;
        }
    btf__buf_puts(b, ".</p>\n<table>\n<tr><th class=\"l\">setting</th><th>K made</th>"
                    "<th>analysis s</th><th>synthesis s</th><th>GPU s</th><th>render s</th>"
                    "<th>bytes</th><th>mean</th><th>±</th><th>worst</th>"
                    "<th class=\"l\">front</th></tr>\n");
    for (int i = 0; i < s->n_points; i++) {
        const btf_sweep_point *p = &s->points[i];
        char t[64], g[32];
        setting_text(&p->setting, t, sizeof t);
        if (p->gpu_synth_s >= 0)
            snprintf(g, sizeof g, "%.3f", p->gpu_synth_s);
        else
            snprintf(g, sizeof g, "–");
        btf__buf_printf(b, "<tr class=\"%s%s\"><td class=\"l\">%s%s</td><td>%d</td><td class=\"time\">%.2f</td>"
                          "<td class=\"time\">%.3f</td><td class=\"time\">%s</td><td class=\"time\">%.3f</td>"
                          "<td>%llu</td><td>%.3f</td>"
                          "<td>%.3f</td><td>%.2f</td><td class=\"l\">%s%s</td></tr>\n",
                       p->is_default ? "def " : "",
                       p->pareto_bytes || p->pareto_time ? "front" : "", t,
                       p->is_default ? " (default)" : "", p->k, p->analyse_s, p->synth_s, g,
                       p->render_s, (unsigned long long)p->bytes, p->mean_combined,
                       p->seed_spread, p->worst_combined, p->pareto_bytes ? "bytes " : "",
                       p->pareto_time ? "time" : "");
    }
    btf__buf_puts(b, "</table>\n<p class=\"note\">No GPU time where no GPU was present (a CPU "
                    "Vulkan driver is not timed).</p>\n");
}

static void trade_json(cJSON *root, const btf_report_base *r)
{
    const btf_car_report *d = (const btf_car_report *)r;
    if (!d->have_sweep) {
        cJSON_AddNullToObject(root, "sweep");
        return;
    }
    const btf_sweep *s = &d->sweep;
    cJSON *o = cJSON_AddObjectToObject(root, "sweep");
    cJSON_AddNumberToObject(o, "shared_seconds", s->shared_s);
    cJSON_AddNumberToObject(o, "seconds", s->seconds);
    cJSON_AddNumberToObject(o, "resumed", s->resumed);
    cJSON_AddNumberToObject(o, "synth_size", r->o->sweep_opts.synth_size);
    cJSON_AddNumberToObject(o, "render_size", r->o->sweep_opts.render_size);
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

const btf_report_section btf__car_trade = {trade_files, trade_html, trade_json};
