/*
 * directions.c — the direction sets BTF measurements are sampled on, and the
 * (theta, phi) <-> unit vector conversions. z is the surface normal, theta is
 * the angle from it, phi the azimuth from +x towards +y, both in degrees.
 */
#include <stdio.h>
#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BTF_PI 3.14159265358979323846

void btf_dir_to_vec(btf_dir d, double v[3])
{
    double t = d.theta * (BTF_PI / 180.0), p = d.phi * (BTF_PI / 180.0);
    double s = sin(t);
    v[0] = s * cos(p);
    v[1] = s * sin(p);
    v[2] = cos(t);
}

btf_dir btf_vec_to_dir(const double v[3])
{
    btf_dir d = {0.0, 0.0};
    /* hypot, not sqrt of squares: vectors near the float limits must not
     * overflow to Inf (or underflow to 0) on the way. */
    double rho = hypot(v[0], v[1]);
    double r = hypot(rho, v[2]);
    if (!(r > 0.0) || !isfinite(r))
        return d; /* a zero or non-finite vector: the pole, by convention */
    d.theta = atan2(rho, v[2]) * (180.0 / BTF_PI);
    /* On the pole the azimuth is undefined; report 0 so that sets compare. */
    if (rho > 1e-12 * r) {
        double p = atan2(v[1], v[0]) * (180.0 / BTF_PI);
        if (p < 0.0)
            p += 360.0;
        if (p >= 360.0)
            p -= 360.0;
        d.phi = p;
    }
    return d;
}

double btf_dir_angle(btf_dir a, btf_dir b)
{
    double u[3], v[3];
    btf_dir_to_vec(a, u);
    btf_dir_to_vec(b, v);
    /* atan2 of |u x v| and u.v stays accurate for tiny and near-180 angles,
     * where acos of the dot product loses all digits. */
    double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double s = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    return atan2(s, u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) * (180.0 / BTF_PI);
}

static int make_rings(btf_dirset *set, const char *name, const double *theta, const int *count,
                      const double *offset, int rings, btf_error *err)
{
    int total = 0;
    for (int r = 0; r < rings; r++)
        total += count[r];
    set->dirs = btf__alloc((size_t)total, sizeof(btf_dir), err);
    if (!set->dirs)
        return BTF_E_NOMEM;
    int k = 0;
    for (int r = 0; r < rings; r++)
        for (int i = 0; i < count[r]; i++) {
            set->dirs[k].theta = theta[r];
            set->dirs[k].phi = theta[r] == 0.0 ? 0.0 : offset[r] + 360.0 * i / count[r];
            k++;
        }
    set->count = total;
    snprintf(set->name, sizeof set->name, "%s", name);
    return BTF_OK;
}

btf_status btf_dirset_ubo81(btf_dirset *set, btf_error *err)
{
    static const double theta[] = {0, 15, 30, 45, 60, 75};
    static const int count[] = {1, 6, 12, 18, 20, 24};
    static const double offset[] = {0, 0, 0, 0, 0, 0};
    return make_rings(set, "ubo81", theta, count, offset, 6, err);
}

btf_status btf__dirset_ubo151(btf_dirset *set, btf_error *err)
{
    static const double theta[] = {0, 11, 23.5, 30, 37.5, 45, 52.5, 60, 67.5, 75};
    static const int count[] = {1, 6, 12, 12, 12, 18, 18, 24, 24, 24};
    static const double offset[] = {0, 15, 0, 15, 0, 0, 7.5, 0, 7.5, 0};
    return make_rings(set, "ubo151", theta, count, offset, 10, err);
}

void btf_dirset_free(btf_dirset *set)
{
    if (!set)
        return;
    free(set->dirs);
    set->dirs = NULL;
    set->count = 0;
}

btf_status btf__dirset_copy(btf_dirset *dst, const btf_dirset *src, btf_error *err)
{
    dst->dirs = btf__alloc((size_t)(src->count ? src->count : 1), sizeof(btf_dir), err);
    if (!dst->dirs)
        return BTF_E_NOMEM;
    memcpy(dst->dirs, src->dirs, (size_t)src->count * sizeof(btf_dir));
    dst->count = src->count;
    memcpy(dst->name, src->name, sizeof dst->name);
    return BTF_OK;
}

int btf_dirset_find(const btf_dirset *set, btf_dir d, double tol_deg)
{
    int best = -1;
    double best_a = tol_deg;
    for (int i = 0; i < set->count; i++) {
        double a = btf_dir_angle(set->dirs[i], d);
        if (a <= best_a) {
            best_a = a;
            best = i;
        }
    }
    return best;
}

/* Ring order: theta ascending, then phi ascending; directions within 1e-6
 * degree of each other count as one. */
static int cmp_dir(const void *a, const void *b)
{
    const btf_dir *x = a, *y = b;
    if (fabs(x->theta - y->theta) > 1e-6)
        return x->theta < y->theta ? -1 : 1;
    if (fabs(x->phi - y->phi) > 1e-6)
        return x->phi < y->phi ? -1 : 1;
    return 0;
}

/* If the list is a known sampling (with names rounded to whole degrees, as
 * UBO2003 file names are), adopt that set's name and exact values. Rounding
 * theta and phi by half a degree each moves a direction by up to about
 * 0.69 degree (ubo151's 23.5 and 7.5 offsets), hence the 0.75 tolerance. */
static int adopt_known(btf_dirset *set, int (*make)(btf_dirset *, btf_error *), btf_error *err)
{
    btf_dirset known;
    if (make(&known, err) != 0)
        return -1;
    int match = known.count == set->count;
    for (int i = 0; match && i < set->count; i++)
        match = btf_dir_angle(set->dirs[i], known.dirs[i]) <= BTF_DIR_NAME_TOLERANCE;
    if (match) {
        free(set->dirs);
        *set = known;
        return 1;
    }
    btf_dirset_free(&known);
    return 0;
}

btf_status btf_dirset_from_list(btf_dirset *set, const btf_dir *dirs, int count, btf_error *err)
{
    memset(set, 0, sizeof *set);
    if (count < 1)
        return btf__fail(err, BTF_E_ARG, "empty direction list");
    set->dirs = btf__alloc((size_t)count, sizeof(btf_dir), err);
    if (!set->dirs)
        return BTF_E_NOMEM;
    for (int i = 0; i < count; i++) {
        btf_dir d = dirs[i];
        if (!isfinite(d.theta) || !isfinite(d.phi) || d.theta < 0.0 || d.theta > 90.0) {
            btf_dirset_free(set);
            return btf__fail(err, BTF_E_ARG, "direction (theta %g, phi %g): theta must be in [0, 90]",
                             d.theta, d.phi);
        }
        d.phi = fmod(d.phi, 360.0);
        if (d.phi < 0.0)
            d.phi += 360.0;
        if (d.theta == 0.0)
            d.phi = 0.0;
        set->dirs[i] = d;
    }
    qsort(set->dirs, (size_t)count, sizeof(btf_dir), cmp_dir);
    int k = 0;
    for (int i = 0; i < count; i++)
        if (k == 0 || cmp_dir(&set->dirs[k - 1], &set->dirs[i]) != 0)
            set->dirs[k++] = set->dirs[i];
    set->count = k;
    snprintf(set->name, sizeof set->name, "custom");
    int r = adopt_known(set, btf_dirset_ubo81, err);
    if (r == 0)
        r = adopt_known(set, btf__dirset_ubo151, err);
    if (r < 0) {
        btf_dirset_free(set);
        return BTF_E_NOMEM;
    }
    return BTF_OK;
}
