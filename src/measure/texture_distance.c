/*
 * texture_distance.c — btf_texture_distance (docs/measure.md): three
 * distances between a reference texture and an image of any size, with no
 * pixel correspondence, each normalised by the reference's own
 * variability. The normalisation is what makes the figures readable: the
 * same distance between the reference's four quadrants (disjoint crops of
 * one material) is what "as close as the material is to itself" measures,
 * so a normalised 1.0 is a faithful texture and 3.0 is three times as far
 * from the reference as the material is from itself.
 */
#include "core/core.h"
#include "measure/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The smallest self-distance divided by (same units as raw): a constant or
 * perfectly uniform reference has self-distance 0, and dividing by these
 * instead keeps the normalised figures finite. Each is far below the
 * self-distance of any real texture (docs/measure.md, "Normalisation"). */
#define FLOOR_SPECTRUM 0.1     /* dB */
#define FLOOR_FIRST_ORDER 0.1  /* Lab units */
#define FLOOR_STRUCTURE 0.01

enum { VIEW_REF, VIEW_IMG, VIEW_Q0, VIEWS = VIEW_Q0 + 4 };

btf_texture_distance_opts btf_texture_distance_defaults(void)
{
    btf_texture_distance_opts o = {.struct_size = sizeof o,
                                   .levels = 0, .reference_name = NULL, .image_name = NULL};
    return o;
}

static btf_status check_image(const btf_image *img, const char *name, btf_error *err)
{
    if (!img || !img->data)
        return btf__fail(err, BTF_E_ARG, "%s: no image", name);
    if (img->channels != 1 && img->channels != 3)
        return btf__fail(err, BTF_E_ARG, "%s: %d channels, expected 1 or 3", name,
                         img->channels);
    if (img->width < MS_MIN_SIDE || img->height < MS_MIN_SIDE)
        return btf__fail(err, BTF_E_ARG,
                         "%s: %dx%d is too small to measure as a texture: each side must be "
                         "at least %d", name, img->width, img->height, MS_MIN_SIDE);
    return BTF_OK;
}

/* Levels whose smallest band, in the smallest view (side s), keeps at
 * least 8 pixels: 1 + floor(log2(s / 8)), at most MS_MAX_LEVELS. */
static int auto_levels(int s)
{
    int l = 1;
    while (l < MS_MAX_LEVELS && (s >> l) >= 8)
        l++;
    return l;
}

static void component(btf_distance_component *c, double raw, double self, double floor_)
{
    c->raw = raw;
    c->self = self;
    c->normalised = raw / (self > floor_ ? self : floor_);
}

static int all_finite(const btf_texture_distances *d)
{
    const btf_distance_component *c[3] = {&d->spectrum, &d->first_order, &d->structure};
    for (int i = 0; i < 3; i++)
        if (!isfinite(c[i]->raw) || !isfinite(c[i]->self) || !isfinite(c[i]->normalised))
            return 0;
    return isfinite(d->combined);
}

/* The quadrants are a quarter of the reference: their statistics are
 * noisier than the whole reference's and the image's, and what separates
 * two samples of one stationary texture is mostly that noise, whose
 * standard deviation falls as 1 / sqrt(pixels). The distance between two
 * samples of N1 and N2 pixels then grows as sqrt(1/N1 + 1/N2): the
 * quadrants' self-distance is rescaled from sqrt(2/Nq) to
 * sqrt(1/Nref + 1/Nimg), so that a faithful image of any size scores about
 * 1 (docs/measure.md, "Normalisation"). Same sizes: the factor is 1/2. */
static double sample_correction(const btf_image *ref, const btf_image *img)
{
    double nq = (double)(ref->width / 2) * (double)(ref->height / 2);
    double nr = (double)ref->width * ref->height, ni = (double)img->width * img->height;
    return sqrt((1.0 / nr + 1.0 / ni) / (2.0 / nq));
}

/* The three raw distances of one pair of views. */
static void distances(const ms_desc *a, const ms_desc *b, double out[3], double lab[3])
{
    out[0] = ms_spectrum_distance(a->spectrum, b->spectrum, a->nbins);
    out[1] = ms_first_order_distance(a, b, lab);
    out[2] = ms_structure_distance(a->bands, b->bands, a->levels);
}

