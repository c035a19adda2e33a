/*
 * rf_render.h — the reflectance-field family's sniff, four-view weights,
 * evaluation and CPU renders (Meseth, Müller & Klein 2003, section 5.4;
 * docs/rf.md). Users reach them through the material interface
 * (btfcar/material.h); the library and its tests call them here. Apart from
 * rf.h so that the report, whose pair type shares a name with rf.h's, can
 * include it alone.
 */
#ifndef BTF_RF_RENDER_H
#define BTF_RF_RENDER_H

#include "btfcar.h"

/* 1 when the bytes start like a reflectance-field file (the signature's
 * first 7 bytes), else 0. */
int btf__rf_sniff(const unsigned char *data, size_t size);

/* ------------------------------------------- reflectance-field renders */

/* The four closest measured views of a direction (paper section 5.4): the
 * two measured theta rings around theta (one at the pole or beyond the
 * last ring), on each the two measured azimuths around phi, bilinear weights
 * in theta and phi that sum to 1 (computed in float, as the renderers
 * blend: to 1e-6). idx[i] and w[i], i < 4 (an index may repeat, e.g. at
 * the pole; unused weights are 0). */
void btf__rf_view_weights(const btf_dirset *views, btf_dir view, int idx[4], double w[4]);

/* Linear RGB of texel (x, y) (wrapped into the surface, btf_rf_surface_size;
 * a sampled model's through its coordinate map) seen from `view` and lit
 * from `light`: the four closest views' fields weighted
 * (btf__rf_view_weights); lafortune evaluates its one field at the view. */
void btf__rf_eval(const btf_rf_model *m, btf_dir view, btf_dir light, int x, int y,
                  float rgb[3]);
/* The flat (view, light) render of docs/render.md with an RF model: pixel
 * (x, y) is surface texel (x mod width, y mod height) (btf_rf_surface_size;
 * a sampled model's through its map), lit by one unit light. width/height
 * 0: the surface's. threads 0: all CPUs. */
btf_status btf__rf_render_flat(const btf_rf_model *m, btf_dir view, btf_dir light, int width,
                               int height, int threads, btf_image *out, btf_error *err);

/* A scene (btf_scene_load, docs/scene.md) rendered with an RF model on the
 * CPU: traced into the CAR renderer's G-buffer; per pixel the local view
 * and light directions in the tangent frame (as the CAR renderer shades
 * them: a light below the surface's horizon gives nothing, a point light
 * falls off as 1/d^2), the texel floor(uv) wrapped into the model's
 * surface (through a sampled model's map), the four closest views' fields
 * at the exact light blended (the flat render's arithmetic), times each
 * light's intensity; background pixels the scene's background. No parallax
 * or bump mapping (the fields hold the relief). width/height 0: 512;
 * threads 0: all CPUs. info (NULL: not wanted): trace_s and shade_s, the
 * rest 0. */
btf_status btf__rf_render_scene(const btf_rf_model *m, const btf_scene *s, int width,
                                int height, int threads, btf_image *out, btf_render_info *info,
                                btf_error *err);

/* The file's reader (rf_file.c); users read a model of either family with
 * btf_material_read (btfcar/material.h). */
btf_status btf__rf_read(const char *path, btf_rf_model *out, btf_error *err);

#endif
