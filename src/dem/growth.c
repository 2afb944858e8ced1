/* An aggregate's contact radius grows to its size over a while instead of
 * at once.  Two merged spheres become one of their summed volume at their
 * centre of mass; at full size that sphere reaches into the neighbours that
 * sat in the "waist" between the two (by up to half a radius for equal
 * spheres), and the elastic energy of such overlaps, released in one contact
 * time, heats a dense bed.  Grown over many contact times, the aggregate
 * pushes its neighbours aside nearly quasi-statically and the contact
 * damping takes the energy.  Mass, inertia and volumes are the aggregate's
 * own from the merge on: only the contact radius lags. */
#include <math.h>
#include <stdlib.h>

#include "dem/dem_wet.h"

int gs_dem_growth_add(gs_dem_granulation *g, gs_dem *d, size_t i, double r0, gs_error *err) {
  gs_dem_particles *p = &d->p;
  const double r1 = p->r[i];
  if (!(r0 < r1)) return GS_OK;
  size_t k = 0;
  while (k < g->ngrow && g->grow[k].id != p->id[i]) k++;
  if (k == g->ngrow) {
    if (g->ngrow == g->grow_cap) {
      size_t nc = g->grow_cap ? 2 * g->grow_cap : 64;
      gs_dem_growing *q = realloc(g->grow, nc * sizeof *q);
      if (!q) return gs_error_set(err, GS_ENOMEM, "out of memory");
      g->grow = q;
      g->grow_cap = nc;
    }
    g->ngrow++;
  }
  g->grow[k] = (gs_dem_growing){p->id[i], d->step, r0, r1};
  p->r[i] = r0;
  return GS_OK;
}

void gs_dem_growth_step(gs_dem_granulation *g, gs_dem *d) {
  const long every = g->growth_k >= 10 ? g->growth_k / 10 : 1;
  if (!g->ngrow || d->step % every) return;
  gs_dem_particles *p = &d->p;
  /* the growing particles are few: find each by a scan over the particles */
  size_t keep = 0;
  for (size_t k = 0; k < g->ngrow; k++) {
    gs_dem_growing *q = &g->grow[k];
    const double f = fmin(1.0, (double)(d->step - q->step0) / (double)g->growth_k);
    long i = -1;
    for (size_t j = 0; j < p->n && i < 0; j++)
      if (p->id[j] == q->id && !p->dead[j]) i = (long)j;
    if (i < 0) continue; /* left through an outlet */
    p->r[i] = f < 1 ? q->r0 + f * (q->r1 - q->r0) : q->r1;
    if (f < 1) g->grow[keep++] = *q;
  }
  g->ngrow = keep;
  d->need_rebuild = 1;
}
