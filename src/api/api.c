/* One entry point for every kind of case: see include/gransim/api.h. */
#include "gransim/api.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gransim/case.h"
#include "gransim/cfg.h"
#include "gransim/couple.h"
#include "gransim/distribution.h"
#include "gransim/dem.h"
#include "gransim/liggghts.h"
#include "gransim/run.h"
#include "gransim/swa.h"

/* The file as loaded and the keys set since, in order: every check or run
 * reads a fresh copy with the keys set again, because reading a case marks
 * the keys it used and takes over its tree. */
struct gs_api_case {
  gs_cfg *base;
  char *path; /* the file, NULL for text */
  char **keys, **values;
  size_t nset;
};

static gs_api_case *wrap(gs_cfg *cfg, const char *path, gs_error *err) {
  if (!cfg) return NULL;
  gs_api_case *c = gs_calloc(1, sizeof *c, err);
  if (c && path && !(c->path = strdup(path))) {
    gs_error_set(err, GS_ENOMEM, "out of memory");
    free(c);
    c = NULL;
  }
  if (!c) {
    gs_cfg_free(cfg);
    return NULL;
  }
  c->base = cfg;
  return c;
}

gs_api_case *gs_api_case_load(const char *path, gs_error *err) {
  return wrap(gs_cfg_load_file(path, err), path, err);
}

gs_api_case *gs_api_case_from_text(const char *text, const char *name, gs_error *err) {
  return wrap(gs_cfg_load_string(text, name ? name : "<text>", err), NULL, err);
}

void gs_api_case_free(gs_api_case *c) {
  if (!c) return;
  gs_cfg_free(c->base);
  for (size_t i = 0; i < c->nset; i++) free(c->keys[i]), free(c->values[i]);
  free(c->keys);
  free(c->values);
  free(c->path);
  free(c);
}

int gs_api_case_set(gs_api_case *c, const char *dotted, const char *value, gs_error *err) {
  int rc = gs_cfg_set(c->base, dotted, value, err);
  if (rc) return rc;
  char **k = realloc(c->keys, (c->nset + 1) * sizeof *k);
  if (k) c->keys = k;
  char **v = realloc(c->values, (c->nset + 1) * sizeof *v);
  if (v) c->values = v;
  if (!k || !v || !(c->keys[c->nset] = strdup(dotted))) return gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!(c->values[c->nset] = strdup(value))) {
    free(c->keys[c->nset]);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  c->nset++;
  return GS_OK;
}

/* A top-level key, looked at without marking it used. */
static int has_top(gs_cfg *cfg, const char *key) {
  gs_cfg_node *root = gs_cfg_root(cfg);
  for (size_t i = 0; gs_cfg_kind_of(root) == GS_CFG_MAP && i < gs_cfg_size(root); i++)
    if (!strcmp(gs_cfg_key_at(root, i), key)) return 1;
  return 0;
}

gs_api_kind gs_api_kind_of_cfg(gs_cfg *cfg) {
  if (has_top(cfg, "coupling")) return GS_API_COUPLED;
  if (has_top(cfg, "dem") && !has_top(cfg, "grid")) return GS_API_DEM;
  return gs_swa_case_wanted(cfg) ? GS_API_SWA : GS_API_SECTIONAL;
}

gs_api_kind gs_api_case_kind(const gs_api_case *c) { return gs_api_kind_of_cfg(c->base); }

const char *gs_api_kind_name(gs_api_kind kind) {
  static const char *const names[] = {"sectional", "swa", "dem", "coupled"};
  return (unsigned)kind < sizeof names / sizeof *names ? names[kind] : "unknown";
}

static gs_cfg *fresh(const gs_api_case *c, gs_error *err) {
  gs_cfg *cfg = gs_cfg_copy(c->base, err);
  for (size_t i = 0; cfg && i < c->nset; i++)
    if (gs_cfg_set(cfg, c->keys[i], c->values[i], err)) {
      gs_cfg_free(cfg);
      cfg = NULL;
    }
  return cfg;
}

/* A coupled case is read stage by stage from its file (src/couple). */
static int coupled_path(const gs_api_case *c, gs_error *err) {
  if (!c->path)
    return gs_error_set(err, GS_EINPUT, "%s: a coupled case is read from its file: load it from a file",
                        gs_cfg_name(c->base));
  if (c->nset)
    return gs_error_set(err, GS_EINPUT, "%s: keys of a coupled case cannot be changed in memory (%s): edit "
                        "a copy of the file", c->path, c->keys[0]);
  return GS_OK;
}

