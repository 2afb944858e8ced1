/* gransim — embedded discrete element method (DEM) for granulators.
 *
 * Spheres with translation and rotation (velocity Verlet), gravity, the
 * Hertz–Mindlin contact with tangential history, Coulomb limit, viscous damping
 * derived from the coefficient of restitution and constant-directional-torque
 * rolling friction (the model family of LIGGGHTS `pair gran model hertz
 * tangential history rolling_friction cdt`), against other spheres and
 * against walls: planes, cylinders and triangle meshes (STL) that may rotate
 * and translate.  Particles come in types; each type has a material and a
 * size class (the PBM class its collisions are booked under).
 *
 * The simulation counts collision *events* (a contact that begins) per pair of
 * size classes and impacts per wall and class, which is what the PBM's
 * aggregation and breakage kernels need; src/dem/stats.c turns them into
 * tables (see docs/case-files.md, section "DEM cases").
 *
 * Units are SI throughout.  All functions return GS_OK or an error code and
 * fill a caller-owned gs_error. */
#ifndef GRANSIM_DEM_H
#define GRANSIM_DEM_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "gransim/cfg.h"
#include "gransim/dem_data.h"
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_dem gs_dem;
typedef struct gs_dem_mesh gs_dem_mesh;

/* Material of a particle type or of a wall.  For a pair, E and nu combine to
 * the effective moduli; e, mu_s and mu_r of the pair are the means of the two
 * materials' values (identical materials give exactly the values given). */
typedef struct {
  double E;       /* Young's modulus [Pa] */
  double nu;      /* Poisson's ratio */
  double e;       /* coefficient of restitution, (0, 1] */
  double mu_s;    /* sliding friction */
  double mu_r;    /* rolling friction (CDT) */
  double density; /* [kg/m^3]; ignored for walls */
} gs_dem_material;

/* Mesh contacts: one per touching region at the closest feature (gransim),
 * or one per triangle with LIGGGHTS 3.8's edge and corner ownership (to
 * compare with LIGGGHTS; see src/dem/mesh_topology.c). */
enum { GS_DEM_MESH_CLOSEST = 0, GS_DEM_MESH_LIGGGHTS = 1 };

typedef struct {
  double dt;          /* time step [s] */
  double gravity[3];  /* [m/s^2] */
  double skin;        /* Verlet skin [m]; lists are rebuilt when a particle moved skin/2 */
  double lo[3], hi[3];/* simulation box; particles leaving it are removed and counted lost */
  int damping;        /* GS_DEM_DAMPING_* */
  int nclass;         /* size classes for statistics (>= 1) */
  double impact_dv;   /* bin width of impact speed histograms [m/s] (0: 0.25) */
  int mesh_contacts;  /* GS_DEM_MESH_* */
} gs_dem_params;

/* ---- setup ------------------------------------------------------------- */
gs_dem *gs_dem_alloc(const gs_dem_params *p, gs_error *err);
void gs_dem_free(gs_dem *d);

/* A particle type: material and size class (0-based).  Returns the type index
 * (>= 0) or -1 with err set. */
int gs_dem_add_type(gs_dem *d, const gs_dem_material *m, int size_class, gs_error *err);

/* Walls.  Each returns the wall index (>= 0) or -1.  name labels outputs. */
int gs_dem_add_plane(gs_dem *d, const char *name, const double point[3], const double normal[3],
                     const gs_dem_material *m, gs_error *err);
/* Cylinder about axis through point; inside != 0: particles are kept inside. */
int gs_dem_add_cylinder(gs_dem *d, const char *name, const double point[3], const double axis[3],
                        double radius, int inside, const gs_dem_material *m, gs_error *err);
/* Triangle mesh; the simulation takes ownership of mesh (also on failure). */
int gs_dem_add_mesh(gs_dem *d, const char *name, gs_dem_mesh *mesh, const gs_dem_material *m,
                    gs_error *err);
