/*
 * rf_map.h — the one indirection of a sampled reflectance-field model
 * (Meseth, Müller & Klein 2003, section 6: "Tong's algorithm does not copy
 * texton values from the example to the new texture but instead stores
 * texture coordinates referencing the example texture. This indirection
 * necessitates an additional dependent texture lookup during rendering"):
 * a surface texel to the sample texel whose coefficients it shows. Every
 * evaluation path (rf_eval.c, rf_render.c, rf_scene.c, rf_error.c) takes
 * its texel from here, so that none of them reads a sampled model's codes
 * as if they covered the surface. A model without a map is its own
 * surface. Private to the library (and the tests).
 */
#ifndef BTF_RF_MAP_H
#define BTF_RF_MAP_H

#include "btfcar.h"

#include <stddef.h>
#include <stdint.h>

/* The surface's sides (btf_rf_surface_size without the call). */
static inline int rf_surface_w(const btf_rf_model *m)
{
    return m->map ? m->surface_width : m->width;
}
static inline int rf_surface_h(const btf_rf_model *m)
{
    return m->map ? m->surface_height : m->height;
}

/* c wrapped into [0, n). */
static inline int rf_wrap(int c, int n)
{
    c %= n;
    return c < 0 ? c + n : c;
}

/* The index (y * width + x) of the sample texel that surface texel (x, y)
 * shows; x and y within the surface. A map entry out of the sample (a
 * model not made by the library or the decoder, which check it) is clamped
 * into it rather than read past the codes. */
static inline size_t rf_surface_texel(const btf_rf_model *m, int x, int y)
{
    if (!m->map)
        return (size_t)y * (size_t)m->width + (size_t)x;
    const uint16_t *c = m->map + 2 * ((size_t)y * (size_t)m->surface_width + (size_t)x);
    size_t u = c[0] < m->width ? c[0] : (size_t)m->width - 1;
    size_t v = c[1] < m->height ? c[1] : (size_t)m->height - 1;
    return v * (size_t)m->width + u;
}

#endif
