/* Harness: a batches file (gransim fit --batches): sieves and batches with
 * their key overrides; the data files it names are read where they exist. */
#include "gransim/study.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".yaml");
  gs_error err = {0};
  gs_fit_batches bs;
  if (path && !gs_fit_batches_read(path, &bs, &err)) gs_fit_batches_free(&bs);
  return 0;
}