/* Prescribed rigid motion of a wall: rotation at omega [rad/s] about the axis
 * through origin (right-hand rule), plus translation at velocity. */
int gs_dem_wall_set_motion(gs_dem *d, int wall, const double origin[3], const double axis[3],
                           double omega, const double velocity[3], gs_error *err);
/* The rotation set by gs_dem_wall_set_motion begins at t_start [s] (>= 0;
 * default 0): before it the wall stands still, so that a bed settles with
 * the impeller at rest; from it the wall turns at omega. */
int gs_dem_wall_set_spin_start(gs_dem *d, int wall, double t_start, gs_error *err);
size_t gs_dem_nwalls(const gs_dem *d);
const char *gs_dem_wall_name(const gs_dem *d, size_t wall);

/* ---- meshes (src/dem/mesh_stl.c) ---------------------------------------- */
/* Read an ASCII or binary STL file, multiplying coordinates by scale. */
gs_dem_mesh *gs_dem_mesh_read_stl(const char *path, double scale, gs_error *err);
/* A mesh from ntri triangles given as 9 coordinates each (copied). */
gs_dem_mesh *gs_dem_mesh_from_triangles(const double *xyz, size_t ntri, gs_error *err);
size_t gs_dem_mesh_ntri(const gs_dem_mesh *m);
void gs_dem_mesh_bounds(const gs_dem_mesh *m, double lo[3], double hi[3]);
void gs_dem_mesh_free(gs_dem_mesh *m);

/* ---- particles ----------------------------------------------------------- */
/* Add a sphere of type at x with velocity v and angular velocity w (NULL =
 * zero).  Returns its id (>= 0, never reused) or -1.  Particles added between
 * steps enter at the next step; overlaps are not checked here (insertion.c). */
long gs_dem_add_particle(gs_dem *d, int type, double radius, const double x[3], const double v[3],
                         const double w[3], gs_error *err);

/* ---- regions, insertion, removal (src/dem/region.c, insertion.c) --------- */
typedef struct {
  int kind;          /* 0 box, 1 cylinder */
  double lo[3], hi[3];           /* box */
  double p[3], a[3], R, Rin, s0, s1; /* cylinder: axis through p along unit a, radii
                                         Rin..R (an annulus if Rin > 0), axial extent
                                         s0..s1 measured from p */
} gs_dem_region;
enum { GS_DEM_REGION_BOX = 0, GS_DEM_REGION_CYLINDER = 1 };
int gs_dem_region_contains(const gs_dem_region *g, const double x[3]);
/* Uniform random point of the region; u are three numbers in [0,1). */
void gs_dem_region_point(const gs_dem_region *g, const double u[3], double x[3]);
double gs_dem_region_volume(const gs_dem_region *g);

/* A size distribution over particle types: entry k inserts type[k] with
 * number or mass fraction frac[k] and a radius uniform in [rmin[k], rmax[k]],
 * or, where gsd is given and gsd[k] > 1, lognormal with median median[k] and
 * geometric standard deviation gsd[k] (ln r normal with mean ln median and
 * sd ln gsd), truncated to [rmin[k], rmax[k]] (drawn with gsl_ran_lognormal,
 * draws outside the range are redrawn). */
typedef struct {
  size_t n;
  const int *type;
  const double *rmin, *rmax, *frac;
  int by_mass;
  const double *median, *gsd; /* NULL: every entry fixed or uniform */
} gs_dem_psd;
/* Mean r^3 of entry k of the distribution (for mass fractions), and the
 * share of the untruncated lognormal inside [rmin, rmax] (1 for a uniform
 * entry); either output may be NULL. */
void gs_dem_psd_moment3(const gs_dem_psd *psd, size_t k, double *mean_r3, double *share);

