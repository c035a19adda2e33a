// synth_field.comp -- the causal recursion of CAR random fields on the GPU
// (Haindl & Filip 2007, section II.C: each sub-band level is a CAR field;
// section III, "Synthesis of the BTF Subspace Images", on the GPU).
// One workgroup per field; the recursion
//     Y(r, c) = sum_s gamma_s Y(r + dr_s, c + dc_s) + sigma e(r, c)
// is parallelised as a wavefront: pixel (r, c) depends only on pixels of
// earlier wavefront steps when the step is t = a r + c with a > dc / |dr| for
// every offset of an earlier row (a = 2 for the usual up-right neighbour), so
// every pixel of one step is computed at once, a barrier between steps. No
// spin-waiting between workgroups (no forward-progress guarantee). Tileable
// fields take the noise of their coordinates modulo the level's period. The sums,
// noise and zero boundary are those of the CPU reference (src/synth/rows.c):
// the results are bit-identical.
#version 450
#extension GL_GOOGLE_include_directive : require

#define BTF_GLSL 1
#include "btf_shared.h"
#include "synth_task.glsl"

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Tasks { Task tasks[]; };
layout(std430, set = 0, binding = 1) coherent buffer Fields { float fields[]; };

// lavapipe ends a shader invocation after 65,535 loop iterations in all,
// silently (the rows beyond came out unwritten), so the host runs the
// wavefront in chunks of steps [s0, s1), one dispatch each; the field buffer
// carries the state between them.
layout(push_constant) uniform Params {
    uint seed_lo, seed_hi;
    int s0, s1;               // wavefront steps of this dispatch
    uint task_base;           // dispatches of more than 65535 fields are split
} pc;

float field_at(uint base, int fw, int r, int c)
{
    // Outside the field (rows before its first, columns beyond its edges): 0.
    return (r >= 0 && c >= 0 && c < fw) ? fields[base + uint(r * fw + c)] : 0.0;
}

void main()
{
    uint t = pc.task_base + gl_WorkGroupID.x;
    int fw = tasks[t].fw, rb = tasks[t].rows_given, a = tasks[t].slope, n = tasks[t].n_offsets;
    int rows = tasks[t].fh - rb; // rows to compute, from buffer row rb
    uint base = tasks[t].field_off;
    int steps = rows > 0 ? a * (rows - 1) + fw : 0;
    for (int s = pc.s0; s < min(steps, pc.s1); s++) {
        // Rows rb + q with c = s - a q inside [0, fw).
        int qlo = (s - fw + 1 > 0) ? (s - fw + a) / a : 0;
        int qhi = min(rows - 1, s / a);
        for (int q = qlo + int(gl_LocalInvocationID.x); q <= qhi; q += 64) {
            int c = s - a * q, r = rb + q;
            precise float acc = 0.0;
            int np = tasks[t].n_earlier;
            for (int k = 0; k < np; k++)
                acc = btf_car_accumulate(acc, tasks[t].gamma[k],
                                         field_at(base, fw, r + tasks[t].off_r[k],
                                                  c + tasks[t].off_c[k]));
            int nr = tasks[t].fy0 + r, nc = tasks[t].fx0 + c;
            if (tasks[t].period_w > 0) { // tileable: periodic noise, as src/synth/rows.c
                nr = btf_period_coord(nr, tasks[t].period_h);
                nc = btf_period_coord(nc, tasks[t].period_w);
            }
            uint urow = uint(nr + BTF_NOISE_ORIGIN);
            uint ucol = uint(nc + BTF_NOISE_ORIGIN);
            float e = btf_noise1(pc.seed_lo, pc.seed_hi, tasks[t].stream, urow, ucol);
            acc = btf_car_output(acc, tasks[t].sigma, e);
            for (int k = np; k < n; k++)
                acc = btf_car_accumulate(acc, tasks[t].gamma[k],
                                         field_at(base, fw, r + tasks[t].off_r[k],
                                                  c + tasks[t].off_c[k]));
            fields[base + uint(r * fw + c)] = acc;
        }
        memoryBarrierBuffer();
        barrier();
    }
}
