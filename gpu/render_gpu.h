/*
 * render_gpu.h — what the CAR model's GPU render pass (gpu/render_gpu.c)
 * lends the other GPU render passes of the library (the reflectance-field
 * pass, gpu/rf_render_gpu.c): the packed G-buffer layout of
 * gpu/render_layout.h. Private; not installed.
 */
#ifndef BTF_RENDER_GPU_H
#define BTF_RENDER_GPU_H

#include "btfcar.h"
#include "scene/gbuffer.h"

/* Rows [y0, y1) of the G-buffer into out, BTF_RP_GB floats per pixel:
 * hit flag (1, or -1 for the background), u, v, frame[9], position[3],
 * view[3]. */
void btf__render_pack_gbuffer(const btf_gbuffer *g, int y0, int y1, float *out);

#endif
