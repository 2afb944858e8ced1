/* The case fragment `gransim compartments` writes (compartments, rates,
 * velocity, hold-ups), opened for the mechanisms and kernels that read it:
 * the exchange mechanism takes its `rates`, the semi_mechanistic kernel its
 * `velocity`.  One loader, so that both resolve the name and check the
 * compartment count alike. */
#include <stdio.h>

#include "gransim/cfg.h"

gs_cfg *gs_cfg_fragment_load(gs_cfg_node *fn, const char *dir, size_t ncomp, gs_error *err) {
  const char *name = gs_cfg_scalar(fn);
  if (!name || !*name) {
    gs_cfg_fail(fn, err, "expected a file name (a fragment of gransim compartments)");
    return NULL;
  }
  char path[4096];
  snprintf(path, sizeof path, "%s%s%s", name[0] == '/' ? "" : dir, name[0] == '/' ? "" : "/", name);
  gs_cfg *cfg = gs_cfg_load_file(path, err);
  if (!cfg) { /* say which line named it: the loader speaks of a case file */
    gs_error_prefix(err, "%s:%d: %s: fragment: ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn));
    return NULL;
  }
  gs_cfg_node *root = gs_cfg_root(cfg);
  long n = 0;
  int rc = root ? gs_cfg_require_kind(root, GS_CFG_MAP, err) : gs_cfg_fail(fn, err, "%s is empty", path);
  if (!rc) rc = gs_cfg_long_range(root, "compartments", 1, 1, 1, 1000000, &n, err);
  if (!rc && (size_t)n != ncomp)
    rc = gs_cfg_fail(fn, err, "%s has %ld compartments, the grid %zu (set grid.compartments: %ld)", path, n,
                     ncomp, n);
  if (rc) {
    gs_cfg_free(cfg);
    return NULL;
  }
  return cfg;
}
