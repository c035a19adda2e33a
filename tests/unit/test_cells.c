/*
 * test_cells.c — the remainders' periodic cells (format 1.7; docs/model.md,
 * "Periodic cells"; docs/model-format.md, "CELL"): a lattice's cell in
 * Hermite normal form, the file's round trip and its refusals, and the
 * analysis of generated materials: the weave keeps a cell for the
 * subspaces where one holds and their CAR fields then miss less of their
 * variance, the
 * leather (no lattice) keeps none, and synthesis places the cell.
 */
#include "testutil.h"
#include "model/model.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Every lattice translate of a texel lies in the same cell texel, and the
 * cell texels are exactly w x h. */
static void check_cell(const int L[4], int w, int h)
{
    int cw, ch, shift;
    assert_int_equal(btf__cells_from_lattice(L, &cw, &ch, &shift), 1);
    assert_int_equal(cw, w);
    assert_int_equal(ch, h);
    assert_true(shift >= 0 && shift < cw);
    btf_cells c = {cw, ch, shift, 1, NULL, NULL};
    int *seen = calloc((size_t)cw * ch, sizeof(int));
    for (int y = -40; y < 40; y++)
        for (int x = -40; x < 40; x++) {
            int i = btf__cell_index(&c, x, y);
            assert_true(i >= 0 && i < cw * ch);
            seen[i] = 1;
            assert_int_equal(btf__cell_index(&c, x + L[0], y + L[1]), i);
            assert_int_equal(btf__cell_index(&c, x - L[2], y - L[3]), i);
        }
    for (int i = 0; i < cw * ch; i++)
        assert_int_equal(seen[i], 1);
    free(seen);
}

static void hermite_cell(void **state)
{
    (void)state;
    check_cell((const int[4]){8, -8, -8, -8}, 16, 8); /* the generated fabric's */
    check_cell((const int[4]){6, 6, 6, -6}, 12, 6);
    check_cell((const int[4]){0, 5, 7, 0}, 7, 5);
    check_cell((const int[4]){3, 1, 1, 4}, 11, 1);
    int w, h, s;
    assert_int_equal(btf__cells_from_lattice((const int[4]){4, 2, 8, 4}, &w, &h, &s), 0);
    assert_int_equal(btf__cells_from_lattice((const int[4]){100, 0, 0, 100}, &w, &h, &s), 0);
}

/* A small model with a structure layer and cells for two subspaces of
 * three (the second left out). */
static void model_with_cells(btf_model *m)
{
    btf_error e = {0};
    memset(m, 0, sizeof *m);
    btf_dir v[2] = {{0, 0}, {30, 90}}, l[2] = {{0, 0}, {45, 90}};
    TU_OK(btf_dirset_from_list(&m->views, v, 2, &e), &e);
    TU_OK(btf_dirset_from_list(&m->lights, l, 2, &e), &e);
    m->n_subspaces = 3;
    m->subspaces = calloc(3, sizeof *m->subspaces);
    for (int k = 0; k < 3; k++) {
        btf_subspace_model *s = &m->subspaces[k];
        s->width = s->height = 16;
        s->basis[0] = s->basis[4] = s->basis[8] = 1.0f;
        s->mean[0] = s->mean[1] = s->mean[2] = 0.4f;
        s->levels = 1;
    }
    m->index = calloc(4, 1);
    m->index[1] = 1, m->index[2] = 2;
    int n = 16;
    m->range_width = m->range_height = n;
    m->range_texel = 1.0f;
    m->range = calloc((size_t)n * n, sizeof(float));
    m->albedo = malloc((size_t)n * n * sizeof(float));
    for (int i = 0; i < n * n; i++)
        m->albedo[i] = btf__albedo_value(120u + (unsigned)(i % 9));
    btf_cells *c = btf__cells_new(4, 2, 2, 3, &e);
    assert_non_null(c);
    for (int k = 0; k < 3; k += 2) {
        c->kept[k] = 1;
        for (int i = 0; i < 4 * 2 * 3; i++)
            c->value[k * 24 + i] = btf__albedo_value(110u + (unsigned)((i * 7 + k) % 37));
    }
    TU_OK(btf__model_set_cells(m, c, &e), &e);
}

