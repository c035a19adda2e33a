/*
 * car_describe.c — btfcar info on a CAR model file (MODEL.btfcar): its
 * direction sets, index table, range map (Haindl & Filip 2007, section II.B) and every
 * subspace's spectral basis and CAR parameters per band and level (section
 * II.C) with each band's synthesis margin, as text or (--json) as the JSON
 * document of docs/model-format.md ("btfcar info --json"). The CAR
 * family's describe (src/material/: btf_material_describe).
 */
#include "material/family.h"
#include "model/model.h"

#include <math.h>

/* The synthesis margin of a band (-1 should the library run out of memory). */
static int band_margin(const btf_model *m, int s, int b, int l)
{
    int margin = -1;
    btf_error err = {0};
    btf_synth_margin(m, s, b, l, &margin, &err);
    return margin;
}

/* The fraction of a band's variance synthesis misses (0 should the library
 * run out of memory: the report is not the model's check). */
static double band_missed(const btf_model *m, int s, int b, int l)
{
    double missed = 0.0;
    btf_error err = {0};
    if (btf_synth_missed_variance(m, s, b, l, &missed, &err) != 0)
        missed = 0.0;
    return missed;
}

/* "0:-1,-1:0", the neighbourhood SPEC syntax of the command line. */
static void format_neighbourhood(const btf_car_band *b, char *buf, size_t n)
{
    size_t k = 0;
    buf[0] = '\0';
    for (int i = 0; i < b->n && k < n; i++)
        k += (size_t)snprintf(buf + k, n - k, "%s%d:%d", i ? "," : "", b->offsets[i].row,
                              b->offsets[i].col);
}

static void range_bounds(const btf_model *m, float *lo, float *hi)
{
    size_t n = (size_t)m->range_width * m->range_height;
    *lo = *hi = m->range[0];
    for (size_t i = 1; i < n; i++) {
        *lo = fminf(*lo, m->range[i]);
        *hi = fmaxf(*hi, m->range[i]);
    }
}

/* Index table cells per subspace (how many (view, light) pairs it serves). */
static int members(const btf_model *m, int s)
{
    int n = 0;
    for (int i = 0; i < m->views.count * m->lights.count; i++)
        n += m->index[i] == s;
    return n;
}

static void text_subspace(FILE *f, const btf_model *m, int s)
{
    const btf_subspace_model *sm = &m->subspaces[s];
    fprintf(f, "subspace %d  ", s);
    if (sm->view >= 0)
        fprintf(f, "view %d (theta %g, phi %g), light %d (theta %g, phi %g), %d images; ", sm->view,
                m->views.dirs[sm->view].theta, m->views.dirs[sm->view].phi, sm->light,
                m->lights.dirs[sm->light].theta, m->lights.dirs[sm->light].phi, members(m, s));
    fprintf(f, "%d x %d, %d level%s\n", sm->width, sm->height, sm->levels,
            sm->levels == 1 ? "" : "s");
    fprintf(f, "  mean      %.6g %.6g %.6g\n", sm->mean[0], sm->mean[1], sm->mean[2]);
    fprintf(f, "  basis     [%.6g %.6g %.6g] [%.6g %.6g %.6g] [%.6g %.6g %.6g]\n", sm->basis[0],
            sm->basis[1], sm->basis[2], sm->basis[3], sm->basis[4], sm->basis[5], sm->basis[6],
            sm->basis[7], sm->basis[8]);
    for (int b = 0; b < 3; b++)
        for (int l = 0; l < sm->levels; l++) {
            const btf_car_band *cb = &sm->bands[b][l];
            char nb[BTF_CAR_MAX_NEIGHBOURS * 10 + 1];
            format_neighbourhood(cb, nb, sizeof nb);
            fprintf(f, "  band %d level %d: %s  gamma", b, l, cb->n ? nb : "(none)");
            for (int i = 0; i < cb->n; i++)
                fprintf(f, " %.6g", cb->gamma[i]);
            fprintf(f, "  sigma %.6g  mean %.6g  margin %d", cb->sigma, cb->mean,
                    band_margin(m, s, b, l));
            double missed = band_missed(m, s, b, l);
            if (missed >= 0.01)
                fprintf(f, "  misses %.0f%% of its variance in synthesis%s", 100.0 * missed,
                        missed >= BTF_CAR_MISSED_LOUD ? " (a periodic pattern?)" : "");
            fprintf(f, "\n");
        }
    const btf_marginal *mg = &sm->marginal;
    if (!mg->knots) {
        fprintf(f, "  marginals none (Gaussian bands: no transfer, no clamp)\n");
        return;
    }
    fprintf(f, "  marginals %d-knot transfer per band; exemplar range", mg->knots);
    for (int b = 0; b < 3; b++)
        fprintf(f, " [%.6g, %.6g]", mg->quantile[b][0], mg->quantile[b][mg->knots - 1]);
    fprintf(f, "; synthesised sd %.6g %.6g %.6g; RGB box [%.6g %.6g %.6g]..[%.6g %.6g %.6g]\n",
            mg->synth_sd[0], mg->synth_sd[1], mg->synth_sd[2], mg->rgb_lo[0], mg->rgb_lo[1],
            mg->rgb_lo[2], mg->rgb_hi[0], mg->rgb_hi[1], mg->rgb_hi[2]);
    if (mg->lab_knots)
        fprintf(f, "  colours   Lab histogram: L* %.4g..%.4g (median %.4g), a* %.4g..%.4g, b* "
                "%.4g..%.4g\n", mg->lab_quantile[0][0], mg->lab_quantile[0][mg->lab_knots - 1],
                mg->lab_quantile[0][mg->lab_knots / 2], mg->lab_quantile[1][0],
                mg->lab_quantile[1][mg->lab_knots - 1], mg->lab_quantile[2][0],
                mg->lab_quantile[2][mg->lab_knots - 1]);
}

