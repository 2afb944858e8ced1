/* Harness: a DEM case file as `gransim dem` reads it (geometry, materials,
 * insertion, outputs; an STL it names is read relative to the file). */
#include "gransim/dem.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".yaml");
  gs_error err = {0};
  if (path) gs_dem_case_free(gs_dem_case_load(path, &err));
  return 0;
}
