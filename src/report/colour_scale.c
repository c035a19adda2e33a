/*
 * colour_scale.c — the report's colour scale for heat maps: a viridis-like
 * path computed in OKLab (Ottosson 2020), not a copied table. Lightness
 * rises linearly with the value (0.30 to 0.93), so equal steps of value
 * look like equal steps of brightness, the order survives grey printing
 * and red-green colour blindness; the hue turns from violet through blue,
 * teal and green to yellow, as viridis does; chroma is lowered where a
 * colour would leave the sRGB gamut.
 */
#include "report/report.h"

#include <math.h>

#define SCALE_PI 3.14159265358979323846

/* OKLab to linear sRGB (the transform's published matrices). */
static void oklab_to_linear(double L, double a, double b, double rgb[3])
{
    double l = L + 0.3963377774 * a + 0.2158037573 * b;
    double m = L - 0.1055613458 * a - 0.0638541728 * b;
    double s = L - 0.0894841775 * a - 1.2914855480 * b;
    l = l * l * l, m = m * m * m, s = s * s * s;
    rgb[0] = 4.0767416621 * l - 3.3077115913 * m + 0.2309699292 * s;
    rgb[1] = -1.2684380046 * l + 2.6097574011 * m - 0.3413193965 * s;
    rgb[2] = -0.0041960863 * l - 0.7034186147 * m + 1.7076147010 * s;
}

static int in_gamut(const double rgb[3])
{
    for (int i = 0; i < 3; i++)
        if (rgb[i] < -1e-9 || rgb[i] > 1 + 1e-9)
            return 0;
    return 1;
}

static unsigned char encode_srgb(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    double e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
    return (unsigned char)lround(e * 255);
}

void btf__colour_scale(double t, unsigned char out[3])
{
    t = isnan(t) ? 0 : t < 0 ? 0 : t > 1 ? 1 : t;
    double L = 0.30 + 0.63 * t;
    double h = (310 - 205 * t) * SCALE_PI / 180;
    double C = 0.13 - 0.10 * t + 0.16 * t * t;
    double rgb[3];
    oklab_to_linear(L, C * cos(h), C * sin(h), rgb);
    if (!in_gamut(rgb)) {
        /* The largest chroma of this lightness and hue inside sRGB. */
        double lo = 0, hi = C;
        for (int i = 0; i < 40; i++) {
            double mid = 0.5 * (lo + hi);
            oklab_to_linear(L, mid * cos(h), mid * sin(h), rgb);
            if (in_gamut(rgb))
                lo = mid;
            else
                hi = mid;
        }
        oklab_to_linear(L, lo * cos(h), lo * sin(h), rgb);
    }
    for (int i = 0; i < 3; i++)
        out[i] = encode_srgb(rgb[i]);
}
