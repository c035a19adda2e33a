// rf_render.comp -- the GPU render pass of reflectance-field models (Meseth,
// Mueller & Klein 2003, section 5: per pixel the four closest measured
// views' fields evaluated at the exact light direction and blended;
// docs/rf.md, "Rendering on the GPU"). Two modes, chosen by the header
// (gpu/rf_layout.h):
//  - tile: the flat (view, light) render; one invocation per distinct texel
//    of the frame (the host expands the tile, src/rf/rf_render.c), the four
//    fields and weights computed on the host by the same text;
//  - scene: one invocation per pixel of a G-buffer traced on the host (the
//    layout of the CAR render pass, gpu/render_layout.h), shaded by
//    btf_rf_shade_pixel.
// Every formula is src/rf/btf_rf_shared.h, the very text the CPU renderer
// runs. The model's 16-bit codes come two to a word, field by field, in up
// to RFP_CODE_BUFS buffers; a sampled model's (paper section 6) surface
// texels are looked up through its coordinate map, which comes in the int
// buffer (rf_surface_texel below, src/rf/rf_map.h's own lookup).
#version 450
#extension GL_GOOGLE_include_directive : require

#define BTF_GLSL 1
#include "rf_layout.h"
#include "render_layout.h"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer GBuf { float gb[]; };
layout(std430, set = 0, binding = 1) readonly buffer Ints { int pi[]; };
layout(std430, set = 0, binding = 2) readonly buffer Floats { float pf[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Out { float rgb[]; };
layout(std430, set = 0, binding = 4) readonly buffer Codes0 { uint c0[]; };
layout(std430, set = 0, binding = 5) readonly buffer Codes1 { uint c1[]; };
layout(std430, set = 0, binding = 6) readonly buffer Codes2 { uint c2[]; };
layout(std430, set = 0, binding = 7) readonly buffer Codes3 { uint c3[]; };
layout(std430, set = 0, binding = 8) readonly buffer Codes4 { uint c4[]; };
layout(std430, set = 0, binding = 9) readonly buffer Codes5 { uint c5[]; };
layout(std430, set = 0, binding = 10) readonly buffer Codes6 { uint c6[]; };
layout(std430, set = 0, binding = 11) readonly buffer Codes7 { uint c7[]; };

#define BTF_RF_CTX int
#define BTF_RF_FIT(c) pi[RFP_FIT]
#define BTF_RF_LOBES(c) pi[RFP_LOBES]
#define BTF_RF_NPARAMS(c) pi[RFP_NPARAMS]
#define BTF_RF_WIDTH(c) pi[RFP_WIDTH]
#define BTF_RF_HEIGHT(c) pi[RFP_HEIGHT]
#define BTF_RF_INV_WIDTH(c) pf[RFP_INV_W]
#define BTF_RF_INV_HEIGHT(c) pf[RFP_INV_H]
#define BTF_RF_TEXEL uint
#define BTF_RF_TEXEL_AT(c, x, y) rf_surface_texel(int(x), int(y))
#define BTF_RF_SRC uvec4
#define BTF_RF_P(src, s) btf_rf_param(src, s)
#define BTF_RF_SCRATCH(name) int name = 0
#define BTF_RF_OPEN(c, f, t, scratch) btf_rf_open(f, t)
#define BTF_RF_VIEWSET(c) 0
#define BTF_RF_N_LIGHTS(c) pi[RFP_NLIGHTS]
#define BTF_RF_LIGHT_KIND(c, j) pi[pi[RFP_LIGHT_KIND] + (j)]
#define BTF_RF_LIGHT_VEC(c, j, k) pf[pi[RFP_LIGHT_VEC] + 3 * (j) + (k)]
#define BTF_RF_LIGHT_RGB(c, j, k) pf[pi[RFP_LIGHT_RGB] + 3 * (j) + (k)]
#define BTF_RFV_SET int
#define BTF_RFV_COUNT(s) pi[RFP_NVIEWS]
#define BTF_RFV_THETA(s, i) pf[pi[RFP_THETA] + (i)]
#define BTF_RFV_PHI(s, i) pf[pi[RFP_PHI] + (i)]
#define BTF_RFV_RING_END(s, i) pi[pi[RFP_RING_END] + (i)]

// The sample texel (index into the codes) that surface texel (x, y)
// shows: src/rf/rf_map.h's rf_surface_texel, the map entry's u and v
// clamped into the sample; a model without a map is its own surface.
uint rf_surface_texel(int x, int y)
{
    if (pi[RFP_MAP] < 0)
        return uint(y) * uint(pi[RFP_WIDTH]) + uint(x);
    uint e = uint(pi[uint(pi[RFP_MAP]) + uint(y) * uint(pi[RFP_WIDTH]) + uint(x)]);
    uint sw = uint(pi[RFP_SAMPLE_W]), sh = uint(pi[RFP_SAMPLE_H]);
    uint u = e & 0xFFFFu, v = e >> 16u;
    u = u < sw ? u : sw - 1u;
    v = v < sh ? v : sh - 1u;
    return v * sw + u;
}

#include "btf_rf_shared.h"

uint rf_word(int b, uint i)
{
    if (b < 4)
        return b == 0 ? c0[i] : b == 1 ? c1[i] : b == 2 ? c2[i] : c3[i];
    return b == 4 ? c4[i] : b == 5 ? c5[i] : b == 6 ? c6[i] : c7[i];
}

// Where texel t of field f starts: (code buffer, index of its first
// 16-bit code in that buffer, float offsets of the field's lo and scale),
// found once per field so that each slot costs one code and two floats.
uvec4 btf_rf_open(int f, uint t)
{
    int slots = pi[RFP_SLOTS];
    uint b = uint(pi[pi[RFP_FIELD_BUF] + f]);
    uint c = 2u * uint(pi[pi[RFP_FIELD_BASE] + f]) + t * uint(slots);
    int k = f * slots;
    return uvec4(b, c, uint(pi[RFP_LO] + k), uint(pi[RFP_SCALE] + k));
}

// Slot s of an opened texel, dequantised (btf_rf_dequant, as the CPU's
// rf_texel_params): read where the shared text uses it.
float btf_rf_param(uvec4 src, int s)
{
    uint c = src.y + uint(s);
    uint w = rf_word(int(src.x), c >> 1u);
    uint q = (w >> ((c & 1u) * 16u)) & 0xFFFFu;
    return btf_rf_dequant(q, pf[src.z + uint(s)], pf[src.w + uint(s)]);
}

void main()
{
    uint p = gl_GlobalInvocationID.y * uint(pi[RFP_ROW_PIX]) + gl_GlobalInvocationID.x;
    if (p >= uint(pi[RFP_NPIX]))
        return;
    btf_rf_rgb c;
    if (pi[RFP_MODE] == RFP_MODE_TILE) {
        uint q = p + uint(pi[RFP_PIX0]);
        uint tw = uint(pi[RFP_TILE_W]);
        btf_rf_views vs = btf_rf_views(pi[RFP_VIEW_F], pi[RFP_VIEW_F + 1], pi[RFP_VIEW_F + 2],
                                       pi[RFP_VIEW_F + 3], pf[RFP_VIEW_W], pf[RFP_VIEW_W + 1],
                                       pf[RFP_VIEW_W + 2], pf[RFP_VIEW_W + 3]);
        c = btf_rf_blend(0, vs, BTF_RF_TEXEL_AT(0, q % tw, q / tw), pf[RFP_LIGHT],
                         pf[RFP_LIGHT + 1], pf[RFP_LIGHT + 2], pf[RFP_VIEW], pf[RFP_VIEW + 1],
                         pf[RFP_VIEW + 2]);
    } else {
        uint g = p * uint(BTF_RP_GB);
        if (gb[g] < 0.0) {
            c = btf_rf_rgb(pf[RFP_BG], pf[RFP_BG + 1], pf[RFP_BG + 2]);
        } else {
            c = btf_rf_shade_pixel(0, gb[g + 3u], gb[g + 4u], gb[g + 5u], gb[g + 6u],
                                   gb[g + 7u], gb[g + 8u], gb[g + 9u], gb[g + 10u], gb[g + 11u],
                                   gb[g + 12u], gb[g + 13u], gb[g + 14u], gb[g + 15u],
                                   gb[g + 16u], gb[g + 17u], gb[g + 1u], gb[g + 2u]);
        }
    }
    rgb[3u * p] = c.r;
    rgb[3u * p + 1u] = c.g;
    rgb[3u * p + 2u] = c.b;
}
