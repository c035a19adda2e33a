/*
 * render_layout.h — where the GPU render pass (gpu/render.comp) finds its
 * parameters, shared by the shader and the host code (gpu/render_gpu.c).
 * Two buffers carry them: the int buffer starts with BTF_RP_INTS ints of
 * header (then the index table, the have flags, the texture offsets and the
 * two hemisphere tables' int arrays), the float buffer with BTF_RP_FLOATS
 * floats of header (then the two tables' points). Plain #defines: the
 * common subset of C and GLSL.
 */
#ifndef BTF_RENDER_LAYOUT_H
#define BTF_RENDER_LAYOUT_H

/* ints */
#define BTF_RP_SIZE 0       /* side of the textures */
#define BTF_RP_NSET 1       /* measured lights (the index table's row) */
#define BTF_RP_NLIGHTS 2    /* the scene's lights */
#define BTF_RP_NPIX 3       /* pixels of this band of the frame */
#define BTF_RP_ROW_PIX 4    /* pixels per dispatch row (gx * 64) */
#define BTF_RP_INDEX 5      /* int offset of the index table */
#define BTF_RP_HAVE 6       /* int offset of the have flags, one per subspace */
#define BTF_RP_TEXOFF 7     /* int offset of the float offsets of the subspace images */
#define BTF_RP_NORMAL 8     /* float offset of the normal map in the maps buffer */
#define BTF_RP_GAIN 9       /* float offset of the pair gains (3 per pair) */
#define BTF_RP_HORIZON 10   /* 1: binding 6 holds the horizon map (shadows) */
#define BTF_RP_TEXCAP 11    /* floats per buffer: the subspace images are one array
                               over bindings 1, 8, 9, 10, the range and normal maps
                               one over 2, 11, 12, 13; float f in buffer f / cap at
                               f % cap (gpu/synth_gpu.h) */
#define BTF_RP_KIND 16      /* [16]: light kinds */
#define BTF_RP_TAB 32       /* two tables of BTF_RP_TAB_STRIDE ints: */
#define BTF_RP_TAB_STRIDE 8
#define BTF_RP_T_GRID 0
#define BTF_RP_T_NHULL 1
#define BTF_RP_T_TRI 2      /* int offsets of the arrays */
#define BTF_RP_T_CS 3
#define BTF_RP_T_CT 4
#define BTF_RP_T_HULL 5
#define BTF_RP_T_APEX 6
#define BTF_RP_T_PTS 7      /* float offset of the points */
#define BTF_RP_INTS 64

/* floats */
#define BTF_RP_OUTER 0      /* cos of the largest measured light theta */
#define BTF_RP_RELIEF 1
#define BTF_RP_BG 2         /* [3] */
#define BTF_RP_AMBIENT 5    /* the model's ambient term */
#define BTF_RP_HMIN 6       /* the height map's extremes */
#define BTF_RP_HMAX 7
#define BTF_RP_VEC 8        /* [16][3] light directions or positions */
#define BTF_RP_RGB 56       /* [16][3] intensities */
#define BTF_RP_FLOATS 112

/* floats per G-buffer pixel: object, u, v, frame[9], position[3], view[3] */
#define BTF_RP_GB 18

#endif