/* Insert up to `count` particles and at most `mass` kg (either may be
 * infinite, not both) at random points of the region, none overlapping a
 * particle (present or pending) or a wall.  A drawn particle (class and
 * radius) is kept until it finds a free spot, so a crowded region does not
 * bias the size distribution; after 20 rounds of 50 spots for one particle
 * the region counts as full and insertion stops.
 * v: initial velocity (NULL = 0).  rng_state: a caller-held seed, advanced
 * once per call; the call's draws come from a GSL mt19937 generator seeded
 * from it.  *n_out, *m_out: what was inserted (may be less: region full). */
int gs_dem_insert(gs_dem *d, const gs_dem_region *reg, const gs_dem_psd *psd, long count,
                  double mass, const double v[3], uint64_t *rng_state, long *n_out, double *m_out,
                  gs_error *err);
/* 1 if a sphere at x of radius r overlaps a wall (as placed now). */
int gs_dem_touches_wall(gs_dem *d, const double x[3], double r);

/* ---- running ------------------------------------------------------------ */
/* Use OpenMP threads only from n particles on (default 20000): below that a
 * step takes well under a millisecond and the threads' synchronisation costs
 * more than it saves, much more on a machine shared with other work. */
void gs_dem_set_parallel_min(gs_dem *d, size_t n);
/* The fewest particles for threads (above); a coupled model's per-particle
 * loops follow it. */
size_t gs_dem_parallel_min(const gs_dem *d);
/* Advance nsteps time steps.  Fails on non-finite positions. */
int gs_dem_run(gs_dem *d, long nsteps, gs_error *err);
/* Remove every particle whose centre satisfies pred (applied at list rebuilds,
 * at least every 200 steps).  Removed particles are recorded (class,
 * residence time since they entered, mass) until taken with
 * gs_dem_take_removed, which returns their number and empties the record. */
size_t gs_dem_take_removed(gs_dem *d, const int **cls, const double **residence,
                           const double **mass);
void gs_dem_remove_if(gs_dem *d, int (*pred)(const double x[3], void *ctx), void *ctx);

/* ---- state (read-only views, valid until the next step) ----------------- */
typedef struct {
  size_t n;
  const double *x, *y, *z, *vx, *vy, *vz, *wx, *wy, *wz, *r, *m;
  const int *type;
  const long *id;
  const double *t_in; /* time each particle entered */
  const double *vs, *vl; /* solid and liquid volume [m^3] (liquid from spray droplets) */
} gs_dem_view;
void gs_dem_get_view(const gs_dem *d, gs_dem_view *v);

/* Hooks for a code coupled to the DEM (a gas phase, src/cfd): `forces` is
 * called at every step once the contact forces are computed and before they
 * move the particles, with the particles as they are now (in the engine's
 * current order, which changes at list rebuilds: key per-particle data by
 * view->id) and their force arrays, to which it adds external forces [N].
 * `after_step` is called after every completed step; a non-zero return
 * (with err set) stops gs_dem_run with that status.  Either may be NULL; a
 * simulation has one set of hooks (NULL removes them). */
typedef struct {
  void (*forces)(const gs_dem_view *v, double *fx, double *fy, double *fz, void *user);
  int (*after_step)(gs_dem *d, void *user, gs_error *err);
  void *user;
} gs_dem_hooks;
void gs_dem_set_hooks(gs_dem *d, const gs_dem_hooks *h);

double gs_dem_time(const gs_dem *d);
double gs_dem_dt(const gs_dem *d); /* the time step [s] */
void gs_dem_get_params(const gs_dem *d, gs_dem_params *p);
long gs_dem_step_count(const gs_dem *d);
int gs_dem_type_class(const gs_dem *d, int type);
size_t gs_dem_ntypes(const gs_dem *d);
/* Smallest Rayleigh time over the particle types present in the type table. */
double gs_dem_rayleigh_time(const gs_dem *d);

