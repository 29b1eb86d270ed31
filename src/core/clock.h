/* The monotonic wall clock every timing in the project reads: accel builds, render
 * progress and time limits, SPPM's time limit, the ray benchmark, the CLI's load time. */
#ifndef CST_CORE_CLOCK_H
#define CST_CORE_CLOCK_H

#include <time.h>

/* Seconds since an arbitrary fixed point (CLOCK_MONOTONIC): only differences mean anything. */
static inline double clock_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
