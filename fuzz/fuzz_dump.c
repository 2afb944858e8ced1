/* Harness: a LIGGGHTS/LAMMPS text dump (the reader of gransim dem-reduce). */
#include "demdata/dump.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".atom");
  gs_error err = {0};
  gs_dump d;
  if (path && !gs_dump_read(path, &d, &err)) gs_dump_free(&d);
  return 0;
}
