// synth_unmix.comp -- the inverse spectral decorrelation on the GPU (Haindl
// & Filip 2007, section II.C, the last step of synthesis; section III, the
// 3 x 3 inverse decorrelation matrix applied to each colour pixel):
// rgb_k = mean_k + sum_b basis[b][k] band_b, with btf_unmix as on the CPU
// (src/synth/colour.c); with a marginal transfer, each band through it
// first and the RGB result brought into the exemplar's box after
// (src/synth/marginal.c, the table made on the host by the same function).
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

// The marginal transfer of band b at v: as transfer1 (src/synth/marginal.c).
float transfer_band(uint j, int b, float v)
{
    float t = btf_knot_pos(v, jobs[j].origin[b], jobs[j].inv_h[b], jobs[j].tlo[b],
                           jobs[j].thi[b]);
    float fl = btf_knot_segment(floor(t));
    int i = b * 16 + (int(fl) & 15); // the lower tail's -1 is entry 15
    return btf_transfer(t, fl, jobs[j].q[i], jobs[j].dq[i], jobs[j].qmin[b], jobs[j].qmax[b]);
}

// The colour into the exemplar's box, as btf__marginal_gamut (src/synth/marginal.c).
void gamut(uint j, inout float c[3])
{
    int inside = 1;
    for (int k = 0; k < 3; k++)
        inside &= btf_in_box(c[k], jobs[j].lo[k], jobs[j].hi[k]);
    if (inside != 0)
        return;
    float s = 1.0;
    for (int k = 0; k < 3; k++) {
        float sk = btf_gamut_share(c[k], jobs[j].mean[k], jobs[j].lo[k], jobs[j].hi[k],
                                   jobs[j].nlo[k], jobs[j].nhi[k]);
        s = sk < s ? sk : s;
    }
    s = s < 0.0 ? 0.0 : s;
    for (int k = 0; k < 3; k++) {
        precise float dk = c[k] - jobs[j].mean[k];
        c[k] = btf_clampf(btf_gamut_point(jobs[j].mean[k], s, dk), jobs[j].lo[k], jobs[j].hi[k]);
    }
}

void main()
{
    uint j = pc.job_base + gl_WorkGroupID.x;
    uint count = uint(jobs[j].width) * uint(jobs[j].height);
    uint p_end = min(count, (gl_WorkGroupID.y + 1u) * uint(BTF_GPU_CHUNK));
    bool on = jobs[j].transfer != 0;
    for (uint p = gl_WorkGroupID.y * uint(BTF_GPU_CHUNK) + gl_LocalInvocationID.x; p < p_end;
         p += 64u) {
        float b0 = gauss[jobs[j].gauss_off[0] + p];
        float b1 = gauss[jobs[j].gauss_off[1] + p];
        float b2 = gauss[jobs[j].gauss_off[2] + p];
        // a non-finite band skips the transfer, so that the host's finite
        // test refuses the image as the CPU does (btf__unmix_row)
        uint e = 0x7F800000u;
        bool finite = (floatBitsToUint(b0) & e) != e && (floatBitsToUint(b1) & e) != e &&
                      (floatBitsToUint(b2) & e) != e;
        bool apply = on && finite;
        if (apply) {
            b0 = transfer_band(j, 0, b0);
            b1 = transfer_band(j, 1, b1);
            b2 = transfer_band(j, 2, b2);
        }
        float c[3];
        for (int k = 0; k < 3; k++)
            c[k] = btf_unmix(jobs[j].mean[k], jobs[j].basis[k], jobs[j].basis[3 + k],
                             jobs[j].basis[6 + k], b0, b1, b2);
        if (apply)
            gamut(j, c);
        for (int k = 0; k < 3; k++)
            rgb[jobs[j].out_off + 3u * p + uint(k)] = c[k];
    }
}