/* One byte of CELL's body changed: the decoder refuses the file naming
 * the section, on one line. */
static void refused(const unsigned char *p, size_t pn, size_t at, unsigned char v,
                    const char *what)
{
    unsigned char *q = malloc(pn);
    memcpy(q, p, pn);
    q[at] = v;
    size_t bad_n;
    unsigned char *bad = tu_model_rewrap(q, pn, 7, &bad_n);
    btf_model back;
    btf_error e = {0};
    assert_int_equal(btf_model_decode(bad, bad_n, what, &back, &e), BTF_E_FORMAT);
    print_message("%s: %s\n", what, e.msg);
    assert_non_null(strstr(e.msg, "CELL"));
    assert_null(strchr(e.msg, '\n'));
    free(bad);
    free(q);
}

static void file_round_trip(void **state)
{
    (void)state;
    btf_error e = {0};
    btf_model m, back;
    model_with_cells(&m);
    unsigned char *f = NULL;
    size_t size = 0;
    TU_OK(btf_model_encode(&m, &f, &size, &e), &e);
    assert_int_equal(f[13], 7); /* format 1.7 */
    TU_OK(btf_model_decode(f, size, "cells", &back, &e), &e);
    const btf_cells *a = btf__model_cells(&m), *b = btf__model_cells(&back);
    assert_non_null(b);
    assert_int_equal(b->w, 4);
    assert_int_equal(b->h, 2);
    assert_int_equal(b->shift, 2);
    assert_memory_equal(b->kept, a->kept, 3);
    assert_memory_equal(b->value, a->value, 3 * 24 * sizeof(float));
    btf_model_free(&back);

    size_t pn;
    unsigned char *p = tu_model_payload(f, &pn);
    size_t body = tu_rf_section(p, pn, "CELL"); /* after its tag and length */
    assert_true(body > 0);
    refused(p, pn, body + 4, 4, "shift at the width");   /* shift (u16 LE) = w */
    refused(p, pn, body + 6, 2, "subspaces");            /* 2 of SUBS's 3 */
    refused(p, pn, body + 8 + 1, 1, "flag of a cell");   /* a kept flag: 1 more cell's bytes */
    refused(p, pn, body + 8 + 2, 2, "flag 2");
    free(p);
    free(f);

    /* cells without the structure layer, or of a factor 0: refused to write */
    btf_cells *c = (btf_cells *)btf__model_cells(&m);
    c->value[5] = 0.0f;
    assert_int_equal(btf_model_encode(&m, &f, &size, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "periodic cell"));
    c->value[5] = 1.0f;
    free(m.albedo);
    m.albedo = NULL;
    assert_int_equal(btf_model_encode(&m, &f, &size, &e), BTF_E_DATA);
    assert_non_null(strstr(e.msg, "periodic cells without"));
    btf_model_free(&m);
}

/* The variance the CAR fields synthesise (the marginals' synthesised
 * deviations, summed over the bands) of the subspaces that keep a cell in
 * c, over the subspaces' mean luminance squared. */
static double fields_variance(const btf_model *m, const btf_cells *c)
{
    double v = 0.0;
    for (int k = 0; k < m->n_subspaces; k++) {
        const btf_subspace_model *s = &m->subspaces[k];
        double mean = (s->mean[0] + s->mean[1] + s->mean[2]) / 3.0;
        for (int b = 0; b < 3 && c->kept[k]; b++)
            v += (double)s->marginal.synth_sd[b] * s->marginal.synth_sd[b] / (mean * mean);
    }
    return v;
}

/* Generated materials at 64 texels (the weave's repeat, (8, 8), fits three
 * times). */
