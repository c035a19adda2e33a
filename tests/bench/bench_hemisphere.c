/*
 * bench_hemisphere.c -- lookups per second of btf__hemisphere_lookup
 * (src/render/btf__hemisphere_lookup.h) on one core, for ubo81 and ubo151:
 * random upper-hemisphere directions (about a third beyond the outer ring,
 * where the hull rule runs) and a 1024^2 frame's worth of near-normal
 * ones. The renderer needs 2 lookups per pixel per light: 1024^2 at 10 fps
 * is 21 million a second over its threads. Median of 5 runs; figures only.
 */
#include "testutil.h"
#include "core/core.h"
#include "render/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N (1 << 20)
#define RUNS 5

static volatile float sink;

static double run(const btf_hemisphere *h, const float *v)
{
    float acc = 0.0f;
    double t0 = tu_now();
    for (int i = 0; i < N; i++) {
        int idx[3];
        float w[3];
        btf__hemisphere_lookup(h, v + 3 * i, idx, w);
        acc += w[0] + (float)idx[1];
    }
    double t = tu_now() - t0;
    sink = acc;
    return N / t;
}

int main(void)
{
    float *v = malloc(sizeof(float) * 3 * N);
    if (!v)
        return 1;
    srand(7);
    for (int which = 0; which < 2; which++) {
        btf_dirset s;
        btf_error e = {0};
        btf_hemisphere *h;
        if ((which == 0 ? btf_dirset_ubo81(&s, &e) : btf__dirset_ubo151(&s, &e)) != 0 ||
            btf_hemisphere_build(&s, &h, &e) != 0) {
            fprintf(stderr, "bench_hemisphere: %s\n", e.msg);
            return 1;
        }
        for (int cone = 0; cone < 2; cone++) {
            for (int i = 0; i < N; i++) {
                /* cone 0: uniform over the hemisphere; 1: within 40 degrees. */
                double z = cone ? 1.0 - (1.0 - cos(40.0 * M_PI / 180.0)) * rand() / RAND_MAX
                                : (double)rand() / RAND_MAX;
                double p = 2.0 * M_PI * rand() / RAND_MAX, r = sqrt(fmax(0.0, 1.0 - z * z));
                v[3 * i] = (float)(r * cos(p));
                v[3 * i + 1] = (float)(r * sin(p));
                v[3 * i + 2] = (float)z;
            }
            double rate[RUNS];
            for (int k = 0; k < RUNS; k++)
                rate[k] = run(h, v);
            double m = tu_median(rate, RUNS);
            printf("hemisphere lookup, %s, %s: %.1f M lookups/s on one core "
                   "(%.1f ms for the 2 x 1024^2 of one frame and light)\n",
                   s.name, cone ? "within 40 deg of the normal" : "uniform over the hemisphere",
                   m * 1e-6, 2.0 * 1048576.0 / m * 1e3);
        }
        btf_hemisphere_free(h);
        btf_dirset_free(&s);
    }
    free(v);
    return 0;
}
