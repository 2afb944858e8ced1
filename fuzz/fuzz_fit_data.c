/* Harness: a measured-data CSV (gransim fit --data, gransim optimise --target),
 * its column names read as sieve classes where they are. */
#include "gransim/study.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".csv");
  gs_error err = {0};
  gs_fit_data d;
  if (path && !gs_fit_data_read(path, &d, &err)) {
    for (size_t j = 0; j < d.ncols; j++) {
      double lo, hi;
      size_t comp;
      (void)gs_fit_sieve_column(d.names[j], &lo, &hi, &comp);
    }
    gs_fit_data_free(&d);
  }
  return 0;
}
