/* The spray's liquid by size class (dem_wet.h): how the droplets a spray
 * sends into a moving bed end up shared over the particles' size classes,
 * set against the absorption law of De et al. (2025, eqs. 7-9), which
 * predicts shares in proportion to granule volume N_k V_k, and against
 * shares in proportion to surface N_k d_k^2 (what a bed whose particles are
 * hit by their projected area alone would give).  The PBM's `share: {type:
 * absorption}` is the former (docs/models.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "dem/dem_stats.h"
#include "dem/dem_wet.h"

void gs_dem_spray_classes(const gs_dem *d, int nclass, gs_dem_spray_class *out) {
  const gs_dem_particles *p = &d->p;
  for (int k = 0; k < nclass; k++) out[k] = (gs_dem_spray_class){0, 0, 0, 0};
  for (size_t i = 0; i < p->n; i++) {
    if (p->dead[i]) continue;
    const int k = d->types[p->type[i]].cls;
    if (k < 0 || k >= nclass) continue;
    out[k].particles += 1;
    out[k].solid += p->vs[i];
    out[k].area += 4 * M_PI * p->r[i] * p->r[i];
    out[k].liquid += p->vl[i];
  }
}

static const char *const units[] = {"class", "1", "name", "1", "particles", "1", "solid_volume [m^3]", "m^3",
                                    "liquid [m^3]", "m^3", "liquid_per_particle [m^3]", "m^3",
                                    "liquid_per_solid [1]", "1", "share [1]", "1", "volume_law_share [1]", "1",
                                    "surface_law_share [1]", "1", "share/volume_law [1]", "1", NULL};

int gs_dem_spray_classes_write(const gs_dem_case *c, const char *dir, gs_error *err) {
  const int n = (int)c->nclass;
  gs_dem_spray_class *k = calloc((size_t)n, sizeof *k);
  if (!k) return gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_dem_spray_classes(c->dem, n, k);
  double L = 0, S = 0, A = 0;
  for (int i = 0; i < n; i++) L += k[i].liquid, S += k[i].solid, A += k[i].area;
  gs_csv_out tab;
  FILE *fp = gs_dem_table_begin(&tab, dir, "spray_classes.csv", err);
  if (!fp) {
    free(k);
    return err->code;
  }
  fprintf(fp, "# liquid held by the particles of each size class at t = %.9g s, against the absorption law "
          "(De et al. 2025, eqs. 7-9: shares in proportion to solid volume; psi = 1) and a surface law "
          "(shares in proportion to particle surface)\n", c->dem->t);
  fprintf(fp, "class,name,particles,solid_volume [m^3],liquid [m^3],liquid_per_particle [m^3],liquid_per_solid [1],"
              "share [1],volume_law_share [1],surface_law_share [1],share/volume_law [1]\n");
  for (int i = 0; i < n; i++) {
    const double share = L > 0 ? k[i].liquid / L : NAN, vlaw = S > 0 ? k[i].solid / S : NAN;
    fprintf(fp, "%d,%s,%.0f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", i + 1, c->cls[i].name, k[i].particles,
            k[i].solid, k[i].liquid, k[i].particles > 0 ? k[i].liquid / k[i].particles : NAN,
            k[i].solid > 0 ? k[i].liquid / k[i].solid : NAN, share, vlaw, A > 0 ? k[i].area / A : NAN,
            vlaw > 0 ? share / vlaw : NAN);
  }
  free(k);
  return gs_dem_table_end(&tab, units, err);
}