static void analysed_cells(void **state)
{
    (void)state;
    btf_error e = {0};
    char path[512];
    btf_dataset *ds = NULL;
    assert_int_equal(tu_generate_dataset("fabric", 64, 3, path, sizeof path, &ds), 0);
    btf_model m, none;
    btf_analyse_report rep;
    btf_analyse_opts o = btf_analyse_defaults();
    o.report = &rep;
    TU_OK(btf_analyse(ds, &o, &m, &e), &e);
    print_message("fabric: %s\n", rep.structure_reason);
    assert_non_null(strstr(rep.structure_reason, "periodic cells of 16 x 8 texels"));
    const btf_cells *c = btf__model_cells(&m);
    assert_true(btf__cells_any(c));
    o.no_cells = 1;
    TU_OK(btf_analyse(ds, &o, &none, &e), &e);
    assert_null(btf__model_cells(&none));
    assert_null(strstr(rep.structure_reason, "periodic"));
    /* where a subspace keeps its cell, its fields model what is left: a
     * fraction of the variance (the same subspaces: the segmentation does
     * not depend on the cells) */
    double with = fields_variance(&m, c), without = fields_variance(&none, c);
    print_message("fabric: the fields' relative variance where a cell is kept %.4g, %.4g "
                  "without the cells\n", with, without);
    assert_true(with < 0.5 * without);
    /* not every subspace keeps one: a cell that makes the member lit
     * farthest from its exemplar worse is left out */
    int kept = 0;
    for (int k = 0; k < c->n_subspaces; k++)
        kept += c->kept[k];
    assert_true(kept >= 1 && kept <= c->n_subspaces);

    /* synthesis places the cell: a subspace image with the cell against
     * the same model with cells of 1s differs exactly by the factor */
    btf_synth_opts so = btf_synth_defaults();
    so.width = so.height = 64;
    so.match_colours = -1; /* off: the factor alone */
    int k = 0;
    while (!c->kept[k])
        k++;
    btf_image a = {0}, b = {0};
    TU_OK(btf_synthesise_image(&m, k, &so, &a, &e), &e);
    btf_cells *ones = btf__cells_new(c->w, c->h, c->shift, c->n_subspaces, &e);
    memcpy(ones->kept, c->kept, (size_t)c->n_subspaces);
    btf_cells *kept_cells = (btf_cells *)c;
    btf_cells saved = *kept_cells;
    kept_cells->value = ones->value; /* the same model, its cells all 1 */
    TU_OK(btf_synthesise_image(&m, k, &so, &b, &e), &e);
    kept_cells->value = saved.value;
    btf__cells_free(ones);
    double ratio_spread = 0.0;
    int differ = 0;
    for (size_t i = 0; i < (size_t)64 * 64 * 3; i++)
        differ += a.data[i] != b.data[i];
    assert_true(differ > 64 * 64); /* the factor is not 1 everywhere */
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            const float *f = btf__cells_of(c, k) + 3 * btf__cell_index(c, x, y);
            for (int ch = 0; ch < 3; ch++) {
                size_t i = ((size_t)y * 64 + x) * 3 + ch;
                if (b.data[i] > 1e-6f)
                    ratio_spread = fmax(ratio_spread, fabs(a.data[i] / b.data[i] / f[ch] - 1.0));
            }
        }
    print_message("fabric: synthesis / cell factor within %.2g of the image without\n",
                  ratio_spread);
    assert_true(ratio_spread < 1e-5);
    btf_image_free(&a);
    btf_image_free(&b);
    btf_model_free(&m);
    btf_model_free(&none);
    btf_dataset_close(ds);

    /* the leather has no lattice: no cells, and its model is as before */
    assert_int_equal(tu_generate_dataset("leather", 64, 3, path, sizeof path, &ds), 0);
    o.no_cells = 0;
    TU_OK(btf_analyse(ds, &o, &m, &e), &e);
    assert_null(btf__model_cells(&m));
    assert_null(strstr(rep.structure_reason, "periodic cells of"));
    btf_model_free(&m);
    btf_dataset_close(ds);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(hermite_cell),
        cmocka_unit_test(file_round_trip),
        cmocka_unit_test(analysed_cells),
    };
    return cmocka_run_group_tests(tests, tu_setup_dir, tu_teardown_dir);
}
