/*
 * shapes.c — ray intersections with the analytic objects (docs/scene.md,
 * "Objects"): a square plane, a sphere, an open finite cylinder; each hit
 * with its material uv in texels (texture_scale, rotation) and tangent
 * frame (scene_finish_frame). Double precision throughout; coordinates
 * are bounded by SCENE_MAX_COORD (scene_check.c) so nothing overflows.
 */
#include "scene/scene.h"

/* The rotated right: the direction of increasing u for an isotropic
 * (s, t) parameterisation turned by rotation_deg (scene_rotate_uv). */
static void rotated_tangent(double rotation_deg, const double right[3], const double up[3],
                            double out[3])
{
    double r = fmod(rotation_deg, 360.0) * (M_PI / 180.0);
    double c = cos(r), sn = sin(r);
    for (int i = 0; i < 3; i++)
        out[i] = c * right[i] + sn * up[i];
}

static void point_on_ray(const double o[3], const double d[3], double t, double p[3])
{
    for (int i = 0; i < 3; i++)
        p[i] = o[i] + t * d[i];
}

static void view_of(const double d[3], double view[3])
{
    view[0] = -d[0], view[1] = -d[1], view[2] = -d[2];
}

int scene_hit_plane(const btf_object *ob, const double o[3], const double d[3], double t_max,
                    scene_hit *h)
{
    double a[3] = {ob->axis[0], ob->axis[1], ob->axis[2]};
    double denom = v3_dot(d, a);
    if (fabs(denom) < 1e-15)
        return 0; /* parallel: a ray in the plane sees its zero-area edge */
    double oc[3];
    v3_sub(ob->center, o, oc);
    double t = v3_dot(oc, a) / denom;
    if (!(t > 0.0 && t < t_max))
        return 0;
    double p[3], rel[3], right[3], up[3];
    point_on_ray(o, d, t, p);
    v3_sub(p, ob->center, rel);
    scene_basis(a, right, up);
    double s = v3_dot(rel, right), tt = v3_dot(rel, up), half = 0.5 * ob->size;
    if (fabs(s) > half || fabs(tt) > half)
        return 0;
    h->t = t;
    for (int i = 0; i < 3; i++)
        h->position[i] = p[i];
    /* u from the square's left edge, v from its top edge (before rotation). */
    double u, v;
    scene_rotate_uv(ob->rotation_deg, s, tt, &u, &v);
    h->uv[0] = (u + half) * ob->texture_scale;
    h->uv[1] = (v + half) * ob->texture_scale;
    double tdir[3], view[3];
    rotated_tangent(ob->rotation_deg, right, up, tdir);
    view_of(d, view);
    scene_finish_frame(a, tdir, view, 0, h);
    return 1;
}

/* Roots of t^2 |dd|^2 + 2 t b + c = 0 in ascending order (a stable
 * form: no cancellation between b and the root); 0 when none is real. */
static int quadratic(double qa, double qb, double qc, double *t0, double *t1)
{
    double disc = qb * qb - qa * qc;
    if (!(disc >= 0.0) || !(qa > 0.0))
        return 0;
    double sq = sqrt(disc);
    double q = qb >= 0.0 ? -(qb + sq) : -(qb - sq);
    double r0 = q / qa, r1 = q != 0.0 ? qc / q : r0;
    *t0 = r0 < r1 ? r0 : r1;
    *t1 = r0 < r1 ? r1 : r0;
    return 1;
}

/* The longitude of unit n around axis a, in [0, 2 pi), from the axis
 * basis (e1 = scene_basis's right, e2 = a x e1); the direction of
 * increasing longitude is -sin(phi) e1 + cos(phi) e2 (unit, never zero). */
static double longitude(const double a[3], const double n[3], double tangent[3])
{
    double e1[3], up[3], e2[3];
    scene_basis(a, e1, up);
    v3_cross(a, e1, e2);
    double phi = atan2(v3_dot(n, e2), v3_dot(n, e1));
    if (phi < 0.0)
        phi += 2.0 * M_PI;
    if (!(phi < 2.0 * M_PI))
        phi = 0.0; /* atan2 of -0 rounds up to 2 pi after the shift */
    double c = cos(phi), s = sin(phi);
    for (int i = 0; i < 3; i++)
        tangent[i] = -s * e1[i] + c * e2[i];
    return phi;
}

