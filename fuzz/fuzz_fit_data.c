/* Harness: a measured-data CSV (gransim fit --data, gransim optimise --target). */
#include "gransim/study.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".csv");
  gs_error err = {0};
  gs_fit_data d;
  if (path && !gs_fit_data_read(path, &d, &err)) gs_fit_data_free(&d);
  return 0;
}
