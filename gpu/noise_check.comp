// noise_check.comp -- checks that src/synth/btf_noise.h compiles as GLSL and
// gives the GPU side of the CPU/GPU bit-exactness test of the synthesis
// noise (the white noise of the CAR fields, Haindl & Filip 2007, II.C).
// Invocation i covers (row0 + i / nblocks, block0 + i % nblocks): it writes
// btf_noise4 for that (row, block) to z[i], the raw Philox-4x32-7 words of
// the same counter to raw[i], and btf_noise1 of the block's 4 columns to z1[i].
// The workgroup size is specialisation constant 0 (default 64), so the host
// test (tests/unit/test_vk.c) can check that results do not depend on it.
#version 450
#extension GL_GOOGLE_include_directive : require

#include "btf_noise.h"

layout(local_size_x = 64, local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) writeonly buffer Noise4 { vec4 z[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Raw { uvec4 raw[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Noise1 { vec4 z1[]; };

layout(push_constant) uniform Params {
    uint seed_lo, seed_hi, stream;
    uint row0, block0, nblocks, count;
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    uint row = pc.row0 + i / pc.nblocks;
    uint block = pc.block0 + i % pc.nblocks;
    z[i] = btf_noise4(pc.seed_lo, pc.seed_hi, pc.stream, row, block);
    raw[i] = btf_philox(uvec4(block, row, pc.stream, BTF_NOISE_TAG),
                        uvec2(pc.seed_lo, pc.seed_hi));
    vec4 one;
    for (uint c = 0u; c < 4u; c++)
        one[c] = btf_noise1(pc.seed_lo, pc.seed_hi, pc.stream, row, 4u * block + c);
    z1[i] = one;
}
