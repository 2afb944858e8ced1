/* Harness: a killed sweep's journal, DIR/runs.csv, as `gransim sweep
 * --resume` reads it (src/study/sweep_journal.c), for a sweep of 3 runs over
 * one key. */
#include <stdlib.h>

#include "harness.h"
#include "study/study_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static gs_design d;
  static int ready;
  if (!ready) {
    gs_error e = {0};
    gs_study_axis ax;
    if (gs_study_parse_set("output.end=1,2,3", &ax, &e) || gs_design_grid(&ax, 1, &d, &e)) abort();
    gs_study_axis_free(&ax);
    ready = 1;
  }
  const char *path = fuzz_input_file(data, size, ".csv");
  if (!path) return 0;
  gs_error err = {0};
  char *row[3] = {0};
  size_t done = 0;
  gs_sweep_journal_read(path, "run,status,output.end,M0,error\n", &d, row, &done, &err);
  for (int r = 0; r < 3; r++) free(row[r]);
  return 0;
}
