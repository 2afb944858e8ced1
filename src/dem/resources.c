/* The resources of a DEM case, stated before a run takes them: the particles
 * it asks for, their memory and the size of the particle frames, against the
 * case's `limits` keys (case/limits.h).  Every figure is a lower bound, so a
 * refusal is certain: fills by mass and mass feeds count their heaviest
 * particle, feeds count nothing when outlets may take particles out, and the
 * memory counts only the per-particle arrays of gs_dem_particles. */
#include <limits.h>
#include <math.h>
#include <stdint.h>

#include "case/limits.h"
#include "dem/dem_case.h"
#include "dem/dem_internal.h"

/* Bytes of gs_dem_particles per particle: its double fields, type, id,
 * dead, wall mask, wall keys and their shear. */
#define X(f) +1
static const double particle_bytes = (0 GS_DEM_DOUBLE_FIELDS(X)) * sizeof(double) + sizeof(int) + sizeof(long) +
                                     sizeof(uint8_t) + sizeof(uint32_t) + GS_DEM_WSLOTS * (sizeof(uint64_t) +
                                                                                          3 * sizeof(double));
#undef X
/* Bytes per particle in a .vtp frame (docs/performance.md): position,
 * velocity, radius, class, id and liquid, raw appended binary. */
#define VTP_BYTES_PER_PARTICLE 84.0

static double heaviest(const gs_dem_case *c) {
  double m = 0;
  for (size_t k = 0; k < c->nclass; k++)
    m = fmax(m, c->cls[k].mat.density * 4.0 / 3.0 * M_PI * pow(c->cls[k].rmax, 3));
  return m;
}

double gs_dem_case_particles_asked(const gs_dem_case *c) {
  const double mmax = heaviest(c);
  double n = 0;
  for (size_t i = 0; i < c->nfill; i++) {
    const gs_dem_inserter *f = &c->fill[i];
    n += f->count != LONG_MAX ? (double)f->count : (mmax > 0 ? floor(f->mass / mmax) : 0);
  }
  for (size_t i = 0; !c->noutlets && i < c->nfeed; i++) {
    const gs_dem_inserter *f = &c->feed[i];
    const double t = fmax(0, fmin(f->end, c->duration) - f->start);
    n += f->number_rate > 0 ? floor(f->number_rate * t) : (mmax > 0 ? floor(f->mass_rate * t / mmax) : 0);
  }
  return n;
}

int gs_dem_case_check_limits(const gs_dem_case *c, gs_cfg_node *root, gs_error *err) {
  gs_limits lim;
  int rc = gs_limits_read(root, &lim, err);
  if (rc) return rc;
  const double n = gs_dem_case_particles_asked(c), memory = n * particle_bytes / 1e9;
  if (memory > lim.memory_gb)
    return gs_cfg_fail(lim.node ? lim.node : root, err,
                       "the case asks for %.0f particles (fill and feeds), which need at least %.3g GB of memory "
                       "(%.0f bytes each), more than limits.memory_gb = %.3g GB%s: use fewer or larger particles, "
                       "or raise limits.memory_gb on a larger machine",
                       n, memory, particle_bytes, lim.memory_gb, lim.node ? "" : " (80 % of this machine's memory)");
  const double frames = c->vtk_every > 0 ? floor(c->duration / c->vtk_every) + 1 : 0;
  const double output = frames * n * VTP_BYTES_PER_PARTICLE / 1e9;
  if (output > lim.output_gb)
    return gs_cfg_fail(lim.node ? lim.node : root, err,
                       "the particle frames (output.vtk_every) would take at least %.3g GB (%.0f frames of %.0f "
                       "particles), more than limits.output_gb = %.3g GB%s: raise output.vtk_every or "
                       "limits.output_gb",
                       output, frames, n, lim.output_gb, lim.node ? "" : " (the default)");
  return GS_OK;
}
