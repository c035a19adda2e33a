/*
 * match_layout.h — where the colour-matching passes on the GPU
 * (gpu/match_sample.comp, match_sort.comp, match_apply.comp) find their
 * parameters, shared by the shaders and the host code (gpu/match_gpu.c).
 * The int buffer holds BTF_MP_INTS ints, the float buffer BTF_MF_MAPS
 * floats of constants and then the three Lab maps (each origin, inv_h,
 * q[SEGS + 1], dq[SEGS]: src/synth/synth.h's btf_lab_map). The constants
 * are made by the C code (src/synth/colour_lab.c) and passed in, not
 * written in the shaders, so that both sides round them the same way.
 * Plain #defines: the common subset of C and GLSL.
 */
#ifndef BTF_MATCH_LAYOUT_H
#define BTF_MATCH_LAYOUT_H

/* ints */
#define BTF_MP_WIDTH 0
#define BTF_MP_HEIGHT 1
#define BTF_MP_OFF 2     /* float offset of the image in the array */
#define BTF_MP_CAP 3     /* floats per buffer of the array (gpu/synth_gpu.h) */
#define BTF_MP_SX 4      /* the sample grid's steps, its columns, its count */
#define BTF_MP_SY 5
#define BTF_MP_COLS 6
#define BTF_MP_NSAMPLE 7
#define BTF_MP_NPAD 8    /* the sort's length: a power of two >= NSAMPLE */
#define BTF_MP_PW 9      /* the structure layer's pattern: width, height, */
#define BTF_MP_PH 10
#define BTF_MP_PCH 11    /* channels (1 or 3; 0: no pattern) */
#define BTF_MP_MATCH 12  /* 1: colour matching, 0: the pattern's multiply only */
#define BTF_MP_ROW_PIX 13 /* pixels per row of workgroups (gx * 64) */
#define BTF_MP_MAGIC 14  /* the cube root's exponent-bit estimate */
#define BTF_MP_INTS 16

/* floats */
#define BTF_MF_SCALE 0   /* the exposure (btf__lab_scale) and its inverse */
#define BTF_MF_INV 1
#define BTF_MF_LO 2      /* [3] the exemplar's RGB box */
#define BTF_MF_HI 5      /* [3] */
#define BTF_MF_TO_XYZ 8  /* [3][3] RGB -> XYZ / white, row-major */
#define BTF_MF_TO_RGB 17 /* [3][3] XYZ * white -> RGB, row-major */
#define BTF_MF_CONST 26  /* [10] T0, SLOPE, F0, F_T0, 1/3, LIGHT_MAX,
                            1/116, 1/500, 1/200, 1/SLOPE */
#define BTF_MF_MAPS 36
#define BTF_MF_MAP_FLOATS (2 + 2 * BTF_MATCH_SEGS + 1)
#define BTF_MATCH_SEGS 256 /* = BTF_LAB_MAP_SEGS (checked in match_gpu.c) */

#endif
