/* The run driver's side of spray and granulation: the droplets move with
 * every DEM step, the granulation updates every Delta t_PBM, and at every
 * output the liquid ledger is written to spray.csv and checked: injected =
 * on particles + airborne + on walls + left (through outlets or the box,
 * as droplets or on particles), to round-off; at the end the liquid per
 * size class goes to spray_classes.csv (spray_classes.c). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem_stats.h"
#include "dem/dem_wet.h"

int gs_dem_wet_start(gs_dem_case *c, const char *dir, gs_error *err) {
  gs_dem_wet *w = c->wet;
  if (!w) return GS_OK;
  gs_dem *d = c->dem;
  int rc = GS_OK;
  snprintf(w->dir, sizeof w->dir, "%s", dir);
  if (w->has_spray) {
    if ((rc = gs_dem_spray_init(&w->spray, &w->noz, c->seed, err))) return rc;
    /* the wall bins must reach a droplet as far as a particle */
    if (w->spray.rd > d->rmax) d->rmax = w->spray.rd;
    if (!(w->f_ledger = gs_dem_table_open(dir, "spray.csv", w->path_ledger, sizeof w->path_ledger, err)))
      return err->code;
    fprintf(w->f_ledger, "time,droplets_injected,droplets_airborne,droplets_absorbed,injected,on_particles,"
                         "airborne,on_walls,left,imbalance,wetted_particles,mean_liquid_content\n");
  }
  if (w->has_gran) rc = gs_dem_granulation_start(&w->gran, d, dir, c->seed, err);
  return rc;
}

int gs_dem_wet_advance(gs_dem_case *c, long nsteps, gs_error *err) {
  gs_dem_wet *w = c->wet;
  if (!w) return gs_dem_run(c->dem, nsteps, err);
  gs_dem *d = c->dem;
  int rc = GS_OK;
  for (long s = 0; s < nsteps && !rc; s++) {
    rc = gs_dem_run(d, 1, err);
    if (!rc && w->has_spray) rc = gs_dem_spray_step(&w->spray, d, err);
    if (!rc && w->has_gran) {
      gs_dem_growth_step(&w->gran, d);
      if (d->step % w->gran.every_k == 0) rc = gs_dem_granulation_update(&w->gran, d, err);
    }
  }
  return rc;
}

int gs_dem_wet_output(gs_dem_case *c, gs_error *err) {
  gs_dem_wet *w = c->wet;
  if (!w || !w->has_spray) return GS_OK;
  gs_dem *d = c->dem;
  gs_dem_liquid_ledger l;
  gs_dem_spray_ledger(&w->spray, d, &l);
  const double imb = l.injected - (l.on_particles + l.airborne + l.on_walls + l.left);
  double wet = 0, lc = 0, np = 0;
  for (size_t i = 0; i < d->p.n; i++) {
    if (d->p.dead[i]) continue;
    const double v = d->p.vs[i] + d->p.vl[i];
    wet += d->p.vl[i] > 0;
    lc += v > 0 ? d->p.vl[i] / v : 0;
    np += 1;
  }
  fprintf(w->f_ledger, "%.9g,%ld,%zu,%ld,%.17g,%.17g,%.17g,%.17g,%.17g,%.3g,%.0f,%.9g\n", d->t,
          w->spray.injected, w->spray.n, w->spray.absorbed, l.injected, l.on_particles, l.airborne,
          l.on_walls, l.left, imb, wet, np > 0 ? lc / np : NAN);
  fflush(w->f_ledger);
  if (ferror(w->f_ledger)) return gs_error_set(err, GS_EIO, "%s: write failed", w->path_ledger);
  if (!(fabs(imb) <= w->tol * l.injected))
    return gs_error_set(err, GS_ENUMERIC,
                        "%s: spray: the liquid ledger is off by %.3g m^3 (%.3g of the %.6g m^3 injected; "
                        "spray.ledger_tolerance %g) at t = %.9g s (step %ld): liquid was created or lost",
                        c->path, imb, l.injected > 0 ? imb / l.injected : imb, l.injected, w->tol, d->t,
                        d->step);
  return GS_OK;
}

int gs_dem_wet_finish(gs_dem_case *c, gs_error *err) {
  gs_dem_wet *w = c->wet;
  if (!w) return GS_OK;
  int rc = GS_OK;
  if (w->f_ledger) {
    rc = gs_dem_table_close(w->f_ledger, w->path_ledger, err);
    w->f_ledger = NULL;
    if (!rc) rc = gs_dem_spray_classes_write(c, w->dir, err);
  }
  if (w->has_gran) {
    int r = gs_dem_granulation_finish(&w->gran, err);
    if (!rc) rc = r;
  }
  return rc;
}

void gs_dem_wet_free(gs_dem_case *c) {
  gs_dem_wet *w = c->wet;
  if (!w) return;
  if (w->f_ledger) fclose(w->f_ledger);
  gs_dem_spray_free(&w->spray);
  gs_dem_granulation_free(&w->gran);
  free(w);
  c->wet = NULL;
}
