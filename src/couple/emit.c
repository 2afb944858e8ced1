/* The DEM stage's case file: the `dem:` section of a coupled case written
 * out as a `gransim dem` case (the embedded DEM reads its cases from files),
 * with the classes derived from the grid and the duration, sampling and
 * steady-state settings of `coupling.steady`.  Scalars are written
 * double-quoted (the reader takes a scalar's text whatever its style), in
 * flow style, one top-level key per line; mesh paths are made absolute,
 * since the file lives in the output folder. */
#include <math.h>
#include <string.h>

#include "couple/couple_internal.h"
#include "gransim/dem.h"

static void put_scalar(FILE *fp, const char *t) {
  fputc('"', fp);
  for (; *t; t++) {
    if (*t == '"' || *t == '\\') fprintf(fp, "\\%c", *t);
    else if (*t == '\n') fputs("\\n", fp);
    else fputc(*t, fp);
  }
  fputc('"', fp);
}

static void put_node(FILE *fp, gs_cfg_node *n, const char *dir) {
  if (gs_cfg_kind_of(n) == GS_CFG_MAP) {
    fputc('{', fp);
    for (size_t i = 0; i < gs_cfg_size(n); i++) {
      const char *key = gs_cfg_key_at(n, i);
      gs_cfg_node *v = gs_cfg_value_at(n, i);
      fprintf(fp, "%s%s: ", i ? ", " : "", key);
      const char *t = gs_cfg_scalar(v);
      if (!strcmp(key, "mesh") && t && t[0] != '/') {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", dir, t);
        put_scalar(fp, path);
      } else put_node(fp, v, dir);
    }
    fputc('}', fp);
  } else if (gs_cfg_kind_of(n) == GS_CFG_SEQ) {
    fputc('[', fp);
    for (size_t i = 0; i < gs_cfg_size(n); i++) {
      if (i) fputs(", ", fp);
      put_node(fp, gs_cfg_item(n, i), dir);
    }
    fputc(']', fp);
  } else put_scalar(fp, gs_cfg_scalar(n) ? gs_cfg_scalar(n) : "");
}

/* A map's keys except those the coupling sets, which are errors there. */
static int put_map_except(FILE *fp, gs_cfg_node *m, const char *dir, const char *const *taken,
                          const char *by, int *first, gs_error *err) {
  if (gs_cfg_require_kind(m, GS_CFG_MAP, err)) return GS_EINPUT;
  for (size_t i = 0; i < gs_cfg_size(m); i++) {
    const char *key = gs_cfg_key_at(m, i);
    gs_cfg_node *v = gs_cfg_value_at(m, i);
    for (const char *const *t = taken; *t; t++)
      if (!strcmp(key, *t))
        return gs_cfg_fail(v, err, "set by the coupling (%s) in a coupled case; remove it", by);
    fprintf(fp, "%s%s: ", *first ? "" : ", ", key);
    put_node(fp, v, dir);
    *first = 0;
  }
  return GS_OK;
}

