// match_apply.comp -- the last pass of colour matching on the device
// (docs/gpu.md, "Colour matching on the device"): each pixel times the
// structure layer's pattern, then (when matching) to Lab, each channel
// through its map, back to RGB clamped into the exemplar's box, in place:
// btf__structure_apply_row and btf__lab_match_row (src/model/structure_map.c,
// src/synth/colour_lab.c) with the same bits. One invocation per pixel, the
// workgroups in rows of ROW_PIX pixels (a frame may have more workgroups
// than a dispatch's x may count).
#version 450
#extension GL_GOOGLE_include_directive : require

#include "match_layout.h"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) buffer Img0 { float img0[]; };
layout(std430, set = 0, binding = 1) buffer Img1 { float img1[]; };
layout(std430, set = 0, binding = 2) buffer Img2 { float img2[]; };
layout(std430, set = 0, binding = 3) buffer Img3 { float img3[]; };
layout(std430, set = 0, binding = 4) buffer Img4 { float img4[]; };
layout(std430, set = 0, binding = 5) buffer Img5 { float img5[]; };
layout(std430, set = 0, binding = 6) buffer Img6 { float img6[]; };
layout(std430, set = 0, binding = 7) buffer Img7 { float img7[]; };
layout(std430, set = 0, binding = 8) readonly buffer Ints { int pi[]; };
layout(std430, set = 0, binding = 9) readonly buffer Floats { float pf[]; };
layout(std430, set = 0, binding = 10) readonly buffer Pattern { float pat[]; };

#include "match_lab.glsl"

void img_write(int f, float v)
{
    int cap = pi[BTF_MP_CAP];
    int b = f / cap;
    int i = f - b * cap;
    switch (b) {
    case 0: img0[i] = v; break;
    case 1: img1[i] = v; break;
    case 2: img2[i] = v; break;
    case 3: img3[i] = v; break;
    case 4: img4[i] = v; break;
    case 5: img5[i] = v; break;
    case 6: img6[i] = v; break;
    default: img7[i] = v; break;
    }
}

void main()
{
    int w = pi[BTF_MP_WIDTH];
    int p = int(gl_WorkGroupID.y) * pi[BTF_MP_ROW_PIX] + int(gl_WorkGroupID.x) * 64 +
            int(gl_LocalInvocationID.x);
    if (p >= w * pi[BTF_MP_HEIGHT])
        return;
    vec3 c = pixel_read(p % w, p / w);
    if (pi[BTF_MP_MATCH] != 0) {
        vec3 lab = lab_pixel(c);
        c = rgb_pixel(vec3(map_at(0, lab.x), map_at(1, lab.y), map_at(2, lab.z)));
    }
    int f = pi[BTF_MP_OFF] + 3 * p;
    img_write(f, c.x);
    img_write(f + 1, c.y);
    img_write(f + 2, c.z);
}
