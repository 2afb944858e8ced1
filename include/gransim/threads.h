/* gransim — when a loop is worth an OpenMP team.
 *
 * Entering a parallel region costs about 2.4 µs on the project's VM even
 * with one thread (libgomp builds a team and wakes a futex at its end; an
 * `if (0)` clause does not avoid it), more than a 16 x 16 compartment's
 * transfer or spray takes.  The seed-000 example entered 6.8 regions per
 * right-hand side, 19 % of its run.  Loops therefore ask here first and run
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
