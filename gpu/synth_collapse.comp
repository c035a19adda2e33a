// synth_collapse.comp -- one pyramid level of the collapse on the GPU
// (Haindl & Filip 2007, section II.C: the synthesised levels recombined;
// section III, "Synthesis of the BTF Subspace Images", on the GPU):
//     G_l = mean_l + Y_l + up(G_{l+1})
// over the level's window, the up-sampling done as on the CPU
// (src/synth/upsample.c): horizontally within each of the coarse rows the
// fine row reads, then vertically, with btf_up_even / btf_up_odd. Dispatched
// level by level, from the coarsest; one workgroup per field, a grid-stride
// loop over its pixels.
#version 450
#extension GL_GOOGLE_include_directive : require

#define BTF_GLSL 1
#include "btf_shared.h"
#include "synth_task.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Tasks { Task tasks[]; };
layout(std430, set = 0, binding = 1) readonly buffer Fields { float fields[]; };
layout(std430, set = 0, binding = 2) buffer Gauss { float gauss[]; };

// Each workgroup (x: the field, y: a chunk of BTF_GPU_CHUNK pixels) loops at
// most BTF_GPU_CHUNK / 64 times: lavapipe silently stops longer loops.
layout(push_constant) uniform Params {
    uint task_base;
} pc;

// Coarse row q of task ct, up-sampled horizontally to fine column x.
float coarse_up(int ct, int q, int x)
{
    uint row = tasks[ct].gauss_off + uint((q - tasks[ct].y0) * tasks[ct].window_w);
    int ci = btf_floordiv2(x) - tasks[ct].x0;
    if ((x & 1) != 0)
        return btf_up_odd(gauss[row + uint(ci)], gauss[row + uint(ci + 1)]);
    return btf_up_even(gauss[row + uint(ci - 1)], gauss[row + uint(ci)], gauss[row + uint(ci + 1)]);
}

void main()
{
    uint t = pc.task_base + gl_WorkGroupID.x;
    int w = tasks[t].window_w, h = tasks[t].window_h, ct = tasks[t].coarse;
    uint count = uint(w) * uint(h);
    uint p_end = min(count, (gl_WorkGroupID.y + 1u) * uint(BTF_GPU_CHUNK));
    for (uint p = gl_WorkGroupID.y * uint(BTF_GPU_CHUNK) + gl_LocalInvocationID.x; p < p_end;
         p += 64u) {
        int x = tasks[t].x0 + int(p % uint(w)), y = tasks[t].y0 + int(p / uint(w));
        float f = fields[tasks[t].field_off +
                         uint((y - tasks[t].fy0) * tasks[t].fw + (x - tasks[t].fx0))];
        float v = btf_add_mean(tasks[t].mean, f);
        if (ct >= 0) {
            int i = btf_floordiv2(y);
            float up;
            if ((y & 1) != 0)
                up = btf_up_odd(coarse_up(ct, i, x), coarse_up(ct, i + 1, x));
            else
                up = btf_up_even(coarse_up(ct, i - 1, x), coarse_up(ct, i, x),
                                 coarse_up(ct, i + 1, x));
            v = btf_add_level(v, up);
        }
        gauss[tasks[t].gauss_off + p] = v;
    }
}
