/* Internal state of the DEM engine, shared by the files of src/dem/.
 * Particles are structure-of-arrays; every per-particle array has capacity
 * `cap` and the first `n` entries are live, kept in cell order (re-sorted at
 * every 8th neighbour-list rebuild and whenever particles are added or
 * removed) so that neighbours are close in memory. */
#ifndef GRANSIM_DEM_INTERNAL_H
#define GRANSIM_DEM_INTERNAL_H

#include <stdint.h>

#include "gransim/dem.h"

/* Wall contacts remembered per particle (tangential history and impact
 * detection).  A sphere rarely touches more than three features at once. */
#define GS_DEM_WSLOTS 4
#define GS_DEM_MAX_WALLS 32
#define GS_DEM_IMPACT_BINS 40

/* Per-particle arrays; the list drives allocation, permutation and removal.
 * vs and vl are the solid and liquid volumes [m^3] (vl grows as a particle
 * absorbs spray droplets, src/dem/spray.c; both add up when particles
 * aggregate, src/dem/granulation.c). */
#define GS_DEM_DOUBLE_FIELDS(X) \
  X(x) X(y) X(z) X(vx) X(vy) X(vz) X(wx) X(wy) X(wz) X(fx) X(fy) X(fz) X(tx) X(ty) X(tz) \
  X(r) X(m) X(invm) X(invI) X(x0) X(y0) X(z0) X(t_in) X(vs) X(vl)

typedef struct {
  size_t n, cap;
#define X(f) double *f;
  GS_DEM_DOUBLE_FIELDS(X)
#undef X
  int *type;
  long *id;
  uint8_t *dead;       /* marked for removal at the next rebuild */
  uint32_t *wall_mask; /* walls touched at the last step (impact = new bit) */
  uint64_t *wkey;      /* GS_DEM_WSLOTS wall-contact keys per particle (0 = empty) */
  double *wshear;      /* 3 per slot */
} gs_dem_particles;

/* Effective contact constants of a pair of materials. */
typedef struct {
  double Estar, Gstar, damp, mu_s, mu_r;
} gs_dem_pair;

enum { GS_DEM_WALL_PLANE, GS_DEM_WALL_CYLINDER, GS_DEM_WALL_MESH };

/* Triangle mesh in its own (body) frame, with a bin grid for contact search. */
struct gs_dem_mesh {
  size_t ntri, nvert;
  double *v;        /* 9 per triangle */
  double *nrm;      /* unit normal, 3 per triangle */
  int *vid;         /* 3 welded vertex ids per triangle (edge/vertex contact dedup) */
  uint8_t *active;  /* LIGGGHTS mode only: bits 0-2 edge k, 3-5 corner k may touch */
  /* bins: built for the largest particle radius + margin */
  double blo[3], bh;
  int bdim[3];
  int *bfirst;      /* CSR over cells */
  int *btri;
  uint64_t *bmask;  /* one bit per cell: has triangles (small enough to stay in cache) */
  double bin_reach; /* particle radius the bins were built for */
};

/* LIGGGHTS 3.8's edge and corner ownership for `mesh_contacts: liggghts`
 * (src/dem/mesh_topology.c); sets m->active once. */
int gs_dem_mesh_liggghts_activity(gs_dem_mesh *m, gs_error *err);

typedef struct {
  int kind;
  char name[64];
  gs_dem_material mat;
  /* plane: p, n; cylinder: p, a (unit), R, inside */
  double p[3], n[3], a[3], R;
  int inside;
  gs_dem_mesh *mesh;
  /* motion */
  int moving;
  double origin[3], axis[3], omega, vel[3];
  double spin_start; /* the rotation begins at this time (a bed settles first) */
  double spin;       /* omega once spin_start is reached, 0 before (set with the frame) */
  double Rm[9], shift[3], tframe; /* body -> world at time tframe */
  /* per-type contact constants, recomputed when types are added */
  gs_dem_pair *pt;
  /* torque and force of the particles on the wall (last step) */
  double force[3], torque[3];
} gs_dem_wall;

typedef struct {
  gs_dem_material mat;
  int cls;
} gs_dem_type;

