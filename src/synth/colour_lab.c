/*
 * colour_lab.c — CIE L*a*b* for colour matching (docs/synthesis.md,
 * "Colour matching"; issue 17): the space the texture distances measure
 * first-order statistics in (measure/lab.c, through OpenCV), here in
 * plain C so that the analysis (the exemplar's quantiles) and the
 * synthesis (the output's, and the map back) convert identically on every
 * path, the GPU's output included (btf_gpu_synthesise matches on the host).
 * The constants are OpenCV's for COLOR_RGB2Lab on floats (sRGB primaries,
 * D65 white, the CIE's linear segment below (6/29)^3), so that a map made
 * here is measured in the same space; the inverse matrix is OpenCV's
 * XYZ-to-RGB. Conversions run in double; the results are rounded to float.
 */
#include "core/core.h"
#include "synth/synth.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const double RGB_TO_XYZ[3][3] = {{0.412453, 0.357580, 0.180423},
                                        {0.212671, 0.715160, 0.072169},
                                        {0.019334, 0.119193, 0.950227}};
static const double XYZ_TO_RGB[3][3] = {{3.240479, -1.53715, -0.498535},
                                        {-0.969256, 1.875991, 0.041556},
                                        {0.055648, -0.204043, 1.057311}};
static const double WHITE[3] = {0.950456, 1.0, 1.088754};
#define LAB_T0 0.008856     /* (6/29)^3: below it the CIE's linear segment */
#define LAB_SLOPE 7.787     /* (29/6)^2 / 3 */
#define LAB_F0 (16.0 / 116.0)

/* The cube root of t > 0: an estimate from the exponent bits (within a few
 * per cent), then two Halley steps (cubic convergence: to about 1e-13);
 * libm's cbrt made colour matching cost three times the synthesis. Plain
 * arithmetic, the same on every machine. */
static double cube_root(double t)
{
    uint64_t u;
    memcpy(&u, &t, sizeof u);
    u = u / 3 + 0x2a9f7893782da1ceull;
    double y;
    memcpy(&y, &u, sizeof y);
    for (int i = 0; i < 2; i++) {
        double y3 = y * y * y;
        y = y * (y3 + 2.0 * t) / (2.0 * y3 + t);
    }
    return y;
}

static double lab_f(double t)
{
    return t > LAB_T0 ? cube_root(t) : LAB_SLOPE * t + LAB_F0;
}

static double lab_f_inv(double f)
{
    return f > 0.206893 ? f * f * f : (f - LAB_F0) / LAB_SLOPE; /* 0.206893 = f(LAB_T0) */
}

/* The exposure of the texture distances (measure/lab.c): an exemplar within
 * [0, 1] is converted as it is, a brighter one scaled so that its largest
 * value is 1. Lab is not invariant to exposure (its linear segment near
 * black is not a cube root), and matching in another exposure than the one
 * measured left up to 1.29 of first-order distance where this leaves 0.9
 * (docs/fidelity.md). */
float btf_lab_scale(const btf_marginal *mg)
{
    float big = mg->rgb_hi[0];
    for (int k = 1; k < 3; k++)
        big = mg->rgb_hi[k] > big ? mg->rgb_hi[k] : big;
    return big > 1.0f ? 1.0f / big : 1.0f;
}

/* Negative light is shown as none, as the distances do (measure/lab.c);
 * values above 1 after the scale are not clipped: the scale puts the
 * exemplar's brightest channel at 1 and colour matching clamps into its box. */
void btf_lab_from_rgb(const float rgb[3], float scale, float lab[3])
{
    double c[3], xyz[3];
    for (int k = 0; k < 3; k++) {
        double v = (double)rgb[k] * scale;
        c[k] = v > 0.0 ? v : 0.0;
    }
    for (int i = 0; i < 3; i++)
        xyz[i] = (RGB_TO_XYZ[i][0] * c[0] + RGB_TO_XYZ[i][1] * c[1] + RGB_TO_XYZ[i][2] * c[2]) /
                 WHITE[i];
    double fx = lab_f(xyz[0]), fy = lab_f(xyz[1]), fz = lab_f(xyz[2]);
    lab[0] = (float)(116.0 * fy - 16.0);
    lab[1] = (float)(500.0 * (fx - fy));
    lab[2] = (float)(200.0 * (fy - fz));
}

void btf_rgb_from_lab(const float lab[3], float scale, float rgb[3])
{
    double fy = ((double)lab[0] + 16.0) / 116.0;
    double f[3] = {fy + (double)lab[1] / 500.0, fy, fy - (double)lab[2] / 200.0};
    double xyz[3];
    for (int i = 0; i < 3; i++)
        xyz[i] = lab_f_inv(f[i]) * WHITE[i];
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)((XYZ_TO_RGB[k][0] * xyz[0] + XYZ_TO_RGB[k][1] * xyz[1] +
                          XYZ_TO_RGB[k][2] * xyz[2]) / scale);
}

