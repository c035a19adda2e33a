/*
 * mesh_frame.c — the surface at a mesh hit (docs/scene.md, "Meshes"): uv
 * interpolated from the vertices (texture_scale and rotation applied), the
 * shading normal interpolated from vertex normals (the face normal when the
 * mesh has none), and the tangent from the triangle's uv derivatives
 * (dP/du of the per-triangle linear map, as in Lengyel 2001's tangent
 * space), Gram-Schmidt against the normal in scene_finish_frame.
 */
#include "scene/scene.h"

void scene_mesh_surface(const btf_object *ob, int tri, double b1, double b2,
                        const double view[3], scene_hit *h)
{
    const btf_mesh *m = &ob->mesh;
    const uint32_t *ix = m->indices + 3 * (size_t)tri;
    double w[3] = {1.0 - b1 - b2, b1, b2};
    double p[3][3], uv[3][2];
    for (int k = 0; k < 3; k++) {
        const float *q = m->positions + 3 * (size_t)ix[k];
        const float *t = m->uvs + 2 * (size_t)ix[k];
        for (int i = 0; i < 3; i++)
            p[k][i] = q[i];
        /* The file's uv (v down) in texels, then the material rotation:
         * s = u, t = -v are the surface coordinates scene_rotate_uv turns. */
        scene_rotate_uv(ob->rotation_deg, ob->texture_scale * t[0], -ob->texture_scale * t[1],
                        &uv[k][0], &uv[k][1]);
    }
    h->uv[0] = w[0] * uv[0][0] + w[1] * uv[1][0] + w[2] * uv[2][0];
    h->uv[1] = w[0] * uv[0][1] + w[1] * uv[1][1] + w[2] * uv[2][1];

    double e1[3], e2[3], ng[3];
    v3_sub(p[1], p[0], e1);
    v3_sub(p[2], p[0], e2);
    v3_cross(e1, e2, ng);
    if (!v3_normalize(ng))
        ng[0] = 0.0, ng[1] = 0.0, ng[2] = 1.0; /* a zero-area triangle is never hit */

    double n[3] = {ng[0], ng[1], ng[2]};
    if (m->normals) {
        double s[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                s[i] += w[k] * m->normals[3 * (size_t)ix[k] + i];
        if (v3_normalize(s))
            for (int i = 0; i < 3; i++)
                n[i] = s[i];
    }
    /* The outward side is the side of the vertex normals (the winding when
     * there are none); the triangle's own plane decides which side the eye
     * is on, so that an interpolated normal turned away from the eye near a
     * silhouette does not flip the frame. That normal is bent to face the
     * eye's side by a hair (N . V = +-1e-3), so N faces the eye. */
    double side = v3_dot(ng, n) < 0.0 ? -1.0 : 1.0; /* ng towards the outward side */
    double ngo[3] = {side * ng[0], side * ng[1], side * ng[2]};
    double eye = v3_dot(ngo, view) >= 0.0 ? 1.0 : -1.0;
    double nv = v3_dot(n, view);
    if (nv * eye < 1e-3) {
        double k = nv - eye * 1e-3;
        for (int i = 0; i < 3; i++)
            n[i] -= k * view[i];
        if (!v3_normalize(n))
            for (int i = 0; i < 3; i++)
                n[i] = ngo[i];
    }

    /* dP/du of the triangle's linear uv map; its layout is mirrored
     * against the outward side when dP/du x (-dP/dv) opposes it, which
     * with v down is det > 0 for a counter-clockwise winding about ng. */
    double du1 = uv[1][0] - uv[0][0], dv1 = uv[1][1] - uv[0][1];
    double du2 = uv[2][0] - uv[0][0], dv2 = uv[2][1] - uv[0][1];
    double det = du1 * dv2 - du2 * dv1;
    double tdir[3] = {0.0, 0.0, 0.0};
    int mirrored = 0;
    double scale = fabs(du1) + fabs(dv1) + fabs(du2) + fabs(dv2);
    if (isfinite(det) && fabs(det) > 1e-12 * scale * scale) {
        for (int i = 0; i < 3; i++)
            tdir[i] = (e1[i] * dv2 - e2[i] * dv1) / det;
        mirrored = det * side > 0.0;
    } /* else degenerate uvs: scene_finish_frame picks a frame around N */
    scene_finish_frame(n, tdir, view, mirrored, h);
}
