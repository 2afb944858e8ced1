/* One helper for every registry of named types (kernels, mechanisms,
 * integrators, selection functions, daughter distributions, stochastic
 * processes): each is a NULL-terminated array of pointers to type structs
 * whose first member is `const char *name`. */
#include <stdio.h>
#include <string.h>

#include "gransim/cfg.h"
#include "cfg/nearest.h"

static const char *name_of(const void *type) { return *(const char *const *)type; }

const void *gs_registry_find(const void *const *types, const char *name) {
  for (size_t i = 0; name && types[i]; i++)
    if (!strcmp(name_of(types[i]), name)) return types[i];
  return NULL;
}

void gs_registry_names(const void *const *types, char *buf, size_t size) {
  if (!size) return;
  buf[0] = '\0';
  for (size_t i = 0; types[i]; i++) {
    if (i) strncat(buf, ", ", size - strlen(buf) - 1);
    strncat(buf, name_of(types[i]), size - strlen(buf) - 1);
  }
}

const void *gs_registry_pick(gs_cfg_node *node, const void *const *types, const char *what,
                             gs_error *err) {
  const char *name = NULL;
  if (gs_cfg_require_kind(node, GS_CFG_MAP, err)) return NULL;
  if (gs_cfg_string_req(node, "type", &name, err)) return NULL;
  const void *found = gs_registry_find(types, name);
  if (found) return found;
  char known[512], hint[128] = "";
  gs_registry_names(types, known, sizeof known);
  size_t n = 0;
  while (types[n]) n++;
  const char *names[256];
  if (n > 256) n = 256;
  for (size_t i = 0; i < n; i++) names[i] = name_of(types[i]);
  const char *near = gs_nearest_word(name, names, n);
  if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
  gs_cfg_fail(gs_cfg_get(node, "type"), err, "unknown %s type%s; expected one of: %s", what, hint, known);
  return NULL;
}
