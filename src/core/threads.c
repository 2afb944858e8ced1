/* See gransim/threads.h. */
#include "gransim/threads.h"

#include <omp.h>

int gs_threads_for(size_t work, size_t min_work) {
  if (work < min_work || omp_in_parallel()) return 1;
  return omp_get_max_threads();
}
