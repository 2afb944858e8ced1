/* A DEM case read from YAML (case_dem.c) and its run driver (run_dem.c). */
#ifndef GRANSIM_DEM_CASE_INTERNAL_H
#define GRANSIM_DEM_CASE_INTERNAL_H

#include "gransim/cfg.h"
#include "gransim/dem.h"

#define GS_DEM_MAX_CLASSES 64
#define GS_DEM_CASE_MAX_WALLS 32
/* The largest time step accepted, as a fraction of the Rayleigh time of the
 * smallest particle (docs/reliability.md, "The DEM refuses nonsense"). */
#define GS_DEM_MAX_RAYLEIGH_FRACTION 0.5

/* Which engine runs the case (dem.engine): the embedded one, or LIGGGHTS
 * through a deck written from the same keys (src/liggghts). */
enum { GS_DEM_ENGINE_EMBEDDED = 0, GS_DEM_ENGINE_LIGGGHTS = 1 };
enum { GS_DEM_SRC_MESH = 0, GS_DEM_SRC_PLANE = 1, GS_DEM_SRC_CYLINDER = 2 };

/* A wall as the case file gave it: kept because the LIGGGHTS deck needs the
 * file, scale and motion, which the embedded engine only holds as triangles. */
typedef struct {
  char name[64];
  int kind;              /* GS_DEM_SRC_* */
  char mesh[4096];       /* mesh: the STL file, resolved against the case's folder */
  double scale;
  gs_dem_material mat;
  int rotating;
  double origin[3], axis[3], omega; /* rotation (omega rad/s about the unit axis) */
  double spin_start;                /* rotation.start: the rotation begins then [s] */
  double velocity[3];
  double point[3], normal[3]; /* plane: a point and the unit normal (the LIGGGHTS deck meshes it) */
  int generated;         /* generate: mesh is empty until gs_dem_case_write_geometry */
  int wall;              /* the engine's wall index */
} gs_dem_wall_src;

typedef struct {
  gs_dem_region reg;
  long count;          /* fill: number (or LONG_MAX) */
  double mass;         /* fill: kg (or inf) */
  double mass_rate, number_rate, every, start, end; /* feed */
  double v[3];
  double *frac;        /* per class */
  int by_mass;
  /* running state */
  double done_n, done_m;
  double next_t;
} gs_dem_inserter;

typedef struct {
  char name[64];
  int type;
  double rmin, rmax;   /* fixed (equal), uniform range, or the lognormal's truncation */
  double median, gsd;  /* lognormal radius when gsd > 1 (else 0) */
  gs_dem_material mat; /* its particles' material (for the LIGGGHTS deck) */
} gs_dem_class;

struct gs_dem_case_s {
  gs_cfg *cfg;
  gs_cfg_node *gas; /* the `gas` section, for src/cfd (NULL: none) */
  char path[1024];
  gs_dem *dem;
  gs_dem_params prm;
  int engine;          /* GS_DEM_ENGINE_* */
  int damping_given;   /* dem.damping was in the file */
  int mesh_contacts_given; /* dem.mesh_contacts was in the file */
  size_t nwall_src;
  gs_dem_wall_src wall_src[GS_DEM_CASE_MAX_WALLS];
  double duration;
  /* dem.geometry_scale: every length of the geometry (box, walls, regions,
   * compartments, spray point) is multiplied by it at load; particle sizes
   * are not, and rotations keep their tip speed (omega / geom) */
  double geom;
  uint64_t seed;
  size_t nclass;
  gs_dem_class cls[GS_DEM_MAX_CLASSES];
  gs_dem_inserter *fill, *feed;
  size_t nfill, nfeed;
  gs_dem_region *outlets;
  size_t noutlets;
  /* statistics */
  int start_steady;
  double stats_start, sample_every;
  double cmp_axis[3], cmp_origin[3], *cmp_edges;
  size_t ncmp;
  int has_holdup;
  gs_dem_region holdup;
  long steady_window;
  double steady_tol;
  unsigned steady_q; /* statistics.steady.quantities: GS_DEM_STEADY_* bits */
  /* output */
  double out_every, vtk_every;
  /* spray and granulation (src/dem/dem_wet.h); NULL when the case has neither */
  struct gs_dem_wet *wet;
  /* dem.max_lost: the largest share of the particles inserted that may leave
   * the box other than through an outlet before the run stops */
  double max_lost;
  /* the run's observer (gs_dem_case_set_observer); sample NULL: none */
  gs_dem_observer observer;
};

/* resources.c: the particles the fills and feeds ask for (a lower bound),
 * and the case against its `limits` (memory, particle frames). */
double gs_dem_case_particles_asked(const gs_dem_case *c);
int gs_dem_case_check_limits(const gs_dem_case *c, gs_cfg_node *root, gs_error *err);

/* case_wet.c, wet_run.c: the `spray:` and `granulation:` sections, and the
 * run driver's calls (a case without them just runs the DEM). */
int gs_dem_wet_read(gs_dem_case *c, gs_cfg_node *root, double rmin, gs_error *err);
int gs_dem_wet_start(gs_dem_case *c, const char *dir, gs_error *err);
int gs_dem_wet_advance(gs_dem_case *c, long nsteps, gs_error *err);
int gs_dem_wet_output(gs_dem_case *c, gs_error *err);
int gs_dem_wet_finish(gs_dem_case *c, gs_error *err);
void gs_dem_wet_free(gs_dem_case *c);
/* case_dem.c's readers of a 3-vector and of a direction (normalised). */
int gs_dem_case_vec3(gs_cfg_node *map, const char *key, int required, const double *def, double out[3],
                     gs_error *err);
int gs_dem_case_unit_vec(gs_cfg_node *map, const char *key, double out[3], gs_error *err);

/* The run's health (health.c): what the driver checks at t = 0 and after
 * every stretch of steps between events, so that a run that has gone wrong
 * stops saying where instead of writing tables from it. */
typedef struct {
  long inserted;     /* particles inserted so far (fill and feeds) */
  uint64_t lost0;    /* the engine's lost count when the run began */
} gs_dem_health;
/* Overlap of two particles, as a share of the smaller radius, above which a
 * run stops (GS_DEM_MAX_START_OVERLAP: at the start, before any step). */
#define GS_DEM_MAX_OVERLAP 0.5
#define GS_DEM_MAX_START_OVERLAP 0.1
void gs_dem_health_init(gs_dem_health *h, const gs_dem_case *c);
/* GS_ENUMERIC naming the step, time, particle(s) and figure when particles
 * overlap by more than the limit (start: at t = 0), a position or velocity
 * is not finite, or more than max_lost of the particles inserted have left
 * the box. */
int gs_dem_health_check(gs_dem_health *h, const gs_dem_case *c, int start, gs_error *err);
/* After the engine failed (rc): adds the first particle with a non-finite
 * position or velocity to the message, if there is one. */
int gs_dem_health_explain(const gs_dem_case *c, int rc, gs_error *err);

/* Insert into the case's simulation with inserter in's region, velocity and
 * class fractions (run_dem.c; the LIGGGHTS engine builds its initial bed with
 * it too, so both engines start from the same particles). */
int gs_dem_case_insert(gs_dem_case *c, gs_dem_inserter *in, long count, double mass, uint64_t *rng,
                       long *n, double *m, gs_error *err);

#endif