int gs_api_case_check(const gs_api_case *c, char *desc, size_t n, gs_error *err) {
  gs_api_kind kind = gs_api_kind_of_cfg(c->base);
  if (kind == GS_API_COUPLED) {
    int rc = coupled_path(c, err);
    return rc ? rc : gs_couple_check(c->path, desc, n, err);
  }
  gs_cfg *cfg = fresh(c, err);
  if (!cfg) return err->code;
  int rc = 0;
  if (kind == GS_API_DEM) {
    gs_dem_case *d = gs_dem_case_from_cfg(cfg, err);
    if (!d) return err->code;
    const int liggghts = gs_dem_case_engine(d) == 1;
    char what[512];
    gs_dem_case_describe(d, what, sizeof what);
    /* (a refusal names the file and line of the key) */
    if (!liggghts || !(rc = gs_lig_check(d, err))) snprintf(desc, n, "DEM case%s: %s", liggghts ? " (engine liggghts)" : "", what);
    gs_dem_case_free(d);
  } else if (kind == GS_API_SWA) {
    gs_swa_case s;
    if (!(rc = gs_swa_case_from_cfg(cfg, &s, err)))
      snprintf(desc, n, "swa solver, %d coordinates, %zu compartments, %zu mechanisms, %zu runs of %zu "
               "particles, %zu output times from %g to %g", s.model.ncoord, s.model.ncomp, s.model.nproc, s.runs,
               s.model.nmax, s.ntimes, s.times[0], s.times[s.ntimes - 1]);
    for (size_t i = 0; !rc && i < s.ndisc; i++) {
      char line[2048];
      size_t used = strlen(desc);
      gs_swa_disc_format(&s, &s.disc[i], line, sizeof line);
      if (used + 1 < n) snprintf(desc + used, n - used, "\n  discretisation: %s", line);
    }
    gs_swa_case_free(&s);
  } else {
    gs_case s;
    memset(&s, 0, sizeof s);
    if (!(rc = gs_case_from_cfg(cfg, &s, err))) {
      const gs_grid *g = &s.model.grid;
      snprintf(desc, n, "%d axes, %zu cells x %zu compartments, %zu mechanisms, %zu output times from %g to "
               "%g, integrator %s", g->dim, g->ncells, g->ncomp, s.model.nmech, s.ntimes, s.times[0],
               s.times[s.ntimes - 1], s.integrator.type->name);
      /* How the grid holds each distribution of the case (distribution.h). */
      for (size_t i = 0; s.model.disc && i < s.model.disc->n; i++) {
        size_t used = strlen(desc);
        char line[1024];
        gs_disc_format(&s.model.disc->r[i], g, s.model.disc->tolerance, line, sizeof line);
        if (used + 1 < n) snprintf(desc + used, n - used, "\n  discretisation: %s", line);
      }
    }
    gs_case_free(&s);
  }
  return rc;
}

int gs_api_case_run(const gs_api_case *c, const char *out_dir, int progress, gs_error *err) {
  if (progress < 0) progress = isatty(2);
  gs_api_kind kind = gs_api_kind_of_cfg(c->base);
  if (kind == GS_API_COUPLED) {
    gs_couple_options opt = {.out_dir = out_dir, .progress = progress};
    int rc = coupled_path(c, err);
    return rc ? rc : gs_couple_run(c->path, &opt, err);
  }
  gs_cfg *cfg = fresh(c, err);
  if (!cfg) return err->code;
  int rc = 0;
  if (kind == GS_API_DEM) {
    gs_dem_case *d = gs_dem_case_from_cfg(cfg, err);
    if (!d) return err->code;
    gs_lig_options lig = {.progress = progress};
    if (gs_dem_case_engine(d) != 1) rc = gs_dem_case_run(d, out_dir, progress, err);
    else if (!(rc = gs_lig_check(d, err))) rc = gs_lig_case_run(d, out_dir, &lig, err);
    gs_dem_case_free(d);
  } else if (kind == GS_API_SWA) {
    gs_swa_case s;
    gs_swa_report rep = {0};
    rc = gs_swa_case_from_cfg(cfg, &s, err);
    if (!rc) rc = gs_swa_case_run(&s, out_dir, progress, NULL, NULL, &rep, err);
    gs_swa_report_free(&rep);
    gs_swa_case_free(&s);
  } else {
    gs_case s;
    memset(&s, 0, sizeof s);
    gs_run_options opt = {.out_dir = out_dir, .progress = progress, .one_process = 1};
    gs_run_report rep;
    rc = gs_case_from_cfg(cfg, &s, err);
    if (!rc) rc = gs_case_run(&s, &opt, NULL, &rep, err);
    gs_case_free(&s);
  }
  return rc;
}