/* The remainders' periodic cells, when the model keeps them. */
static void text_cells(FILE *f, const btf_model *m)
{
    const btf_cells *c = btf__model_cells(m);
    if (!btf__cells_any(c))
        return;
    int kept = 0;
    for (int k = 0; k < c->n_subspaces; k++)
        kept += c->kept[k];
    fprintf(f, "cells       the structure repeats on a lattice: a periodic cell of %d x %d texels "
            "(shift %d) for %d of %d subspaces divides their remainders; the CAR fields model "
            "what is left (docs/model.md, \"Periodic cells\")\n", c->w, c->h, c->shift, kept,
            c->n_subspaces);
}

static void model_text(FILE *f, const btf_model *m, const describe_file *mf)
{
    char views[128], lights[128];
    fprintf(f, "model       %s\n", mf->path);
    /* Exact bytes: models are a few kilobytes, the figure users compare. */
    fprintf(f, "format      btfcar model %u.%u, %lld bytes\n", mf->major, mf->minor, mf->bytes);
    if (m->views.count) {
        txt_describe_set(&m->views, views, sizeof views);
        txt_describe_set(&m->lights, lights, sizeof lights);
        fprintf(f, "views       %s\n", views);
        fprintf(f, "lights      %s\n", lights);
        int pairs = m->views.count * m->lights.count, measured = 0;
        for (int i = 0; i < pairs; i++)
            measured += m->index[i] != BTF_PAIR_NONE;
        if (measured < pairs)
            fprintf(f, "index       %d views x %d lights -> %d subspaces; %d of the %d pairs "
                    "measured (a sparse set: the others stand for their nearest measured "
                    "pair)\n", m->views.count, m->lights.count, m->n_subspaces, measured, pairs);
        else
            fprintf(f, "index       %d views x %d lights -> %d subspaces\n", m->views.count,
                    m->lights.count, m->n_subspaces);
    } else {
        fprintf(f, "views       none (a single texture)\n");
        fprintf(f, "lights      none (a single texture)\n");
    }
    fprintf(f, "subspaces   %d\n", m->n_subspaces);
    int with = 0;
    for (int s = 0; s < m->n_subspaces; s++)
        with += m->subspaces[s].marginal.knots != 0;
    fprintf(f, "marginals   %s (%d of %d subspaces)\n",
            with ? "transfers onto the exemplar's histogram, RGB clamped to its range"
                : "none (Gaussian bands; format 1.0/1.1 or fitted without them)",
            with, m->n_subspaces);
    int lab = 0;
    for (int s = 0; s < m->n_subspaces; s++)
        lab += m->subspaces[s].marginal.knots && m->subspaces[s].marginal.lab_knots;
    fprintf(f, "colours     %s (%d of %d subspaces)\n",
            lab ? "the exemplar's CIE Lab histogram: synthesis matches it "
                  "(--no-match-colours skips)"
               : "no Lab histogram (format 1.2 or older): synthesis without colour matching",
            lab, m->n_subspaces);
    if (m->range && m->range_texel == 1.0f) {
        float lo, hi;
        range_bounds(m, &lo, &hi);
        /* at the analysed resolution: the measured map, quilted onto a surface */
        fprintf(f, "range map   %d x %d at the analysed resolution (texel 1), quilted onto any "
                "surface, heights %.6g..%.6g\n", m->range_width, m->range_height, lo, hi);
    } else if (m->range) {
        float lo, hi;
        range_bounds(m, &lo, &hi);
        /* the tile in memory is periodic: a 1.0 file's is made so on reading */
        fprintf(f, "range map   %d x %d periodic tile%s, texel %g (a period of %g x %g analysed "
                "texels), heights %.6g..%.6g\n", m->range_width, m->range_height,
                mf->major == 1 && mf->minor == 0 ? " (made periodic on reading: format 1.0)" : "",
                m->range_texel, m->range_width * (double)m->range_texel,
                m->range_height * (double)m->range_texel, lo, hi);
    } else {
        fprintf(f, "range map   none\n");
    }
    if (m->albedo)
        fprintf(f, "structure   albedo pattern (grey%s), shading a + %smax(0, n.l) with "
                "ambient a = %.4g: the CAR fields model the remainder (docs/model.md)\n",
                m->chroma ? " and a colour layer: the colours vary across the sample" : ": one "
                "colour across the sample", m->shadows ? "vis " : "", m->ambient);
    else
        fprintf(f, "structure   none: the CAR fields model the whole exemplars%s\n",
                m->range && m->range_texel != 1.0f ? " (a range tile below the analysed "
                "resolution holds no albedo)" : "");
    if (m->shadows)
        fprintf(f, "shadows     the relief casts them (horizon map of the range map)\n");
    text_cells(f, m);
    fprintf(f, "pair gains  %s\n", m->gain ? "one colour per measured pair: each keeps its mean "
            "colour" : "none (format 1.4 or older, or analysed without them)");
    for (int s = 0; s < m->n_subspaces; s++)
        text_subspace(f, m, s);
}

