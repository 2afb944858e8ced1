/* The health of a DEM run (dem_case.h): the driver's checks that stop a run
 * which has stopped meaning anything.  Particles that overlap by a large
 * share of their radius are outside what a Hertz contact describes (a time
 * step too large for the stiffness, or particles too soft for the load, and
 * then they pass through each other and the walls); particles that leave
 * the box other than through an outlet escaped through a hole or were shot
 * out by such overlaps; a non-finite position poisons every table.  Each is
 * reported with the step, the time, the particle ids and the figure. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dem/dem_case.h"
#include "dem/dem_internal.h"
#include "dem/dem_wet.h"

void gs_dem_health_init(gs_dem_health *h, const gs_dem_case *c) {
  h->inserted = 0;
  h->lost0 = c->dem->lost;
}

/* The first particle whose position or velocity is not finite, or -1. */
static long first_non_finite(const gs_dem_particles *p) {
  for (size_t i = 0; i < p->n; i++)
    if (!isfinite(p->x[i] + p->y[i] + p->z[i] + p->vx[i] + p->vy[i] + p->vz[i])) return (long)i;
  return -1;
}

static int non_finite_error(const gs_dem *d, long i, gs_error *err) {
  const gs_dem_particles *p = &d->p;
  return gs_error_set(err, GS_ENUMERIC, "DEM: particle %ld has a non-finite position (%g, %g, %g) or velocity "
                      "(%g, %g, %g) at step %ld (t = %g s)", p->id[i], p->x[i], p->y[i], p->z[i], p->vx[i],
                      p->vy[i], p->vz[i], d->step, d->t);
}

/* An aggregate still growing to its size (growth.c) overlaps its neighbours
 * by design until it has pushed them aside: its pairs are not judged. */
static int growing(const gs_dem_case *c, long id) {
  const gs_dem_wet *w = c->wet;
  if (!w || !w->has_gran) return 0;
  for (size_t k = 0; k < w->gran.ngrow; k++)
    if (w->gran.grow[k].id == id) return 1;
  return 0;
}

int gs_dem_health_check(gs_dem_health *h, const gs_dem_case *c, int start, gs_error *err) {
  const gs_dem *d = c->dem;
  const gs_dem_particles *p = &d->p;
  long bad = first_non_finite(p);
  if (bad >= 0) return non_finite_error(d, bad, err);
  /* the largest overlap over the pairs of the neighbour list (it holds every
   * pair in contact: the forces were just computed from it) */
  double worst = 0;
  long wi = -1, wj = -1;
  for (size_t i = 0; d->nl_first && i < p->n; i++)
    for (int k = d->nl_first[i]; k < d->nl_first[i + 1]; k++) {
      const size_t j = (size_t)d->nl_j[k];
      const double dx = p->x[i] - p->x[j], dy = p->y[i] - p->y[j], dz = p->z[i] - p->z[j];
      const double rmin = fmin(p->r[i], p->r[j]);
      const double share = (p->r[i] + p->r[j] - sqrt(dx * dx + dy * dy + dz * dz)) / rmin;
      if (share > worst && !growing(c, p->id[i]) && !growing(c, p->id[j])) {
        worst = share;
        wi = (long)i;
        wj = (long)j;
      }
    }
  const double limit = start ? GS_DEM_MAX_START_OVERLAP : GS_DEM_MAX_OVERLAP;
  if (worst > limit)
    return gs_error_set(err, GS_ENUMERIC, "DEM: particles %ld and %ld overlap by %.0f %% of the smaller radius "
                        "(%g m) at step %ld (t = %g s); more than %.0f %% %s", p->id[wi], p->id[wj], 100 * worst,
                        fmin(p->r[wi], p->r[wj]), d->step, d->t, 100 * limit,
                        start ? "at the start: the particles were placed inside each other"
                              : "is outside what the contact law describes: the time step is too large for the "
                                "stiffness, or the particles too soft for the load (dem.time_step, materials E)");
  const uint64_t lost = d->lost - h->lost0;
  if (h->inserted > 0 && (double)lost > c->max_lost * (double)h->inserted)
    return gs_error_set(err, GS_ENUMERIC, "DEM: %llu of the %ld particles inserted have left the box other than "
                        "through an outlet by step %ld (t = %g s), more than dem.max_lost = %g of them: they "
                        "escaped through a hole in a wall or were thrown out by overlapping contacts",
                        (unsigned long long)lost, h->inserted, d->step, d->t, c->max_lost);
  return GS_OK;
}

int gs_dem_health_explain(const gs_dem_case *c, int rc, gs_error *err) {
  long bad = first_non_finite(&c->dem->p);
  if (bad < 0) return rc;
  char was[sizeof err->msg];
  snprintf(was, sizeof was, "%s", err->msg);
  non_finite_error(c->dem, bad, err);
  size_t len = strlen(err->msg);
  snprintf(err->msg + len, sizeof err->msg - len, ": %s", was);
  err->code = rc;
  return rc;
}