/* Counters accumulated since the last gs_dem_counters_reset (for rates). */
typedef struct {
  int nclass;
  size_t nwalls;
  const uint64_t *pair_events;   /* nclass*nclass, [i*nclass+j] with i <= j (upper triangle) */
  const uint64_t *wall_impacts;  /* nwalls*nclass */
  const double *wall_vn_sum;     /* sum of normal impact speeds, nwalls*nclass */
  const double *wall_vn2_sum;    /* sum of squared normal impact speeds */
  const double *wall_vt_sum;     /* sum of tangential impact speeds */
  uint64_t lost;                 /* particles that left the box */
  uint64_t rebuilds;             /* neighbour list rebuilds */
  double t0;                     /* time of the last reset */
} gs_dem_counters;
void gs_dem_get_counters(const gs_dem *d, gs_dem_counters *c);
void gs_dem_counters_reset(gs_dem *d);
/* Impact speed histogram of wall w, class c: nbins bins of width dv from 0
 * (the last bin takes everything above). */
const uint64_t *gs_dem_impact_histogram(const gs_dem *d, size_t wall, int cls, int *nbins,
                                        double *dv);
/* Impacts slower than this [m/s] are resting contacts (a particle placed
 * touching a wall): they count as impacts but their speed is not recorded,
 * as `gransim dem-reduce` leaves them out of its fits (min_speed). */
#define GS_DEM_MIN_IMPACT_SPEED 1e-3
/* The speed of every wall impact since the last gs_dem_counters_reset:
 * U = |v - v_wall|, the particle's velocity relative to the wall material at
 * the contact point when the contact began.  Returns their number; for impact
 * k, wall_class[k] = wall * nclass + class and ln_u[k] = ln U [ln(m/s)].
 * Ordered by step and, within a step, by particle id, so the record does not
 * depend on the number of threads.  Valid until the next step or reset. */
size_t gs_dem_impact_speeds(const gs_dem *d, const int **wall_class, const double **ln_u);

/* Number of particle-particle contacts currently active. */
size_t gs_dem_ncontacts(const gs_dem *d);
/* Kinetic energy: translational and rotational [J]. */
void gs_dem_kinetic_energy(const gs_dem *d, double *trans, double *rot);
/* Torque of the particles on a wall about its rotation axis (last step) [N m]. */
double gs_dem_wall_axial_torque(const gs_dem *d, size_t wall);
/* Current world-frame triangle coordinates of a mesh wall (9 per triangle),
 * written to out (caller provides 9*ntri doubles; NULL: only count); returns
 * ntri, 0 if not a mesh. */
size_t gs_dem_wall_triangles(const gs_dem *d, size_t wall, double *out);

/* ---- DEM case files (src/dem/case_dem.c, run_dem.c; docs/case-files.md) -- */
typedef struct gs_dem_case_s gs_dem_case;
/* Read and validate a DEM case; builds the simulation (meshes read, walls
 * placed) but inserts nothing yet. */
gs_dem_case *gs_dem_case_load(const char *path, gs_error *err);
/* The same from a loaded case file (taken over, also on failure): a caller
 * that changed keys (gs_cfg_set) first.  Relative mesh paths resolve against
 * gs_cfg_dir. */
gs_dem_case *gs_dem_case_from_cfg(gs_cfg *cfg, gs_error *err);
/* One line describing the case (for `gransim dem --check`). */
void gs_dem_case_describe(const gs_dem_case *c, char *buf, size_t n);
/* Write the case's generated walls (walls[].generate) as STL files into
 * out_dir/geometry/NAME.stl (metres), and have the LIGGGHTS deck refer to
 * them; *nwritten (may be NULL): how many.  gs_dem_case_run and the LIGGGHTS
 * engine call it; `gransim geometry` alone. */
