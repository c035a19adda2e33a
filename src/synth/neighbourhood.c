/*
 * neighbourhood.c — a CAR band as synthesis sees it (Haindl & Filip 2007,
 * section II.C: the recursion Y_r = sum_s gamma_s Y_{r+s} + sigma e_r over
 * a causal neighbourhood): the order in which the terms of one pixel are
 * added, the same-row shapes the fast loops are written for, and the
 * checks a band must pass before any backend synthesises it. CPU
 * generators (rows, wavefront) and the GPU host code order the terms
 * through these functions, which is what keeps them bit-identical.
 */
#include "core/core.h"
#include "car/car.h"
#include "synth/synth.h"

#include "btf_shared.h"

int btf__car_same_row_order(const btf_car_band *b, int *idx)
{
    int n = 0;
    for (int s = 0; s < b->n; s++)
        if (b->offsets[s].row == 0)
            idx[n++] = s;
    for (int i = 1; i < n; i++) /* insertion sort by column, ascending; stable */
        for (int j = i; j > 0 && b->offsets[idx[j]].col < b->offsets[idx[j - 1]].col; j--) {
            int t = idx[j];
            idx[j] = idx[j - 1];
            idx[j - 1] = t;
        }
    return n;
}

int btf__car_same_row_shape(const btf_car_band *b, float gamma3[3])
{
    int idx[BTF_CAR_MAX_NEIGHBOURS];
    int n = btf__car_same_row_order(b, idx);
    if (n > 3)
        return -1;
    gamma3[0] = gamma3[1] = gamma3[2] = 0.0f;
    for (int k = 0; k < n; k++) {
        if (b->offsets[idx[k]].col != k - n)
            return -1;
        gamma3[3 - n + k] = b->gamma[idx[k]];
    }
    return n;
}

btf_status btf__synth_check_band(const btf_car_band *b, int margin, btf_error *err)
{
    if (b->n < 0 || b->n > BTF_CAR_MAX_NEIGHBOURS)
        return btf__fail(err, BTF_E_ARG, "CAR model with %d neighbours", b->n);
    if (margin < 0 || margin > BTF_SYNTH_MARGIN_MAX)
        return btf__fail(err, BTF_E_ARG, "CAR synthesis margin %d: expected 0..%d", margin,
                         BTF_SYNTH_MARGIN_MAX);
    for (int s = 0; s < b->n; s++) {
        btf_offset o = b->offsets[s];
        if (!(o.row < 0 || (o.row == 0 && o.col < 0)))
            return btf__fail(err, BTF_E_ARG, "CAR offset %d:%d is not causal", o.row, o.col);
        /* the bound of model files and neighbourhood specs: one rule for
         * every way a band comes in (the API takes any int8 offset) */
        if (o.row < -64 || o.col < -64 || o.col > 64)
            return btf__fail(err, BTF_E_ARG, "CAR offset %d:%d reaches beyond 64 pixels", o.row,
                             o.col);
    }
    return BTF_OK;
}

btf_status btf__synth_check_size(int width, int height, btf_error *err)
{
    if (width < 1 || height < 1 || width > BTF_SYNTH_MAX_SIDE || height > BTF_SYNTH_MAX_SIDE)
        return btf__fail(err, BTF_E_ARG, "synthesis size %dx%d: expected 1..%d on each side", width,
                         height, BTF_SYNTH_MAX_SIDE);
    return BTF_OK;
}
