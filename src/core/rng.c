/*
 * rng.c — a small deterministic random stream (splitmix64, Steele et al.
 * 2014) for seeded choices on the CPU: k-means++ seeding and restarts of
 * segmentation (Haindl & Filip 2007, section II.A). The CAR synthesis noise
 * is a separate, counter-based generator shared with the GPU.
 */
#include "core/core.h"

void btf__rng_seed(btf_rng *r, uint64_t seed)
{
    r->state = seed;
}

uint64_t btf__rng_next(btf_rng *r)
{
    uint64_t z = (r->state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double btf__rng_uniform(btf_rng *r)
{
    return (double)(btf__rng_next(r) >> 11) * 0x1.0p-53;
}
