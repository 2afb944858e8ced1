/* The generated walls of a DEM case written as STL files (dem.h,
 * gs_dem_case_write_geometry): into DIR/geometry/, where the LIGGGHTS deck
 * refers to them and a user opens them in ParaView. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "dem/dem_case.h"
#include "dem/dem_generate.h"
#include "dem/dem_internal.h"

int gs_dem_case_write_geometry(gs_dem_case *c, const char *dir, size_t *nwritten, gs_error *err) {
  size_t n = 0;
  char gdir[3900], path[4000];
  if (strlen(dir) > 3800) return gs_error_set(err, GS_EINPUT, "%s: output folder name too long", dir);
  snprintf(gdir, sizeof gdir, "%s/geometry", dir);
  for (size_t k = 0; k < c->nwall_src; k++) {
    gs_dem_wall_src *s = &c->wall_src[k];
    if (!s->generated) continue;
    if (!n && ((mkdir(dir, 0777) && errno != EEXIST) || (mkdir(gdir, 0777) && errno != EEXIST)))
      return gs_error_set(err, GS_EIO, "%s: cannot create: %s", gdir, strerror(errno));
    /* the triangles in the body frame, which is the world's at t = 0 */
    const gs_dem_mesh *m = c->dem->walls[s->wall].mesh;
    snprintf(path, sizeof path, "%.3890s/%.63s.stl", gdir, s->name);
    int rc = gs_dem_write_stl(path, s->name, m->v, m->ntri, err);
    if (rc) return rc;
    /* absolute, since LIGGGHTS runs in another folder */
    char *abs = realpath(path, NULL);
    snprintf(s->mesh, sizeof s->mesh, "%s", abs ? abs : path);
    free(abs);
    s->scale = 1;
    n++;
  }
  if (nwritten) *nwritten = n;
  return GS_OK;
}

int gs_dem_generate_walls(gs_cfg_node *walls, const char *dir, FILE *report, size_t *nwritten, gs_error *err) {
  int rc = gs_cfg_require_kind(walls, GS_CFG_SEQ, err);
  size_t n = 0;
  for (size_t k = 0; k < gs_cfg_size(walls) && !rc; k++) {
    gs_cfg_node *w = gs_cfg_item(walls, k), *gen = gs_cfg_get(w, "generate");
    const char *name;
    if (!gen) continue;
    if ((rc = gs_cfg_require_kind(w, GS_CFG_MAP, err)) || (rc = gs_cfg_string_req(w, "name", &name, err)) ||
        (rc = gs_cfg_require_kind(gen, GS_CFG_MAP, err)))
      break;
    gs_dem_tris tr = {0};
    gs_dem_gen_motion gm;
    rc = gs_dem_generate(gen, &tr, &gm, err);
    if (!rc && !n && mkdir(dir, 0777) && errno != EEXIST)
      rc = gs_error_set(err, GS_EIO, "%s: cannot create: %s", dir, strerror(errno));
    char path[4400];
    snprintf(path, sizeof path, "%.4000s/%.63s.stl", dir, name);
    if (!rc) rc = gs_dem_write_stl(path, name, tr.v, tr.ntri, err);
    if (!rc && report) {
      double vol, area, lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      gs_dem_tris_measure(tr.v, tr.ntri, &vol, &area);
      for (size_t i = 0; i < 3 * tr.ntri; i++)
        for (int a = 0; a < 3; a++) lo[a] = fmin(lo[a], tr.v[3 * i + (size_t)a]), hi[a] = fmax(hi[a], tr.v[3 * i + (size_t)a]);
      fprintf(report, "%s: %zu facets, closed, solid volume %.6g m^3, area %.6g m^2, from (%.4g, %.4g, %.4g) to "
              "(%.4g, %.4g, %.4g) m%s\n", path, tr.ntri, vol, area, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
              gm.rotating ? "; turns about z" : "");
    }
    gs_dem_tris_free(&tr);
    n += !rc;
  }
  if (nwritten) *nwritten = n;
  return rc;
}
