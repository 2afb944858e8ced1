/* Structure-of-arrays particle storage: growth, copy of one particle, free. */
#include <stdlib.h>
#include <string.h>

#include "dem/dem_internal.h"

static int grow(void **ptr, size_t elem, size_t cap, gs_error *err) {
  void *q = realloc(*ptr, (cap ? cap : 1) * elem);
  if (!q) return gs_error_set(err, GS_ENOMEM, "out of memory for %zu particles", cap);
  *ptr = q;
  return GS_OK;
}

int gs_dem_particles_reserve(gs_dem_particles *p, size_t cap, gs_error *err) {
  if (cap <= p->cap) return GS_OK;
  size_t nc = p->cap ? p->cap : 64;
  while (nc < cap) nc *= 2;
  int rc = GS_OK;
#define X(f) if (!rc) rc = grow((void **)&p->f, sizeof(double), nc, err);
  GS_DEM_DOUBLE_FIELDS(X)
#undef X
  if (!rc) rc = grow((void **)&p->type, sizeof(int), nc, err);
  if (!rc) rc = grow((void **)&p->id, sizeof(long), nc, err);
  if (!rc) rc = grow((void **)&p->dead, 1, nc, err);
  if (!rc) rc = grow((void **)&p->wall_mask, sizeof(uint32_t), nc, err);
  if (!rc) rc = grow((void **)&p->wkey, sizeof(uint64_t) * GS_DEM_WSLOTS, nc, err);
  if (!rc) rc = grow((void **)&p->wshear, 3 * sizeof(double) * GS_DEM_WSLOTS, nc, err);
  if (!rc) p->cap = nc;
  return rc;
}

void gs_dem_particles_free(gs_dem_particles *p) {
#define X(f) free(p->f);
  GS_DEM_DOUBLE_FIELDS(X)
#undef X
  free(p->type);
  free(p->id);
  free(p->dead);
  free(p->wall_mask);
  free(p->wkey);
  free(p->wshear);
  memset(p, 0, sizeof *p);
}

void gs_dem_particles_copy(gs_dem_particles *dst, size_t di, const gs_dem_particles *src,
                           size_t si) {
#define X(f) dst->f[di] = src->f[si];
  GS_DEM_DOUBLE_FIELDS(X)
#undef X
  dst->type[di] = src->type[si];
  dst->id[di] = src->id[si];
  dst->dead[di] = src->dead[si];
  dst->wall_mask[di] = src->wall_mask[si];
  memcpy(dst->wkey + di * GS_DEM_WSLOTS, src->wkey + si * GS_DEM_WSLOTS,
         GS_DEM_WSLOTS * sizeof(uint64_t));
  memcpy(dst->wshear + di * 3 * GS_DEM_WSLOTS, src->wshear + si * 3 * GS_DEM_WSLOTS,
         3 * GS_DEM_WSLOTS * sizeof(double));
}