static void json_band(FILE *f, const btf_car_band *b, int margin, double missed)
{
    char nb[BTF_CAR_MAX_NEIGHBOURS * 10 + 1];
    format_neighbourhood(b, nb, sizeof nb);
    fputs("{\"neighbourhood\": ", f);
    txt_json_string(f, nb);
    fputs(", \"offsets\": [", f);
    for (int i = 0; i < b->n; i++)
        fprintf(f, "%s[%d, %d]", i ? ", " : "", b->offsets[i].row, b->offsets[i].col);
    fputs("], \"gamma\": ", f);
    txt_json_f32s(f, b->gamma, b->n);
    fputs(", \"sigma\": ", f);
    txt_json_f32(f, b->sigma);
    fputs(", \"mean\": ", f);
    txt_json_f32(f, b->mean);
    fprintf(f, ", \"margin\": %d, \"missed_variance\": %.3g", margin, missed);
    fputc('}', f);
}

static void json_subspace(FILE *f, const btf_model *m, int s)
{
    const btf_subspace_model *sm = &m->subspaces[s];
    fprintf(f, "{\"view\": %d, \"light\": %d, \"width\": %d, \"height\": %d, \"mean\": ",
            sm->view, sm->light, sm->width, sm->height);
    txt_json_f32s(f, sm->mean, 3);
    fputs(", \"basis\": [", f);
    for (int r = 0; r < 3; r++) {
        fputs(r ? ", " : "", f);
        txt_json_f32s(f, sm->basis + 3 * r, 3);
    }
    fprintf(f, "], \"levels\": %d,\n   \"bands\": [", sm->levels);
    for (int b = 0; b < 3; b++) {
        fputs(b ? ",\n    [" : "\n    [", f);
        for (int l = 0; l < sm->levels; l++) {
            fputs(l ? ",\n     " : "", f);
            json_band(f, &sm->bands[b][l], band_margin(m, s, b, l), band_missed(m, s, b, l));
        }
        fputc(']', f);
    }
    const btf_marginal *mg = &sm->marginal;
    fputs("],\n   \"marginal\": ", f);
    if (!mg->knots) {
        fputs("null}", f);
        return;
    }
    fprintf(f, "{\"knots\": %d, \"synth_mean\": ", mg->knots);
    txt_json_f32s(f, mg->synth_mean, 3);
    fputs(", \"synth_sd\": ", f);
    txt_json_f32s(f, mg->synth_sd, 3);
    fputs(", \"quantiles\": [", f);
    for (int b = 0; b < 3; b++) {
        fputs(b ? ", " : "", f);
        txt_json_f32s(f, mg->quantile[b], mg->knots);
    }
    fputs("], \"rgb_lo\": ", f);
    txt_json_f32s(f, mg->rgb_lo, 3);
    fputs(", \"rgb_hi\": ", f);
    txt_json_f32s(f, mg->rgb_hi, 3);
    fputs(", \"lab_quantiles\": ", f);
    if (!mg->lab_knots) {
        fputs("null}}", f);
        return;
    }
    for (int c = 0; c < 3; c++) {
        fputs(c ? ", " : "[", f);
        txt_json_f32s(f, mg->lab_quantile[c], mg->lab_knots);
    }
    fputs("]}}", f);
}