int gs_couple_write_dem_case(FILE *fp, gs_cfg_node *root, const char *dir, const gs_couple_settings *s,
                             const gs_couple_classes *cl, const double *fractions, gs_error *err) {
  if (gs_cfg_require_kind(root, GS_CFG_MAP, err)) return GS_EINPUT;
  int rc = GS_OK, have_dem = 0, have_stats = 0, have_out = 0;
  char q[96]; /* the detector's quantities (coupling.steady.quantities) */
  gs_dem_steady_quantities_join(s->quantities, ", ", q, sizeof q);
  fprintf(fp, "# written by gransim couple: the dem section with the classes derived from the PBM grid\n");
  for (size_t i = 0; i < gs_cfg_size(root) && !rc; i++) {
    const char *key = gs_cfg_key_at(root, i);
    gs_cfg_node *v = gs_cfg_value_at(root, i);
    int first = 1;
    if (!strcmp(key, "classes"))
      return gs_cfg_fail(v, err, "the DEM classes of a coupled case come from the PBM grid "
                         "(coupling.classes); remove this list");
    if (!strcmp(key, "dem")) {
      /* system scaling rescales the geometry every cycle (dem.geometry_scale) */
      static const char *const taken[] = {"duration", NULL};
      gs_cfg_node *own = s->scale_n && gs_cfg_kind_of(v) == GS_CFG_MAP ? gs_cfg_get(v, "geometry_scale") : NULL;
      if (own)
        return gs_cfg_fail(own, err, "set by the coupling in a coupled case with scaling (coupling.scaling rescales "
                           "the geometry every cycle); remove it");
      fputs("dem: {", fp);
      rc = put_map_except(fp, v, dir, taken, "coupling.steady.max_time", &first, err);
      fprintf(fp, "%sduration: %.17g", first ? "" : ", ", s->max_time);
      if (s->scale_n) fprintf(fp, ", geometry_scale: %.17g", s->geom_now);
      fputs("}\n", fp);
      have_dem = 1;
    } else if (!strcmp(key, "statistics")) {
      static const char *const taken[] = {"start", "sample_every", "steady", NULL};
      fputs("statistics: {", fp);
      rc = put_map_except(fp, v, dir, taken, "coupling.steady", &first, err);
      fprintf(fp, "%sstart: steady, sample_every: %.17g, steady: {window: %ld, tolerance: %.17g, quantities: [%s]}}\n",
              first ? "" : ", ", s->sample_every, s->window, s->tolerance, q);
      have_stats = 1;
    } else if (!strcmp(key, "output")) {
      static const char *const taken[] = {"every", NULL};
      fputs("output: {", fp);
      rc = put_map_except(fp, v, dir, taken, "coupling.steady.sample_every", &first, err);
      fprintf(fp, "%severy: %.17g}\n", first ? "" : ", ", s->sample_every);
      have_out = 1;
    } else if (!strcmp(key, "materials") && !isnan(s->e_now) && gs_cfg_kind_of(v) == GS_CFG_SEQ) {
      /* the coupling's material takes the population's restitution (two-way) */
      fputs("materials: [", fp);
      for (size_t m = 0; m < gs_cfg_size(v); m++) {
        gs_cfg_node *mat = gs_cfg_item(v, m);
        const char *name = gs_cfg_kind_of(mat) == GS_CFG_MAP ? gs_cfg_scalar(gs_cfg_get(mat, "name")) : NULL;
        if (m) fputs(", ", fp);
        if (!name || strcmp(name, s->material)) {
          put_node(fp, mat, dir);
          continue;
        }
        fputc('{', fp);
        for (size_t i2 = 0; i2 < gs_cfg_size(mat); i2++)
          if (strcmp(gs_cfg_key_at(mat, i2), "e")) {
            fprintf(fp, "%s: ", gs_cfg_key_at(mat, i2));
            put_node(fp, gs_cfg_value_at(mat, i2), dir);
            fputs(", ", fp);
          }
        fprintf(fp, "e: %.17g}", s->e_now);
      }
      fputs("]\n", fp);
    } else if ((!strcmp(key, "fill") || !strcmp(key, "feed")) && (fractions || s->scale_n)) {
      static const char *const taken_all[] = {"count", "mass", "fractions", "fractions_by", NULL};
      /* the population sets the fractions, system scaling the count */
      static const char *const taken_count[] = {"count", "mass", NULL};
      const char *const *taken = !fractions ? taken_count : taken_all + (s->scale_n ? 0 : 2);
      if (gs_cfg_require_kind(v, GS_CFG_SEQ, err)) return GS_EINPUT;
      /* system scaling fixes the DEM's particle count: one fill holds them all */
      if (s->scale_n && (!strcmp(key, "feed") || gs_cfg_size(v) != 1))
        return gs_cfg_fail(v, err, "coupling.scaling keeps the DEM at scaling.particles = %ld particles: expected one "
                           "`fill` and no `feed` (this %s has %zu entries)", s->scale_n, key, gs_cfg_size(v));
      fprintf(fp, "%s: [", key);
      for (size_t f = 0; f < gs_cfg_size(v) && !rc; f++) {
        first = 1;
        fputs(f ? ", {" : "{", fp);
        rc = put_map_except(fp, gs_cfg_item(v, f), dir, taken,
                            s->scale_n ? "the PBM population and coupling.scaling" : "the PBM population, coupling.mode two_way",
                            &first, err);
        if (s->scale_n) {
          fprintf(fp, "%scount: %ld", first ? "" : ", ", s->scale_n);
          first = 0;
        }
        if (fractions) {
          fprintf(fp, "%sfractions_by: number, fractions: [", first ? "" : ", ");
          for (size_t c = 0; c < cl->n; c++) fprintf(fp, "%s%.17g", c ? ", " : "", fractions[c]);
          fputc(']', fp);
        }
        fputc('}', fp);
      }
      fputs("]\n", fp);
    } else {
      fprintf(fp, "%s: ", key);
      put_node(fp, v, dir);
      fputc('\n', fp);
    }
  }
  if (rc) return rc;
  if (!have_dem) return gs_cfg_fail(root, err, "missing key 'dem' (time_step, box, ...) in the DEM case");
  if (!have_stats)
    fprintf(fp, "statistics: {start: steady, sample_every: %.17g, steady: {window: %ld, tolerance: %.17g, "
            "quantities: [%s]}}\n", s->sample_every, s->window, s->tolerance, q);
  /* one output row per sample, so that the time series holds the detector's samples */
  if (!have_out) fprintf(fp, "output: {every: %.17g}\n", s->sample_every);
  fputs("classes:\n", fp);
  for (size_t k = 0; k < cl->n; k++)
    fprintf(fp, "  - {name: c%zu, radius: [%.17g, %.17g], material: \"%s\"}\n", k + 1, cl->edges[k] / 2,
            cl->edges[k + 1] / 2, s->material);
  return ferror(fp) ? gs_error_set(err, GS_EIO, "cannot write the DEM case") : GS_OK;
}
