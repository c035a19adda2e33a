// hemisphere_check.comp -- compiles src/render/btf__hemisphere_lookup.h as GLSL
// (the accessors a render shader defines over storage buffers; docs/render.md,
// "Interpolation over the hemisphere"), so the build proves the shared text
// stays valid GLSL. Not dispatched by the library; the render pass (render.comp)
// is its user.
#version 450
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer P { float pts[]; };
layout(std430, binding = 1) readonly buffer I { int ints[]; };
layout(std430, binding = 2) buffer O { float outw[]; };
layout(push_constant) uniform PC { int tri_off, cs_off, ct_off, hull_off, apex_off, grid, n_hull; } pc;
#define BTF_HEMI_TABLE int
#define BTF_HEMI_POINT(tab, i, k) pts[2 * (i) + (k)]
#define BTF_HEMI_TRIANGLE(tab, t, k) ints[pc.tri_off + 3 * (t) + (k)]
#define BTF_HEMI_GRID(tab) pc.grid
#define BTF_HEMI_CELL_START(tab, c) ints[pc.cs_off + (c)]
#define BTF_HEMI_CELL_TRI(tab, j) ints[pc.ct_off + (j)]
#define BTF_HEMI_N_HULL(tab) pc.n_hull
#define BTF_HEMI_HULL(tab, i) ints[pc.hull_off + (i)]
#define BTF_HEMI_HULL_APEX(tab, i) ints[pc.apex_off + (i)]
#include "../src/render/btf_hemisphere_lookup.h"
void main() {
    uint g = gl_GlobalInvocationID.x;
    btf_hemi_weights r = btf_hemi_lookup(0, outw[3 * g], outw[3 * g + 1], outw[3 * g + 2]);
    outw[3 * g] = r.w0; outw[3 * g + 1] = r.w1 + float(r.i0); outw[3 * g + 2] = r.w2;
}
