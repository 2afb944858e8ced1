/* Harness: an STL mesh, ASCII or binary (told apart by size). */
#include "gransim/dem.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".stl");
  gs_error err = {0};
  if (path) gs_dem_mesh_free(gs_dem_mesh_read_stl(path, 1e-3, &err));
  return 0;
}