static btf_status measure(const float *lab_ref, const btf_image *ref, const float *lab_img,
                          const btf_image *img, int s, int levels, btf_texture_distances *out,
                          btf_error *err)
{
    int qw = ref->width / 2, qh = ref->height / 2;
    ms_view v[VIEWS] = {
        [VIEW_REF] = {lab_ref, ref->width, 0, 0, ref->width, ref->height},
        [VIEW_IMG] = {lab_img, img->width, 0, 0, img->width, img->height},
    };
    for (int q = 0; q < 4; q++)
        v[VIEW_Q0 + q] = (ms_view){lab_ref, ref->width, (q & 1) * qw, (q >> 1) * qh, qw, qh};
    ms_desc d[VIEWS];
    memset(d, 0, sizeof d);
    btf_status rc = BTF_OK;
    for (int i = 0; i < VIEWS && rc == BTF_OK; i++)
        rc = ms_describe(&v[i], s, levels, &d[i], err);
    if (rc == BTF_OK) {
        double raw[3], self[3] = {0, 0, 0}, pair[3];
        distances(&d[VIEW_REF], &d[VIEW_IMG], raw, out->first_order_lab);
        for (int a = 0; a < 4; a++)
            for (int b = a + 1; b < 4; b++) {
                distances(&d[VIEW_Q0 + a], &d[VIEW_Q0 + b], pair, NULL);
                for (int k = 0; k < 3; k++)
                    self[k] += pair[k] / 6.0;
            }
        double c = sample_correction(ref, img);
        for (int k = 0; k < 3; k++)
            self[k] *= c;
        component(&out->spectrum, raw[0], self[0], FLOOR_SPECTRUM);
        component(&out->first_order, raw[1], self[1], FLOOR_FIRST_ORDER);
        component(&out->structure, raw[2], self[2], FLOOR_STRUCTURE);
        out->combined = (out->spectrum.normalised + out->first_order.normalised +
                         out->structure.normalised) / 3.0;
        out->spectrum_bins = s / 2;
        out->levels = levels;
    }
    for (int i = 0; i < VIEWS; i++)
        ms_desc_free(&d[i]);
    return rc;
}

btf_status btf_texture_distance(const btf_image *ref, const btf_image *img,
                                const btf_texture_distance_opts *opts,
                                btf_texture_distances *out, btf_error *err)
{
    btf_texture_distance_opts d = btf_texture_distance_defaults(), o;
    if (btf__opts_take(&o, sizeof o, opts, &d, "btf_texture_distance", err))
        return BTF_E_ARG;
    const char *rname = o.reference_name ? o.reference_name : "reference";
    const char *iname = o.image_name ? o.image_name : "image";
    if (!out)
        return btf__fail(err, BTF_E_ARG, "texture distance: no output");
    memset(out, 0, sizeof *out);
    btf_status rc = check_image(ref, rname, err);
    if (rc == BTF_OK)
        rc = check_image(img, iname, err);
    if (rc != BTF_OK)
        return rc;
    if (o.levels < 0 || o.levels > MS_MAX_LEVELS)
        return btf__fail(err, BTF_E_ARG, "texture distance: levels %d out of range 0..%d",
                         o.levels, MS_MAX_LEVELS);
    int s = ref->width / 2;
    if (ref->height / 2 < s)
        s = ref->height / 2;
    if (img->width < s)
        s = img->width;
    if (img->height < s)
        s = img->height;
    int levels = o.levels ? o.levels : auto_levels(s);
    double exposure = ms_exposure(ref);
    float *lab_ref = NULL, *lab_img = NULL;
    rc = ms_lab(ref, exposure, rname, &lab_ref, err);
    if (rc == BTF_OK)
        rc = ms_lab(img, exposure, iname, &lab_img, err);
    if (rc == BTF_OK)
        rc = measure(lab_ref, ref, lab_img, img, s, levels, out, err);
    free(lab_ref);
    free(lab_img);
    if (rc == BTF_OK && !all_finite(out))
        rc = btf__fail(err, BTF_E_NUMERIC, "%s vs %s: a distance is not finite", rname, iname);
    if (rc != BTF_OK) {
        memset(out, 0, sizeof *out);
        return rc;
    }
    out->exposure = exposure;
    return BTF_OK;
}
