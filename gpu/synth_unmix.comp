// synth_unmix.comp -- the inverse spectral decorrelation on the GPU (Haindl
// & Filip 2007, section II.C, the last step of synthesis; section III, the
// 3 x 3 inverse decorrelation matrix applied to each colour pixel):
// rgb_k = mean_k + sum_b basis[b][k] band_b, with btf_unmix as on the CPU
// (src/synth/colour.c).
// One workgroup per subspace image, a grid-stride loop over its pixels.
#version 450
#extension GL_GOOGLE_include_directive : require

#define BTF_GLSL 1
#include "btf_shared.h"
#include "synth_task.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Unmixes { Unmix jobs[]; };
layout(std430, set = 0, binding = 1) readonly buffer Gauss { float gauss[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { float rgb[]; };

// x: the image, y: a chunk of BTF_GPU_CHUNK pixels (see synth_collapse.comp).
layout(push_constant) uniform Params {
    uint job_base;
} pc;

void main()
{
    uint j = pc.job_base + gl_WorkGroupID.x;
    uint count = uint(jobs[j].width) * uint(jobs[j].height);
    uint p_end = min(count, (gl_WorkGroupID.y + 1u) * uint(BTF_GPU_CHUNK));
    for (uint p = gl_WorkGroupID.y * uint(BTF_GPU_CHUNK) + gl_LocalInvocationID.x; p < p_end;
         p += 64u) {
        float b0 = gauss[jobs[j].gauss_off[0] + p];
        float b1 = gauss[jobs[j].gauss_off[1] + p];
        float b2 = gauss[jobs[j].gauss_off[2] + p];
        for (int k = 0; k < 3; k++)
            rgb[jobs[j].out_off + 3u * p + uint(k)] =
                btf_unmix(jobs[j].mean[k], jobs[j].basis[k], jobs[j].basis[3 + k],
                          jobs[j].basis[6 + k], b0, b1, b2);
    }
}
