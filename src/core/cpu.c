/*
 * cpu.c — the number of online CPUs, the default thread count of every
 * stage, and the monotonic clock the stages' reported times come from.
 */
#include "core/core.h"

#include <time.h>
#include <unistd.h>

int btf__cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}

double btf__now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}