static void json_index(FILE *f, const btf_model *m)
{
    if (!m->index) {
        fputs("null", f);
        return;
    }
    fputc('[', f);
    for (int v = 0; v < m->views.count; v++) {
        fputs(v ? ",\n   [" : "\n   [", f);
        for (int l = 0; l < m->lights.count; l++)
            fprintf(f, "%s%u", l ? ", " : "", m->index[v * m->lights.count + l]);
        fputc(']', f);
    }
    fputc(']', f);
}

static void model_json(FILE *f, const btf_model *m, const describe_file *mf)
{
    fprintf(f, "{\"format\": \"btfcar-model\", \"version\": [%u, %u], \"file\": ", mf->major,
            mf->minor);
    txt_json_string(f, mf->path);
    fprintf(f, ", \"file_bytes\": %lld,\n \"views\": ", mf->bytes);
    txt_json_dirset(f, &m->views);
    fputs(",\n \"lights\": ", f);
    txt_json_dirset(f, &m->lights);
    fputs(",\n \"index\": ", f);
    json_index(f, m);
    fprintf(f, ",\n \"subspaces\": [");
    for (int s = 0; s < m->n_subspaces; s++) {
        fputs(s ? ",\n  " : "\n  ", f);
        json_subspace(f, m, s);
    }
    fputs("],\n \"range\": ", f);
    if (m->range) {
        float lo, hi;
        range_bounds(m, &lo, &hi);
        fprintf(f, "{\"width\": %d, \"height\": %d, \"texel\": ", m->range_width,
                m->range_height);
        txt_json_f32(f, m->range_texel);
        fputs(", \"min\": ", f);
        txt_json_f32(f, lo);
        fputs(", \"max\": ", f);
        txt_json_f32(f, hi);
        fprintf(f, ", \"periodic\": %s}", m->range_texel == 1.0f ? "false" : "true");
    } else {
        fputs("null", f);
    }
    fputs(",\n \"structure\": ", f);
    if (m->albedo) {
        fprintf(f, "{\"albedo\": true, \"colour_layer\": %s, \"shadows\": %s, \"ambient\": ",
                m->chroma ? "true" : "false", m->shadows ? "true" : "false");
        txt_json_f32(f, m->ambient);
        fputs("}", f);
    } else {
        fputs("null", f);
    }
    const btf_cells *c = btf__model_cells(m);
    if (btf__cells_any(c)) {
        fprintf(f, ",\n \"cells\": {\"width\": %d, \"height\": %d, \"shift\": %d, \"kept\": [",
                c->w, c->h, c->shift);
        for (int k = 0; k < c->n_subspaces; k++)
            fprintf(f, "%s%s", k ? ", " : "", c->kept[k] ? "true" : "false");
        fputs("]}", f);
    } else {
        fputs(",\n \"cells\": null", f);
    }
    fprintf(f, ",\n \"pair_gains\": %s", m->gain ? "true" : "false");
    fputs("}\n", f);
}

void car_describe(const btf_model *m, const describe_file *file, FILE *f, int json)
{
    if (json)
        model_json(f, m, file);
    else
        model_text(f, m, file);
}
