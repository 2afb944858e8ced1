/* Harness: a CSV table over size classes, read both ways the case reader
 * does: a square kernel table (rows = classes, values >= 0, symmetric) and
 * a table of a fixed number of rows (the DEM impact table). */
#include "harness.h"
#include "kernel/class_table.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".csv");
  if (!path) return 0;
  for (size_t rows = 0; rows <= 3; rows += 3) {
    gs_error err = {0};
    gs_class_table t;
    if (!gs_class_table_read(path, rows, &t, &err)) gs_class_table_free(&t);
  }
  return 0;
}