struct gs_dem {
  gs_dem_params prm;
  gs_dem_particles p;
  gs_dem_type *types;
  size_t ntypes;
  gs_dem_pair *pp; /* ntypes*ntypes */
  gs_dem_wall walls[GS_DEM_MAX_WALLS];
  size_t nwalls;
  double rmax;     /* largest radius seen (sizes the cells and mesh bins) */
  double t;
  long step;
  long next_id;
  int need_rebuild;
  int pairs_dirty;  /* types or walls added since the constants were computed */
  long since_rebuild;
  /* pending particles (added between steps), and the rebuild's second buffer */
  gs_dem_particles pend, tmp;
  /* neighbour list (half list, CSR), with contact history per entry */
  size_t nl_cap;
  int *nl_first;
  int *nl_j;
  uint8_t *nl_touch;
  double *nl_shear; /* 3 per entry */
  /* cell grid */
  double cell_h, cell_inv;
  int cdim[3];
  size_t ncells;
  int *cell_first; /* ncells + 1 */
  /* scratch */
  int *perm, *cellof;
  int *order, *pos; /* particles in cell order, and each particle's place in it */
  size_t perm_cap;
  /* thread force buffers (threads 1..nt-1; thread 0 writes the particle arrays) */
  int nthreads;
  size_t par_min; /* fewest particles for which the loops use threads */
  double *tbuf;
  size_t tbuf_cap;
  /* counters */
  uint64_t *pair_events; /* nclass^2 */
  uint64_t *wall_impacts;
  double *wall_vn_sum, *wall_vn2_sum, *wall_vt_sum;
  uint64_t *impact_hist; /* nwalls*nclass*GS_DEM_IMPACT_BINS */
  double impact_dv;
  /* ln U of every wall impact since the last counters reset, in the order of
   * the steps and, within a step, of the particle ids (so the record does not
   * depend on the thread count): wall*nclass + class, and ln U */
  int *imp_q;
  double *imp_lnu;
  size_t nimp, imp_cap;
  int oom; /* a force loop ran out of memory (reported by gs_dem_run) */
  uint64_t lost, rebuilds;
  double t_reset;
  /* particles removed by the predicate since the last gs_dem_take_removed */
  int *rm_cls;
  double *rm_rt, *rm_m;
  size_t nrm, rm_cap, rm_taken;
  /* collision onsets recorded one by one for the granulation (pair_log.c);
   * NULL unless gs_dem_pair_log_enable was called */
  struct gs_dem_pair_log *plog;
  /* solid and liquid volume of the particles removed (outlets, box) */
  double vs_removed, vl_removed;
  gs_dem_hooks hooks; /* external forces and after-step calls (gs_dem_set_hooks) */
  /* removal predicate */
  int (*remove_pred)(const double x[3], void *ctx);
  void *remove_ctx;
};

/* particles.c */
int gs_dem_particles_reserve(gs_dem_particles *p, size_t cap, gs_error *err);
void gs_dem_particles_free(gs_dem_particles *p);
/* Copy particle src_i of src into slot dst_i of dst. */
void gs_dem_particles_copy(gs_dem_particles *dst, size_t dst_i, const gs_dem_particles *src,
                           size_t src_i);

/* material.c */
void gs_dem_pair_constants(const gs_dem_material *a, const gs_dem_material *b, int damping,
                           gs_dem_pair *out);
int gs_dem_update_pairs(gs_dem *d, gs_error *err);

/* sim.c: pair tables and mesh bins for the current types, walls and radii */
int gs_dem_prepare(gs_dem *d, gs_error *err);

/* neighbour.c */
int gs_dem_rebuild(gs_dem *d, gs_error *err);
int gs_dem_needs_rebuild(const gs_dem *d);

/* pair_log.c: a collision onset (particle ids ida < idb, normal approach
 * speed vn >= 0 [m/s]); records of one force evaluation are put in id order
 * so the log does not depend on the number of threads */
typedef struct {
  long ida, idb;
  double vn;
} gs_dem_pair_rec;
typedef struct gs_dem_pair_log {
  gs_dem_pair_rec *r;
  size_t n, cap;
  int oom;
} gs_dem_pair_log;
int gs_dem_pair_log_enable(gs_dem *d, gs_error *err);
void gs_dem_pair_log_push(gs_dem_pair_log *b, long ida, long idb, double vn);
/* Append the per-thread buffers of one force evaluation to d->plog. */
void gs_dem_pair_log_merge(gs_dem *d, gs_dem_pair_log *bufs, int nt);
void gs_dem_pair_log_free(gs_dem *d);

/* pair_forces.c, wall_forces.c */
void gs_dem_pair_forces(gs_dem *d);
void gs_dem_wall_forces(gs_dem *d);

/* geometry.c: closest point on triangle abc to p; returns the feature:
 * 0 face, 1..3 edge ab/bc/ca, 4..6 vertex a/b/c. */
int gs_dem_closest_on_triangle(const double p[3], const double a[3], const double b[3],
                               const double c[3], double q[3]);
/* Wall frames: gs_dem_wall_frame sets the rotation for time t; then world ->
 * body for a point, body -> world for a point and a direction, and the
 * velocity of the wall material at a world point. */
void gs_dem_wall_frame(gs_dem_wall *w, double t);
void gs_dem_wall_to_body(const gs_dem_wall *w, const double xw[3], double xb[3]);
void gs_dem_wall_point_to_world(const gs_dem_wall *w, const double xb[3], double xw[3]);
void gs_dem_wall_dir_to_world(const gs_dem_wall *w, const double db[3], double dw[3]);
void gs_dem_wall_velocity(const gs_dem_wall *w, const double xw[3], double v[3]);

/* mesh_closed.c: the edges of m that belong to one facet only (the borders
 * of holes) into *nopen, and the first facet (file order) having one, with
 * that edge (vertex k to k + 1 of the facet), into *tri and *k. */
int gs_dem_mesh_open_edges(const gs_dem_mesh *m, size_t *nopen, size_t *tri, int *k, gs_error *err);

/* mesh_bins.c */
int gs_dem_mesh_build_bins(gs_dem_mesh *m, double reach, gs_error *err);
void gs_dem_mesh_weld(gs_dem_mesh *m);

#endif
