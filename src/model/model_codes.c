/*
 * model_codes.c — the quantised values the model file keeps
 * (docs/model-format.md): each Lab quantile as a 16-bit code ("LABQ") and
 * each pair gain as a signed byte ("GAIN"), the albedo pattern's and the
 * periodic cells' factors as one byte ("STRC", "CELL"). The analysis rounds what it
 * fits through the same codes, so the model in memory is the one the file
 * gives back; they live with the model, below both the analysis and the
 * synthesis that use them.
 */
#include "model/model.h"

#include <math.h>

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

unsigned btf__lab_code(int c, float v)
{
    double t = ((double)v - lab_low(c)) / lab_span(c) * 65535.0;
    return t <= 0.0 ? 0u : t >= 65535.0 ? 65535u : (unsigned)lround(t);
}

float btf__lab_decode(int c, unsigned code)
{
    return (float)(lab_low(c) + lab_span(c) * (double)(code > 65535u ? 65535u : code) / 65535.0);
}

/* Gains are kept as log2 on a grid of 1/64 octave over [-2, 2): 1.1 %
 * steps, one signed byte a channel (docs/model-format.md, "GAIN"). A
 * pair more than four times off its subspace is held there. */
#define GAIN_STEPS_PER_OCTAVE 64.0
int btf__gain_code(float g)
{
    double l = log2(g > 0.0f && isfinite(g) ? (double)g : 1.0);
    double q = floor(l * GAIN_STEPS_PER_OCTAVE + 0.5);
    return q < -128.0 ? -128 : q > 127.0 ? 127 : (int)q;
}

float btf__gain_value(int q)
{
    return (float)exp2((double)q / GAIN_STEPS_PER_OCTAVE);
}

/* The albedo pattern is kept on a log2 grid of 1/32 over [-4, 4]: 2.2 %
 * steps, one byte a texel (docs/model-format.md, "STRC"). */
#define ALBEDO_LOG_MIN (-4.0)
#define ALBEDO_STEPS_PER_OCTAVE 32.0
unsigned btf__albedo_code(float a)
{
    double l = log2(a > 0.0f && isfinite(a) ? (double)a : 1.0);
    double q = floor((l - ALBEDO_LOG_MIN) * ALBEDO_STEPS_PER_OCTAVE + 0.5);
    return q < 0.0 ? 0u : q > 255.0 ? 255u : (unsigned)q;
}

float btf__albedo_value(unsigned q)
{
    return (float)exp2((double)q / ALBEDO_STEPS_PER_OCTAVE + ALBEDO_LOG_MIN);
}
