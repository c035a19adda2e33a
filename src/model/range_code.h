/*
 * range_code.h — the range-map tile's quantisation and prediction coding
 * (model/range_code.c; Haindl & Filip 2007, section II.B; the layout is
 * docs/model-format.md, "RANG: the range-map tile"), used by the model file
 * (model/model_maps.c), the analysis and model/range_periodic.c. Private
 * to the library.
 */
#ifndef BTF_RANGE_CODE_H
#define BTF_RANGE_CODE_H

#include <stddef.h>
#include <stdint.h>

/* The range map's grid: h = (k + q + 1/2) 2^e, q in [0, 65535], with
 * k + q + 1/2 held exactly by a float (24-bit significand) and no value
 * below the smallest denormal or above FLT_MAX. */
#define BTF_RANGE_GRID_E_MIN (-148)
#define BTF_RANGE_GRID_E_MAX 105
#define BTF_RANGE_GRID_Q_MAX 65535.0
#define BTF_RANGE_GRID_K_LIMIT 8388608.0 /* 2^23 */

/* The canonical grid (e, k) of heights in [lo, hi]: the smallest e at which
 * every height floors to k + q with q <= 65535 and k + q + 1 within 24 bits;
 * -1 when no e fits. */
int btf__range_grid_choose(double lo, double hi, int *e, int32_t *k);
/* The height of grid value q: (k + q + 1/2) 2^e as a float. */
float btf__range_grid_value(int e, int32_t k, unsigned q);
/* The lowest and highest of n >= 1 heights. */
void btf__range_extremes(const float *h, size_t n, float *lo, float *hi);
/* Moves n finite heights onto their canonical grid, as writing and reading
 * them would (a tile on its grid is a fixed point of the file); -1 when
 * their span fits no grid (they stay). */
int btf__range_snap(float *h, size_t n);
/* The prediction of quantised sample (x, y) of a w-wide tile q from its
 * left, upper and upper-left neighbours (those before it in row order). */
unsigned btf__range_predict(const uint16_t *q, int w, int x, int y);
/* The residual q - pred modulo 2^16, zigzag-coded (0, -1, 1, -2 -> 0, 1, 2,
 * 3), and back: unzigzag(zigzag(q, p), p) == q. */
unsigned btf__range_zigzag(unsigned q, unsigned pred);
unsigned btf__range_unzigzag(unsigned z, unsigned pred);

#endif
