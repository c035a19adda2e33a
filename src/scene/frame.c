/*
 * frame.c — the material's orientation on a surface and the tangent frame
 * of a hit (docs/scene.md, "Material orientation", "Back faces"): shared by
 * the analytic shapes and the meshes, so that every object follows one
 * convention: T along increasing u, B along decreasing v (up the texture
 * image), N = T x B towards the eye, like the project's normal maps.
 */
#include "scene/scene.h"

void scene_basis(const double a[3], double right[3], double up[3])
{
    /* World +y is "up" on walls; on floors and ceilings (+-y normals) the
     * far side, world -z, is. 0.9 = cos 25.8 deg keeps the projection long. */
    double ref[3] = {0.0, 1.0, 0.0};
    if (fabs(a[1]) > 0.9)
        ref[1] = 0.0, ref[2] = -1.0;
    double k = v3_dot(ref, a);
    for (int i = 0; i < 3; i++)
        up[i] = ref[i] - k * a[i];
    v3_normalize(up); /* |up| >= sin 25.8 deg: never degenerate */
    v3_cross(up, a, right);
    v3_normalize(right);
}

void scene_rotate_uv(double rotation_deg, double s, double t, double *u, double *v)
{
    /* The material turned counter-clockwise (seen from outside) by the
     * angle: a surface point's material coordinates turn the other way. */
    double r = fmod(rotation_deg, 360.0) * (M_PI / 180.0);
    double c = cos(r), sn = sin(r);
    *u = c * s + sn * t;
    *v = -(-sn * s + c * t);
}

/* Any unit vector perpendicular to unit n (Frisvad-style branch on z). */
static void any_perpendicular(const double n[3], double t[3])
{
    double ref[3] = {1.0, 0.0, 0.0};
    if (fabs(n[0]) > 0.6)
        ref[0] = 0.0, ref[1] = 1.0;
    double k = v3_dot(ref, n);
    for (int i = 0; i < 3; i++)
        t[i] = ref[i] - k * n[i];
    v3_normalize(t);
}

void scene_finish_frame(const double n_out[3], const double tdir[3], const double view[3],
                        int mirrored, scene_hit *h)
{
    double n[3] = {n_out[0], n_out[1], n_out[2]};
    double t[3] = {tdir[0], tdir[1], tdir[2]};
    int back = v3_dot(n, view) < 0.0;
    if (back)
        v3_scale(n, -1.0);
    if (back != mirrored) {
        /* Seen from behind (or a mirrored layout): u runs the other way so
         * that the material reads unmirrored in a right-handed frame. */
        h->uv[0] = -h->uv[0];
        v3_scale(t, -1.0);
    }
    /* Gram-Schmidt of T against N. */
    double k = v3_dot(t, n);
    for (int i = 0; i < 3; i++)
        t[i] -= k * n[i];
    double tl = v3_len(t);
    if (!(tl > 1e-12 * (1.0 + v3_len(tdir))) || !isfinite(tl))
        any_perpendicular(n, t);
    else
        v3_scale(t, 1.0 / tl);
    double b[3];
    v3_cross(n, t, b);
    v3_normalize(b);
    for (int i = 0; i < 3; i++) {
        h->frame[i] = t[i];
        h->frame[3 + i] = b[i];
        h->frame[6 + i] = n[i];
    }
}
