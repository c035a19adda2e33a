// render.comp -- the second GPU pass (Haindl & Filip 2007, section III and
// Fig. 1; docs/render.md, "On the GPU"): per pixel of a G-buffer traced on
// the host, the local view and light directions, the triangle lookups and
// barycentric weights (src/render/btf__hemisphere_lookup.h), the index-table
// lookup, the parallax-shifted reads of the subspace images the first pass
// (synthesis) left in a device buffer, the relit result
// (src/render/btf_render_shared.h: the very text the CPU renderer runs).
// One invocation per pixel; the layout of the parameters is
// gpu/render_layout.h.
#version 450
#extension GL_GOOGLE_include_directive : require

#define BTF_GLSL 1
#include "render_layout.h"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer GBuf { float gb[]; };
layout(std430, set = 0, binding = 1) readonly buffer Tex { float tex[]; };
layout(std430, set = 0, binding = 2) readonly buffer Maps { float maps[]; };
layout(std430, set = 0, binding = 3) readonly buffer Ints { int pi[]; };
layout(std430, set = 0, binding = 4) readonly buffer Floats { float pf[]; };
layout(std430, set = 0, binding = 5) writeonly buffer Out { float rgb[]; };
layout(std430, set = 0, binding = 6) readonly buffer Hor { uint hz[]; };
// Nonzero when a pixel selected a subspace the first pass did not
// synthesise: beside the colours, which may take any value.
layout(std430, set = 0, binding = 7) buffer Missing { uint missing[]; };
// The subspace images are one array of floats over binding 1 and these
// (gpu/synth_gpu.h: as many buffers as the device's largest storage buffer
// needs; unused ones bind a small placeholder that is never read).
layout(std430, set = 0, binding = 8) readonly buffer Tex1 { float tex1[]; };
layout(std430, set = 0, binding = 9) readonly buffer Tex2 { float tex2[]; };
layout(std430, set = 0, binding = 10) readonly buffer Tex3 { float tex3[]; };
// The range and normal maps likewise over binding 2 and these.
layout(std430, set = 0, binding = 11) readonly buffer Maps1 { float maps1[]; };
layout(std430, set = 0, binding = 12) readonly buffer Maps2 { float maps2[]; };
layout(std430, set = 0, binding = 13) readonly buffer Maps3 { float maps3[]; };
// The subspace images' buffers 4-7 (gpu/synth_gpu.h, BTF_GPU_DEVICE_BUFFERS).
layout(std430, set = 0, binding = 14) readonly buffer Tex4 { float tex4[]; };
layout(std430, set = 0, binding = 15) readonly buffer Tex5 { float tex5[]; };
layout(std430, set = 0, binding = 16) readonly buffer Tex6 { float tex6[]; };
layout(std430, set = 0, binding = 17) readonly buffer Tex7 { float tex7[]; };
// The maps' buffers 4-7.
layout(std430, set = 0, binding = 18) readonly buffer Maps4 { float maps4[]; };
layout(std430, set = 0, binding = 19) readonly buffer Maps5 { float maps5[]; };
layout(std430, set = 0, binding = 20) readonly buffer Maps6 { float maps6[]; };
layout(std430, set = 0, binding = 21) readonly buffer Maps7 { float maps7[]; };

float btf_map_read(int f)
{
    int cap = pi[BTF_RP_TEXCAP];
    int b = f / cap;
    int i = f - b * cap;
    if (b < 4)
        return b == 0 ? maps[i] : b == 1 ? maps1[i] : b == 2 ? maps2[i] : maps3[i];
    return b == 4 ? maps4[i] : b == 5 ? maps5[i] : b == 6 ? maps6[i] : maps7[i];
}

float btf_tex_read(int f)
{
    int cap = pi[BTF_RP_TEXCAP];
    int b = f / cap;
    int i = f - b * cap;
    if (b < 4)
        return b == 0 ? tex[i] : b == 1 ? tex1[i] : b == 2 ? tex2[i] : tex3[i];
    return b == 4 ? tex4[i] : b == 5 ? tex5[i] : b == 6 ? tex6[i] : tex7[i];
}

