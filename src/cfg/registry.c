/* Lookup of registered types by the "type" key of a case-file map. */
#include <string.h>

#include "gransim/cfg.h"

const void *gs_registry_pick(gs_cfg_node *node, const void *const *types, const char *what,
                             gs_error *err) {
  const char *name = NULL;
  if (gs_cfg_require_kind(node, GS_CFG_MAP, err)) return NULL;
  if (gs_cfg_string_req(node, "type", &name, err)) return NULL;
  for (size_t i = 0; types[i]; i++) {
    const char *const *entry_name = (const char *const *)types[i];
    if (!strcmp(*entry_name, name)) return types[i];
  }
  char known[512] = "";
  for (size_t i = 0; types[i]; i++) {
    const char *const *entry_name = (const char *const *)types[i];
    if (i) strncat(known, ", ", sizeof known - strlen(known) - 1);
    strncat(known, *entry_name, sizeof known - strlen(known) - 1);
  }
  gs_cfg_fail(gs_cfg_get(node, "type"), err, "unknown %s type; expected one of: %s", what, known);
  return NULL;
}