int gs_dem_case_write_geometry(gs_dem_case *c, const char *out_dir, size_t *nwritten, gs_error *err);
/* The generated walls of a `walls` list (a DEM case's, or a coupled case's
 * dem.walls) built and written as out_dir/NAME.stl, without the rest of the
 * case; report (may be NULL): one line per mesh (facets, volume, area,
 * bounds).  For `gransim geometry`. */
int gs_dem_generate_walls(struct gs_cfg_node *walls, const char *out_dir, FILE *report, size_t *nwritten,
                          gs_error *err);
/* The generator types of walls[].generate, one "  name  summary" line each
 * (for `gransim list`). */
void gs_dem_list_generators(FILE *fp);
/* Run it, writing the tables, time series and VTK files into out_dir. */
int gs_dem_case_run(gs_dem_case *c, const char *out_dir, int progress, gs_error *err);
void gs_dem_case_free(gs_dem_case *c);

/* The quantities the steady-state detector can watch (statistics.steady.
 * quantities), NULL-terminated, in the order of the GS_DEM_STEADY_* bits:
 * holdup_mass, collision_rate, kinetic_energy (translational + rotational). */
extern const char *const gs_dem_steady_quantities[];
enum { GS_DEM_STEADY_HOLDUP = 1, GS_DEM_STEADY_COLLISIONS = 2, GS_DEM_STEADY_KINETIC = 4 };
/* The default: hold-up mass and collision rate (Sampat et al. 2018). */
#define GS_DEM_STEADY_DEFAULT (GS_DEM_STEADY_HOLDUP | GS_DEM_STEADY_COLLISIONS)
/* A `quantities` list (one or more of those names, each once) into *mask;
 * a misspelt name is refused with a did-you-mean hint. */
int gs_dem_steady_quantities_read(struct gs_cfg_node *list, unsigned *mask, gs_error *err);
/* The names of mask, joined by sep ("holdup_mass, collision_rate"). */
void gs_dem_steady_quantities_join(unsigned mask, const char *sep, char *buf, size_t n);

/* The figures of a DEM case run at every statistics sample
 * (statistics.sample_every), handed to its observer. */
typedef struct {
  double t;                /* [s] */
  long step;
  size_t particles;
  double holdup_mass;      /* [kg] */
  double collisions_per_s; /* particle-particle collision events over the last sample interval [1/s] */
  double kinetic_energy;   /* translational + rotational [J] */
  int steady;              /* the case's own detector (statistics.steady) has fired */
  int window;              /* the statistics window is open (the tables average from its start) */
} gs_dem_sample;
/* An observer of a case's run, called at every sample before the sample
 * enters the statistics.  Setting *open_window opens the statistics window
 * at this sample if it is not open yet (as statistics.start: steady does when
 * the case's detector fires); setting *stop ends the run after this step's
 * events, the tables written as of then (as if dem.duration ended there).  A
 * non-zero return (err set) stops the run with that status. */
typedef struct {
  int (*sample)(const gs_dem_sample *s, void *user, int *open_window, int *stop, gs_error *err);
  void *user;
} gs_dem_observer;
/* Set (NULL: remove) the observer of gs_dem_case_run. */
void gs_dem_case_set_observer(gs_dem_case *c, const gs_dem_observer *o);
/* The simulation the case runs (for gs_dem_set_hooks), its duration [s], and
 * its `gas` section (NULL if none; read by src/cfd, gs_cfd_case_create). */
gs_dem *gs_dem_case_sim(gs_dem_case *c);
double gs_dem_case_duration(const gs_dem_case *c);
struct gs_cfg_node *gs_dem_case_gas(gs_dem_case *c);
/* The engine the case asks for (dem.engine): 0 embedded, 1 LIGGGHTS
 * (include/gransim/liggghts.h runs those). */
int gs_dem_case_engine(const gs_dem_case *c);
/* Overrides dem.engine (`gransim dem --engine`); no key's reading depends on it. */
void gs_dem_case_set_engine(gs_dem_case *c, int engine);

#ifdef __cplusplus
}
#endif
#endif
