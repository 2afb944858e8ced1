/* Harness: a killed run's journal, DIR/.result.journal, as `gransim run
 * --resume` reads it (src/output/journal.c): every record checked, the
 * committed rows read back, the header checked against a small case's
 * model (src/output/journal_header.c). */
#include <stdlib.h>

#include "gransim/case.h"
#include "harness.h"
#include "output/journal.h"
#include "output/journal_header.h"

static gs_case the_case;
static int loaded;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (!loaded) {
    gs_error e = {0};
    gs_cfg *cfg = gs_cfg_load_string(
        "grid:\n  axes: [{name: v, type: geometric, min: 1e-3, max: 1, cells: 8}]\n"
        "initial: {type: cell, number: 1, index: [4]}\n"
        "mechanisms: [{type: aggregation, kernel: {type: constant, beta0: 1}}]\noutput: {end: 1}\n",
        "journal.yaml", &e);
    if (!cfg || gs_case_from_cfg(cfg, &the_case, &e)) abort();
    loaded = 1;
  }
  const char *path = fuzz_input_file(data, size, ".journal");
  if (!path) return 0;
  gs_error err = {0};
  void *head = NULL;
  size_t nhead = 0, nvals = 0;
  gs_journal *j = gs_journal_reopen(path, &head, &nhead, &nvals, &err);
  if (!j) return 0;
  const char *text, *name;
  gs_journal_header_check(head, nhead, &the_case.model, 0, path, &text, &name, &err);
  double *row = nvals < (1u << 20) ? malloc((nvals + 1) * sizeof *row) : NULL;
  for (uint64_t i = 0; row && i < gs_journal_committed(j); i++)
    if (gs_journal_read(j, i, row, &err)) break;
  free(row);
  free(head);
  gs_journal_close(j, &err);
  return 0;
}
