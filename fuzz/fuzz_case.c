/* Harness: a case file as `gransim check` reads it: the YAML tree, then the
 * reader its kind asks for: the stochastic solver's (solver.method: swa), a
 * coupled case's (a `coupling:` section, checked stage by stage), or the
 * sectional one. */
#include <stdlib.h>
#include <string.h>

#include "gransim/case.h"
#include "gransim/cfg.h"
#include "gransim/couple.h"
#include "gransim/swa.h"
#include "harness.h"

static int is_coupled(gs_cfg *cfg) {
  gs_cfg_node *root = gs_cfg_root(cfg);
  for (size_t i = 0; gs_cfg_kind_of(root) == GS_CFG_MAP && i < gs_cfg_size(root); i++)
    if (!strcmp(gs_cfg_key_at(root, i), "coupling")) return 1;
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_input_text(data, size);
  if (!text) return 0;
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(text, "fuzz.yaml", &err);
  if (cfg && gs_swa_case_wanted(cfg)) {
    gs_swa_case c;
    gs_swa_case_from_cfg(cfg, &c, &err); /* takes cfg over */
    gs_swa_case_free(&c);
  } else if (cfg && is_coupled(cfg)) {
    gs_cfg_free(cfg);
    const char *path = fuzz_input_file(data, size, ".yaml");
    char desc[1024];
    if (path) gs_couple_check(path, desc, sizeof desc, &err);
  } else if (cfg) {
    gs_case c;
    gs_case_from_cfg(cfg, &c, &err); /* takes cfg over */
    gs_case_free(&c);
  }
  free(text);
  return 0;
}
