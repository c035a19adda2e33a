// match_sort.comp -- one step of a bitonic sort (Batcher 1968) of the three
// rows of keys match_sample.comp wrote, each row of NPAD (a power of two)
// keys on its own: the exact order statistics of the sample, whose values
// the host turns into quantiles by the CPU's code (btf__lab_quantiles_at,
// src/synth/colour_lab.c), so that the maps are the CPU's. A sort of 16,384
// keys is 105 such steps; each invocation compares one pair.
#version 450

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) buffer Keys { float keys[]; };

layout(push_constant) uniform Params {
    uint j;    // the pair's distance
    uint k;    // the merged runs' length
    uint npad; // keys per row
    uint base; // unused (the last word of every push: synth_gpu.c's dispatch)
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= 3u * pc.npad)
        return;
    uint row = i / pc.npad, at = i % pc.npad, other = at ^ pc.j;
    if (other <= at)
        return;
    uint a = row * pc.npad + at, b = row * pc.npad + other;
    bool up = (at & pc.k) == 0u;
    float x = keys[a], y = keys[b];
    if ((x > y) == up) {
        keys[a] = y;
        keys[b] = x;
    }
}
