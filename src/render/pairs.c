/*
 * pairs.c — the nine (view, light) pairs of a pixel (Haindl & Filip 2007,
 * section III: the 3 nearest measured views x the 3 nearest lights, with
 * barycentric weights) reduced to the distinct subspace images they select
 * through the index table, each with its summed weight: equal subspaces
 * are sampled once. Weights below BTF_RENDER_MIN_WEIGHT are dropped and the
 * rest renormalised (a discontinuity of at most ~2e-5 in the blend). Shared by the needed-subspace walk and the shading.
 */
#include "render/shade.h"

/* Weights below this are rounding (a measured direction's own weight is 1
 * only to ~1e-6): they are dropped and the rest renormalised, so that a
 * pixel at a measured pair selects that pair's subspace alone. */
#define BTF_RENDER_MIN_WEIGHT 1e-5f

/* The weights kept and their sum. */
static float kept_sum(const float w[3])
{
    float s = 0.0f;
    for (int i = 0; i < 3; i++)
        if (w[i] >= BTF_RENDER_MIN_WEIGHT)
            s += w[i];
    return s;
}

void btf_render_pairs_of(const uint8_t *index, int n_lights, const int iv[3],
                         const float wv[3], const int il[3], const float wl[3],
                         btf_render_pairs *out)
{
    out->n = 0;
    float sv = kept_sum(wv), sl = kept_sum(wl);
    if (!(sv > 0.0f) || !(sl > 0.0f))
        return;
    for (int i = 0; i < 3; i++) {
        if (!(wv[i] >= BTF_RENDER_MIN_WEIGHT))
            continue;
        for (int j = 0; j < 3; j++) {
            if (!(wl[j] >= BTF_RENDER_MIN_WEIGHT))
                continue;
            int k = index[(size_t)iv[i] * (size_t)n_lights + (size_t)il[j]];
            float w = (wv[i] / sv) * (wl[j] / sl);
            int d = 0;
            while (d < out->n && out->sub[d] != k)
                d++;
            if (d == out->n) {
                out->sub[d] = k;
                out->w[d] = 0.0f;
                out->n++;
            }
            out->w[d] += w;
        }
    }
}

void btf_render_local_view(const float *frame, const float view[3], float out[3])
{
    btf_render_to_local(frame, view, out);
    if (!(out[2] > BTF_RENDER_MIN_Z))
        out[2] = BTF_RENDER_MIN_Z;
}

int btf_render_light_at(const btf_light *l, const float p[3], float dir[3], float rgb[3])
{
    float scale = 1.0f;
    if (l->kind == BTF_LIGHT_POINT) {
        double d[3], n2 = 0.0;
        for (int i = 0; i < 3; i++) {
            d[i] = l->position[i] - (double)p[i];
            n2 += d[i] * d[i];
        }
        if (!(n2 > 1e-24) || !isfinite(n2))
            return 0;
        double inv = 1.0 / sqrt(n2);
        for (int i = 0; i < 3; i++)
            dir[i] = (float)(d[i] * inv);
        scale = (float)(1.0 / n2);
    } else {
        double n2 = 0.0;
        for (int i = 0; i < 3; i++)
            n2 += l->direction[i] * l->direction[i];
        if (!(n2 > 0.0) || !isfinite(n2))
            return 0;
        double inv = 1.0 / sqrt(n2);
        for (int i = 0; i < 3; i++)
            dir[i] = (float)(l->direction[i] * inv);
    }
    for (int i = 0; i < 3; i++)
        rgb[i] = l->rgb[i] * scale;
    return 1;
}