#define BTF_TAB_I(tab, f) pi[BTF_RP_TAB + (tab) * BTF_RP_TAB_STRIDE + (f)]
#define BTF_HEMI_TABLE int
#define BTF_HEMI_POINT(tab, i, k) pf[BTF_TAB_I(tab, BTF_RP_T_PTS) + 2 * (i) + (k)]
#define BTF_HEMI_TRIANGLE(tab, t, k) pi[BTF_TAB_I(tab, BTF_RP_T_TRI) + 3 * (t) + (k)]
#define BTF_HEMI_GRID(tab) BTF_TAB_I(tab, BTF_RP_T_GRID)
#define BTF_HEMI_CELL_START(tab, c) pi[BTF_TAB_I(tab, BTF_RP_T_CS) + (c)]
#define BTF_HEMI_CELL_TRI(tab, j) pi[BTF_TAB_I(tab, BTF_RP_T_CT) + (j)]
#define BTF_HEMI_N_HULL(tab) BTF_TAB_I(tab, BTF_RP_T_NHULL)
#define BTF_HEMI_HULL(tab, i) pi[BTF_TAB_I(tab, BTF_RP_T_HULL) + (i)]
#define BTF_HEMI_HULL_APEX(tab, i) pi[BTF_TAB_I(tab, BTF_RP_T_APEX) + (i)]

#define BTF_SHADE_CTX int
#define BTF_SHADE_VIEWS(ctx) 0
#define BTF_SHADE_LIGHTS(ctx) 1
#define BTF_SHADE_SIZE(ctx) pi[BTF_RP_SIZE]
#define BTF_SHADE_N_LIGHTS_SET(ctx) pi[BTF_RP_NSET]
#define BTF_SHADE_INDEX(ctx, i) pi[pi[BTF_RP_INDEX] + (i)]
#define BTF_SHADE_HAVE(ctx, k) pi[pi[BTF_RP_HAVE] + (k)]
#define BTF_SHADE_TEX(ctx, k, i) btf_tex_read(pi[pi[BTF_RP_TEXOFF] + (k)] + (i))
#define BTF_SHADE_HEIGHT(ctx, i) btf_map_read(i)
#define BTF_SHADE_NORMAL(ctx, i) btf_map_read(pi[BTF_RP_NORMAL] + (i))
#define BTF_SHADE_LIGHT_OUTER_Z(ctx) pf[BTF_RP_OUTER]
#define BTF_SHADE_AMBIENT(ctx) pf[BTF_RP_AMBIENT]
#define BTF_SHADE_GAIN(ctx, i, c) pf[pi[BTF_RP_GAIN] + 3 * (i) + (c)]
#define BTF_SHADE_HAS_HORIZON(ctx) pi[BTF_RP_HORIZON]
#define BTF_SHADE_HORIZON(ctx, i) hz[i]
#define BTF_SHADE_HMIN(ctx) pf[BTF_RP_HMIN]
#define BTF_SHADE_HMAX(ctx) pf[BTF_RP_HMAX]
#define BTF_SHADE_N_LIGHTS(ctx) pi[BTF_RP_NLIGHTS]
#define BTF_SHADE_LIGHT_KIND(ctx, j) pi[BTF_RP_KIND + (j)]
#define BTF_SHADE_LIGHT_VEC(ctx, j, k) pf[BTF_RP_VEC + 3 * (j) + (k)]
#define BTF_SHADE_LIGHT_RGB(ctx, j, k) pf[BTF_RP_RGB + 3 * (j) + (k)]

#include "btf_render_shared.h"

void main()
{
    uint p = gl_GlobalInvocationID.y * uint(pi[BTF_RP_ROW_PIX]) + gl_GlobalInvocationID.x;
    if (p >= uint(pi[BTF_RP_NPIX]))
        return;
    uint g = p * uint(BTF_RP_GB);
    if (gb[g] < 0.0) {
        rgb[3u * p] = pf[BTF_RP_BG];
        rgb[3u * p + 1u] = pf[BTF_RP_BG + 1];
        rgb[3u * p + 2u] = pf[BTF_RP_BG + 2];
        return;
    }
    btf_pixel c = btf_shade_pixel(0, gb[g + 3u], gb[g + 4u], gb[g + 5u], gb[g + 6u], gb[g + 7u],
                                  gb[g + 8u], gb[g + 9u], gb[g + 10u], gb[g + 11u],
                                  gb[g + 12u], gb[g + 13u], gb[g + 14u], gb[g + 15u],
                                  gb[g + 16u], gb[g + 17u], gb[g + 1u], gb[g + 2u],
                                  pf[BTF_RP_RELIEF]);
    // A pixel that selects a subspace the first pass did not synthesise
    // tells the host through the flag (it never lets that happen: the
    // needed set is the shading's own rule).
    if (c.missing != 0)
        atomicOr(missing[0], 1u);
    rgb[3u * p] = c.r;
    rgb[3u * p + 1u] = c.g;
    rgb[3u * p + 2u] = c.b;
}
