/*
 * rf_quant.c — how a reflectance-field model keeps its parameters: every
 * slot of every texel as a 16-bit code over the range that slot spans in
 * its field (a measured view; Meseth, Müller & Klein 2003, section 5.2,
 * keep each lobe parameter as a texture slice per view, here with a scale
 * and an offset per slice): v = lo + code (hi - lo) / 65535, so a value is
 * kept within (hi - lo) / 131070 of the fitted one. The chromaticity
 * factors are the texel's average colour over its images divided by their
 * average luminance (section 4.2, "the final color is computed as in [15]").
 */
#include "rf/rf.h"

void rf_quantise_field(const float *vals, size_t texels, int slots, float *lo, float *hi,
                       uint16_t *codes)
{
    for (int s = 0; s < slots; s++) {
        float a = vals[s], b = vals[s];
        for (size_t t = 1; t < texels; t++) {
            float v = vals[t * slots + s];
            a = v < a ? v : a;
            b = v > b ? v : b;
        }
        lo[s] = a, hi[s] = b;
        for (size_t t = 0; t < texels; t++)
            codes[t * slots + s] = rf_quantise(vals[t * slots + s], a, b);
    }
}

void rf_chroma(double r, double g, double b, float out[3])
{
    double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    if (!(y > 1e-12) || !isfinite(y)) {
        out[0] = out[1] = out[2] = 1.0f;
        return;
    }
    double c[3] = {r / y, g / y, b / y};
    for (int i = 0; i < 3; i++)
        out[i] = (float)rf_clampd(isfinite(c[i]) ? c[i] : 1.0, 0.0, 64.0);
}
