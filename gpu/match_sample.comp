// match_sample.comp -- the first pass of colour matching on the device
// (docs/gpu.md, "Colour matching on the device"; the CPU's pass is
// src/synth/colour_match.c): the L*, a*, b* of the image's sample grid
// (btf__lab_sample_row: every sx-th pixel of every sy-th row), after the
// structure layer's multiply, into three rows of NPAD keys; the keys past
// the sample are +Inf, so that the sort (match_sort.comp) leaves them last.
// One invocation per key.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "match_layout.h"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Img0 { float img0[]; };
layout(std430, set = 0, binding = 1) readonly buffer Img1 { float img1[]; };
layout(std430, set = 0, binding = 2) readonly buffer Img2 { float img2[]; };
layout(std430, set = 0, binding = 3) readonly buffer Img3 { float img3[]; };
layout(std430, set = 0, binding = 4) readonly buffer Img4 { float img4[]; };
layout(std430, set = 0, binding = 5) readonly buffer Img5 { float img5[]; };
layout(std430, set = 0, binding = 6) readonly buffer Img6 { float img6[]; };
layout(std430, set = 0, binding = 7) readonly buffer Img7 { float img7[]; };
layout(std430, set = 0, binding = 8) readonly buffer Ints { int pi[]; };
layout(std430, set = 0, binding = 9) readonly buffer Floats { float pf[]; };
layout(std430, set = 0, binding = 10) readonly buffer Pattern { float pat[]; };
layout(std430, set = 0, binding = 11) writeonly buffer Keys { float keys[]; };

#include "match_lab.glsl"

void main()
{
    int s = int(gl_GlobalInvocationID.x), npad = pi[BTF_MP_NPAD];
    if (s >= npad)
        return;
    if (s >= pi[BTF_MP_NSAMPLE]) {
        float inf = uintBitsToFloat(0x7f800000u);
        keys[s] = inf;
        keys[npad + s] = inf;
        keys[2 * npad + s] = inf;
        return;
    }
    int cols = pi[BTF_MP_COLS];
    int x = (s % cols) * pi[BTF_MP_SX], y = (s / cols) * pi[BTF_MP_SY];
    vec3 lab = lab_pixel(pixel_read(x, y));
    keys[s] = lab.x;
    keys[npad + s] = lab.y;
    keys[2 * npad + s] = lab.z;
}
