// synth_task.glsl -- the task records the synthesis shaders read (std430;
// CAR synthesis, Haindl & Filip 2007, section II.C).
// Their C mirror is in gpu/synth_gpu.c (gpu_task, gpu_unmix): 4-byte
// members only, so both sides agree on the layout without padding rules.

// One CAR field: (subspace, band, level). Offsets are pre-ordered by the
// host in btf_shared.h's sum order: earlier rows first (stored order), then
// the same row from the farthest column to the nearest; the noise term is
// added between the two groups.
struct Task {
    int fx0, fy0, fw, fh;     // absolute column of the buffer's column 0 and row of its
                              // row 0; buffer width and rows (a strip of the field)
    int rows_given;           // rows [0, rows_given) of the buffer are given (carried
                              // over from the previous strip, or zero before the
                              // field's first row); rows [rows_given, fh) are computed
    int x0, y0;               // the level's window in this strip (absolute): first
    int window_w, window_h;   // column and row, width and rows
    uint field_off, gauss_off; // offsets (floats) into Fields[] and Gauss[]
    uint stream;              // noise stream (subspace, band, level)
    int n_offsets;            // neighbours (off_r, off_c, gamma)
    int n_earlier;            // of which the first n_earlier are on earlier rows
    int slope;                // wavefront slope a: pixel (r, c) is ready at step a r + c
    int coarse;               // the task of level + 1 of the same band, or -1
    int period_w, period_h;   // tileable: pixel (r, c) takes the noise of (r mod period_h,
                              // c mod period_w), btf_period_coord; 0: not periodic
    float sigma, mean;
    int off_r[24];
    int off_c[24];
    float gamma[24];
};

// One subspace image: the inverse decorrelation of its three level-0 bands.
struct Unmix {
    float mean[3];
    float basis[9];
    uint gauss_off[3];        // level-0 G windows of bands 0, 1, 2
    uint out_off;             // offset (floats) of the RGB image in Out[]
    int width, height;        // the image's width, the strip's rows
    int transfer;             // 1: the marginal transfer is on (src/synth/marginal.c)
    float origin[3], inv_h[3]; // per band: the grid (btf_knot_pos), the end knots on it,
    float tlo[3], thi[3];      // the exemplar's range
    float qmin[3], qmax[3];
    float q[48];              // [band * 16 + i]: segment i's start value and rise
    float dq[48];
    float lo[3], hi[3];       // the RGB box, the mean's distances below and above
    float nlo[3], nhi[3];
};