/* Sorts n floats (finite or not, no NaN: Lab of clamped light) by an LSD
 * radix sort on their bits made order-preserving (sign flipped, negatives
 * inverted): three passes of 11 bits, O(n), exact, where qsort's compare
 * calls made colour matching ten times slower than the synthesis it
 * follows. tmp holds n floats. */
static uint32_t float_key(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u & 0x80000000u ? ~u : u | 0x80000000u;
}

static void radix_sort(float *v, float *tmp, size_t n)
{
    float *src = v, *dst = tmp;
    for (int shift = 0; shift < 33; shift += 11) {
        size_t count[2049] = {0};
        for (size_t i = 0; i < n; i++)
            count[(float_key(src[i]) >> shift & 2047u) + 1]++;
        for (int b = 0; b < 2048; b++)
            count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++)
            dst[count[float_key(src[i]) >> shift & 2047u]++] = src[i];
        float *t = src;
        src = dst, dst = t;
    }
    if (src != v) /* three passes: the result is in tmp */
        memcpy(v, src, n * sizeof *v);
}

/* The sample: every pixel up to BTF_LAB_SAMPLE of them, else the pixels of a
 * regular grid of steps sx, sy (each the smallest that brings the count
 * within it): deterministic, spread over the whole image. */
static void sample_steps(int w, int h, int *sx, int *sy)
{
    *sx = *sy = 1;
    while ((size_t)((w + *sx - 1) / *sx) * (size_t)((h + *sy - 1) / *sy) > BTF_LAB_SAMPLE) {
        if ((w + *sx - 1) / *sx >= (h + *sy - 1) / *sy)
            (*sx)++;
        else
            (*sy)++;
    }
}

btf_status btf_lab_quantiles(const btf_image *img, float scale, float q[3][BTF_MARGIN_KNOTS],
                             btf_error *err)
{
    int sx, sy;
    sample_steps(img->width, img->height, &sx, &sy);
    size_t n = (size_t)((img->width + sx - 1) / sx) * (size_t)((img->height + sy - 1) / sy);
    float *v = btf_alloc(n * 4, sizeof(float), err); /* 3 channels, then radix scratch */
    if (!v)
        return BTF_E_NOMEM;
    size_t i = 0;
    for (int y = 0; y < img->height; y += sy)
        for (int x = 0; x < img->width; x += sx, i++) {
            float lab[3];
            btf_lab_from_rgb(img->data + 3 * ((size_t)y * img->width + x), scale, lab);
            for (int c = 0; c < 3; c++)
                v[c * n + i] = lab[c];
        }
    /* linear between order statistics at h = (n - 1) p, p = j / (knots - 1),
     * as the band quantiles of the marginal transfer (analyse/marginal_fit.c) */
    for (int c = 0; c < 3; c++) {
        float *s = v + c * n;
        radix_sort(s, v + 3 * n, n);
        for (int j = 0; j < BTF_MARGIN_KNOTS; j++) {
            double hpos = (double)(n - 1) * j / (BTF_MARGIN_KNOTS - 1);
            size_t k = (size_t)hpos;
            double f = hpos - (double)k;
            double x = k + 1 < n ? s[k] + f * ((double)s[k + 1] - s[k]) : s[n - 1];
            float lim = c == 0 ? 100.0f : 128.0f, low = c == 0 ? 0.0f : -128.0f;
            float qv = (float)x;
            qv = qv < low ? low : qv > lim ? lim : qv;
            q[c][j] = j > 0 && qv < q[c][j - 1] ? q[c][j - 1] : qv;
        }
    }
    free(v);
    return BTF_OK;
}

/* The model file keeps each Lab quantile as a 16-bit code over its
 * channel's range (docs/model-format.md, "LABQ"): steps of 0.0015 in L*
 * and 0.0039 in a*, b*, far below a just noticeable difference (about 1). */
static double lab_low(int c)
{
    return c == 0 ? 0.0 : -128.0;
}

static double lab_span(int c)
{
    return c == 0 ? 100.0 : 256.0;
}

unsigned btf_lab_code(int c, float v)
{
    double t = ((double)v - lab_low(c)) / lab_span(c) * 65535.0;
    return t <= 0.0 ? 0u : t >= 65535.0 ? 65535u : (unsigned)lround(t);
}

float btf_lab_decode(int c, unsigned code)
{
    return (float)(lab_low(c) + lab_span(c) * (double)(code > 65535u ? 65535u : code) / 65535.0);
}