int scene_hit_sphere(const btf_object *ob, const double o[3], const double d[3], double t_max,
                     scene_hit *h)
{
    double oc[3];
    v3_sub(o, ob->center, oc);
    double r = ob->radius, t0, t1;
    if (!quadratic(v3_dot(d, d), v3_dot(oc, d), v3_dot(oc, oc) - r * r, &t0, &t1))
        return 0;
    double t = t0 > 0.0 ? t0 : t1; /* the far root: the eye inside */
    if (!(t > 0.0 && t < t_max))
        return 0;
    double p[3], n[3];
    point_on_ray(o, d, t, p);
    v3_sub(p, ob->center, n);
    if (!v3_normalize(n))
        return 0;
    /* Longitude/latitude (docs/scene.md, "Sphere"): u = R phi, v = R theta
     * (theta the polar angle from the axis), so that texels have their
     * true size along the meridians and the equator. */
    double tan0[3], up0[3];
    double phi = longitude(ob->axis, n, tan0);
    double ca = v3_dot(n, ob->axis);
    double theta = acos(ca > 1.0 ? 1.0 : ca < -1.0 ? -1.0 : ca);
    v3_cross(n, tan0, up0); /* towards the pole: decreasing v */
    double u, v;
    scene_rotate_uv(ob->rotation_deg, r * phi, -r * theta, &u, &v);
    h->t = t;
    for (int i = 0; i < 3; i++)
        h->position[i] = p[i];
    h->uv[0] = u * ob->texture_scale;
    h->uv[1] = v * ob->texture_scale;
    double tdir[3], view[3];
    rotated_tangent(ob->rotation_deg, tan0, up0, tdir);
    view_of(d, view);
    scene_finish_frame(n, tdir, view, 0, h);
    return 1;
}

int scene_hit_cylinder(const btf_object *ob, const double o[3], const double d[3],
                       double t_max, scene_hit *h)
{
    const double *a = ob->axis;
    double oc[3], op[3], dp[3];
    v3_sub(o, ob->center, oc);
    double oa = v3_dot(oc, a), da = v3_dot(d, a);
    for (int i = 0; i < 3; i++) {
        op[i] = oc[i] - oa * a[i];
        dp[i] = d[i] - da * a[i];
    }
    double r = ob->radius, half = 0.5 * ob->height, t0, t1;
    /* A ray along the axis (|dp| ~ 0) meets the open tube nowhere but
     * grazing its wall: no hit. */
    if (!quadratic(v3_dot(dp, dp), v3_dot(op, dp), v3_dot(op, op) - r * r, &t0, &t1))
        return 0;
    double roots[2] = {t0, t1};
    for (int k = 0; k < 2; k++) {
        double t = roots[k];
        if (!(t > 0.0 && t < t_max))
            continue;
        double ha = oa + t * da; /* height along the axis from the centre */
        if (fabs(ha) > half)
            continue; /* beyond an open end: the far wall may still be hit */
        double p[3], n[3];
        point_on_ray(o, d, t, p);
        for (int i = 0; i < 3; i++)
            n[i] = op[i] + t * dp[i];
        if (!v3_normalize(n))
            continue;
        double tan0[3];
        double phi = longitude(a, n, tan0);
        double u, v;
        /* u = R phi around, v from the top rim down the axis. */
        scene_rotate_uv(ob->rotation_deg, r * phi, ha, &u, &v);
        h->t = t;
        for (int i = 0; i < 3; i++)
            h->position[i] = p[i];
        h->uv[0] = u * ob->texture_scale;
        h->uv[1] = (v + half) * ob->texture_scale;
        double tdir[3], view[3];
        rotated_tangent(ob->rotation_deg, tan0, a, tdir);
        view_of(d, view);
        scene_finish_frame(n, tdir, view, 0, h);
        return 1;
    }
    return 0;
}
