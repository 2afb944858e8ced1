/* Harness: the variations of a study (gransim sweep --set KEY=V1,V2,... or
 * --range KEY=LO:HI[:log]) applied to a small case: the argument is parsed,
 * the design built (a grid, or a Latin hypercube of 2 points), and the case
 * of every run (at most 4) read from a copy of the tree with the values set,
 * as the sweep does before any run starts.  An input holding ':' is a range. */
#include <stdlib.h>
#include <string.h>

#include "gransim/cfg.h"
#include "gransim/study.h"
#include "harness.h"

static const char base_case[] =
    "grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-4, max: 1.0e4, cells: 20, zero_first: true}\n"
    "initial: {type: exponential, number: 1, mean: 1}\n"
    "mechanisms:\n  - type: aggregation\n    kernel: {type: constant, beta0: 1}\n"
    "solver: {method: rk, rtol: 1.0e-8, atol: 1.0e-14}\n"
    "output: {end: 10, count: 11}\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *arg = fuzz_input_text(data, size);
  if (!arg) return 0;
  gs_error err = {0};
  gs_cfg *base = gs_cfg_load_string(base_case, "base.yaml", &err);
  gs_study_axis axis;
  memset(&axis, 0, sizeof axis);
  gs_design d;
  memset(&d, 0, sizeof d);
  const int range = strchr(arg, ':') != NULL;
  int rc = base ? 0 : 1;
  if (!rc) rc = range ? gs_study_parse_range(arg, &axis, &err) : gs_study_parse_set(arg, &axis, &err);
  if (!rc) rc = range ? gs_design_lhs(&axis, 1, 2, 7, &d, &err) : gs_design_grid(&axis, 1, &d, &err);
  for (size_t r = 0; !rc && r < d.nruns && r < 4; r++) {
    gs_case c;
    gs_study_case(base, &d, r, &c, &err);
    gs_case_free(&c);
  }
  gs_design_free(&d);
  gs_study_axis_free(&axis);
  gs_cfg_free(base);
  free(arg);
  return 0;
}
