/*
 * srgb_levels.c — linear float pixels as 8-bit sRGB levels (0..255, not
 * rounded), the scale on which the report states errors and codes images
 * (docs/report-compression.md). A dataset of 8-bit sRGB files decodes each
 * code through a 256-entry table (io/image_file.c); its values are found in
 * that table exactly (a bucket index and a step or two) and give back the
 * codes, so only other values (EXR, 16-bit PNG) pay for a powf.
 */
#include "report/report.h"

#include <math.h>

void btf__srgb_levels_init(btf_srgb_levels_table *t)
{
    for (int i = 0; i < 256; i++)
        t->lut[i] = btf__srgb_to_linear((float)i / 255.0f);
    int code = 0;
    for (int k = 0; k <= 4096; k++) {
        float at = (float)k / 4096.0f;
        while (code < 255 && t->lut[code] < at)
            code++;
        t->start[k] = (unsigned char)code;
    }
}

void btf__srgb_levels(const btf_srgb_levels_table *t, const float *linear, size_t n, float *out)
{
    for (size_t i = 0; i < n; i++) {
        float v = linear[i];
        if (v >= 0.0f && v <= 1.0f) {
            /* The codes whose values can equal v start at the bucket below. */
            int k = (int)(v * 4096.0f);
            int c = t->start[k > 0 ? k - 1 : 0];
            while (c < 255 && t->lut[c] < v)
                c++;
            if (t->lut[c] == v) {
                out[i] = (float)c;
                continue;
            }
        }
        out[i] = btf__linear_to_srgb(v) * 255.0f;
    }
}
