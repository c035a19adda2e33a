/*
 * cpu.c — the number of online CPUs, the default thread count of every stage.
 */
#include "core/core.h"

#include <unistd.h>

int btf_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}
