/*
 * rf_layout.h — where the GPU render pass of reflectance-field models
 * (gpu/rf_render.comp) finds its parameters, shared by the shader and the
 * host code (gpu/rf_render_gpu.c). The int buffer starts with RFP_INTS
 * ints of header, then the per-field code buffer and word offset, the
 * views' ring ends, a sampled model's coordinate map (paper section 6,
 * src/rf/rf_map.h: one word per surface texel, u | v << 16, row by row)
 * and the lights' kinds; the float buffer with RFP_FLOATS
 * floats of header, then the per-field, per-slot lo and scale, the views'
 * theta and phi and the lights' vectors and intensities. Plain #defines:
 * the common subset of C and GLSL.
 */
#ifndef BTF_RF_LAYOUT_H
#define BTF_RF_LAYOUT_H

/* ints */
#define RFP_MODE 0         /* RFP_MODE_TILE or RFP_MODE_SCENE */
#define RFP_FIT 1
#define RFP_LOBES 2
#define RFP_NPARAMS 3
#define RFP_SLOTS 4
#define RFP_WIDTH 5        /* the surface's texels (a sampled model's map's, else the model's) */
#define RFP_HEIGHT 6
#define RFP_NPIX 7         /* invocations that do work in this band */
#define RFP_ROW_PIX 8      /* invocations per dispatch row (gx * 64) */
#define RFP_PIX0 9         /* tile mode: the first tile texel of this band */
#define RFP_TILE_W 10      /* tile mode: texels per tile row */
#define RFP_NVIEWS 11
#define RFP_NLIGHTS 12
#define RFP_FIELD_BUF 13   /* int offset: per field, its code buffer (0..3; -1 not uploaded) */
#define RFP_FIELD_BASE 14  /* int offset: per field, its first word in that buffer */
#define RFP_RING_END 15    /* int offset: per view, the end of the ring starting there */
#define RFP_LIGHT_KIND 16  /* int offset: per light, 0 directional, 1 point */
#define RFP_LO 17          /* float offset: fields x slots lo */
#define RFP_SCALE 18       /* float offset: fields x slots (hi - lo) / 65535 */
#define RFP_THETA 19       /* float offset: per view, theta (degrees) */
#define RFP_PHI 20         /* float offset: per view, phi (degrees) */
#define RFP_LIGHT_VEC 21   /* float offset: per light, direction or position [3] */
#define RFP_LIGHT_RGB 22   /* float offset: per light, intensity [3] */
#define RFP_MAP 23         /* int offset: the coordinate map; -1 a model without one */
#define RFP_VIEW_F 24      /* tile mode: [4] the blended fields */
#define RFP_SAMPLE_W 28    /* the model's own texels (its codes'; the sample's) */
#define RFP_SAMPLE_H 29
#define RFP_INTS 32

#define RFP_MODE_TILE 0    /* the flat render: the distinct texels, one view, one light */
#define RFP_MODE_SCENE 1   /* a scene: one G-buffer pixel per invocation */

/* floats */
#define RFP_VIEW_W 0       /* tile mode: [4] the fields' weights */
#define RFP_LIGHT 4        /* tile mode: [3] the unit light */
#define RFP_VIEW 7         /* tile mode: [3] the unit view (Lafortune) */
#define RFP_INV_W 10       /* 1.0f / the surface's width */
#define RFP_INV_H 11
#define RFP_BG 12          /* scene mode: [3] background */
#define RFP_FLOATS 16

/* The code buffers bound at once (bindings 4 ..): a model whose codes
 * need more than this many of the device's largest storage buffers is
 * refused. */
#define RFP_CODE_BUFS 8

#endif
