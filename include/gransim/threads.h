/* gransim — when a loop is worth an OpenMP team.
 *
 * Entering a parallel region has a fixed cost even with one thread (libgomp
 * builds a team and wakes a futex at its end; an `if (0)` clause does not
 * avoid it), and it can exceed the work of a small loop such as a 16 x 16
 * compartment's transfer or spray (measured in docs/performance.md, "OpenMP
 * regions that were not needed").  Loops therefore ask here first and run
 * plain C when the answer is 1. */
#ifndef GRANSIM_THREADS_H
#define GRANSIM_THREADS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Threads a loop of `work` units should use: 1 when OpenMP offers one
 * thread, when called from inside a parallel region, or when work <
 * min_work; otherwise the team size OpenMP would use. */
int gs_threads_for(size_t work, size_t min_work);

#ifdef __cplusplus
}
#endif
#endif
