/* Wet granulation inside the embedded DEM (issue 27, after Sen et al. 2014):
 * binder droplets sprayed from a nozzle cone and absorbed by the particles
 * they touch (spray.c), and the population balance run on the DEM particles
 * themselves: solid x liquid classes, collisions of wetted particles that
 * aggregate by a registered success rule (granulation.c, success_rules.c).
 * The case keys `spray:` and `granulation:` are read in case_wet.c and the
 * run driver calls wet_run.c.  docs/models.md, "Spray and granulation in the
 * DEM", has the equations and decisions. */
#ifndef GRANSIM_DEM_WET_H
#define GRANSIM_DEM_WET_H

#include <gsl/gsl_rng.h>
#include <stdio.h>

#include "dem/dem_case.h"
#include "dem/dem_internal.h"

/* ---- spray (spray.c) ---------------------------------------------------- */
typedef struct {
  double point[3], axis[3]; /* nozzle exit and unit axis of the cone */
  double half_angle;        /* [rad], in (0, pi/2] */
  double diameter;          /* droplet diameter [m] */
  double mass_rate;         /* liquid [kg/s] */
  double density;           /* liquid [kg/m^3] */
  double speed;             /* droplet exit speed [m/s] */
  double start, end;        /* spraying window [s] */
} gs_dem_nozzle;

typedef struct {
  double x[3], v[3];
} gs_dem_drop;

/* Liquid volumes [m^3]: every injected droplet is in exactly one place. */
typedef struct {
  double injected, on_particles, airborne, on_walls, left;
} gs_dem_liquid_ledger;

/* An acceleration on a droplet besides gravity (the gas phase's drag, for
 * one): a[3] at position x and velocity v [m/s^2]. */
typedef void (*gs_dem_drop_accel)(void *ctx, const double x[3], const double v[3], double a[3]);

typedef struct {
  gs_dem_nozzle noz;
  gs_dem_drop_accel accel;  /* NULL: gravity only */
  void *accel_ctx;
  double vd, md, rd;        /* droplet volume, mass, radius */
  double e1[3], e2[3];      /* unit vectors normal to the axis */
  gsl_rng *rng;
  gs_dem_drop *drop;
  size_t n, cap;
  long injected, absorbed, walls, left; /* droplets */
} gs_dem_spray;

int gs_dem_spray_init(gs_dem_spray *s, const gs_dem_nozzle *noz, uint64_t seed, gs_error *err);
void gs_dem_spray_free(gs_dem_spray *s);
/* Direction of a droplet from two uniform numbers in [0,1): uniform over the
 * solid angle of the cone (cos theta uniform in [cos half_angle, 1]). */
void gs_dem_spray_direction(const gs_dem_spray *s, const double u[2], double dir[3]);
/* One DEM step's worth for the droplets, after the particles' step: inject
 * those due by the current time, move all ballistically, and settle those
 * touching a particle (absorbed), a wall, an outlet or the box's edge. */
int gs_dem_spray_step(gs_dem_spray *s, gs_dem *d, gs_error *err);
/* Credit particle i with a droplet of volume vol and mass mass moving at v
 * (momentum conserved; the radius stays that of the solid). */
void gs_dem_absorb(gs_dem *d, size_t i, double vol, double mass, const double v[3]);
void gs_dem_spray_ledger(const gs_dem_spray *s, const gs_dem *d, gs_dem_liquid_ledger *l);

/* ---- success rules (success_rules.c) ------------------------------------ */
/* The state of one partner of a collision, for a rule. */
typedef struct {
  double m, r, vs, vl;
} gs_dem_partner;

typedef struct gs_dem_rule gs_dem_rule;
typedef struct {
  const char *name;
  int (*read)(gs_cfg_node *n, gs_dem_rule *r, gs_error *err);
  /* 1 if the pair aggregates; vn is the normal approach speed at contact
   * onset [m/s], u a uniform number in [0,1) drawn for every collision */
  int (*success)(const gs_dem_rule *r, const gs_dem_partner *a, const gs_dem_partner *b,
                 double vn, double u);
} gs_dem_rule_type;

struct gs_dem_rule {
  const gs_dem_rule_type *type;
  double efficiency, lc_min; /* constant: psi0 and the least liquid content */
  int either;                /* constant: one wet partner suffices */
  double viscosity, restitution, asperity; /* stokes */
};

extern const gs_dem_rule_type *const gs_dem_rule_types[];
/* Liquid content l / (s + l) of a partner (0 for no volume). */
double gs_dem_liquid_content(const gs_dem_partner *p);

/* ---- granulation (granulation.c) ---------------------------------------- */
typedef struct {
  double every;             /* Delta t_PBM [s] */
  long every_k;             /* in steps */
  gs_dem_rule rule;
  double ds, dl;            /* class widths of solid and liquid volume [m^3] */
  int ns, nl;               /* numbers of classes; the last of each is open */
  gsl_rng *rng;
  FILE *f_sum, *f_cls, *f_col;
  char path_sum[4200], path_cls[4200], path_col[4200];
  double t_last;            /* time of the previous update */
  long updates;
  uint64_t collisions, aggregations; /* totals */
  int *cls;                 /* class of each live particle at an update */
  int *idx;                 /* particle index by id (-1: not live) */
  uint8_t *used;            /* aggregated in this update */
  size_t idx_cap, cls_cap;
  double *ncoll, *nagg;     /* per class pair */
  double *kn, *kexp;        /* per pair of solid classes, over the run: collisions
                               and the exposure, the sum of F_a F_b dt over the updates */
  char path_kernel[4200];
  /* aggregates whose contact radius still grows to their size (growth.c) */
  long growth_k;            /* steps the growth takes (0: the full size at once) */
  struct gs_dem_growing *grow;
  size_t ngrow, grow_cap;
} gs_dem_granulation;

/* Class (0 .. ns*nl-1) of a particle of solid volume vs and liquid vl:
 * solid class round(vs/ds) in 1..ns, liquid class round(vl/dl) in 0..nl-1,
 * the last of each taking everything above. */
int gs_dem_granulation_class(const gs_dem_granulation *g, double vs, double vl);
int gs_dem_granulation_start(gs_dem_granulation *g, gs_dem *d, const char *dir, uint64_t seed,
                             gs_error *err);
/* Aggregate the collisions logged since the last update; write the rows. */
int gs_dem_granulation_update(gs_dem_granulation *g, gs_dem *d, gs_error *err);
int gs_dem_granulation_finish(gs_dem_granulation *g, gs_error *err);
void gs_dem_granulation_free(gs_dem_granulation *g);
/* Merge particle j into particle i: summed solid, liquid and mass, at the
 * centre of mass with the momentum-conserving velocity; j is marked dead. */
void gs_dem_merge(gs_dem *d, size_t i, size_t j);

/* ---- aggregate growth (growth.c) ------------------------------------------ */
typedef struct gs_dem_growing {
  long id, step0;
  double r0, r1;            /* contact radius at the merge and the aggregate's own */
} gs_dem_growing;
/* Particle i was just merged with a partner: its contact radius restarts at
 * r0 and grows linearly to its size over g->growth_k steps. */
int gs_dem_growth_add(gs_dem_granulation *g, gs_dem *d, size_t i, double r0, gs_error *err);
/* Advance the growing radii (every growth_k/10 steps, each time followed by
 * a neighbour-list rebuild, so no contact is missed). */
void gs_dem_growth_step(gs_dem_granulation *g, gs_dem *d);

/* ---- case keys and driver (case_wet.c, wet_run.c) ------------------------ */
typedef struct gs_dem_wet {
  int has_spray, has_gran;
  gs_dem_nozzle noz;
  gs_dem_spray spray;
  gs_dem_granulation gran;
  FILE *f_ledger;
  char path_ledger[4200];
  double tol;               /* relative tolerance of the liquid ledger */
  char dir[4096];           /* the run's output folder (spray_classes.csv) */
} gs_dem_wet;

/* spray_classes.c: the liquid the particles of each size class absorbed,
 * against the shares of the absorption law (De et al. 2025: in proportion to
 * granule volume) and of a law in proportion to surface, written to
 * DIR/spray_classes.csv at the end of a run with a spray. */
typedef struct {
  double particles;  /* live particles of the class */
  double solid;      /* their solid volume [m^3] */
  double area;       /* their surface, 4 pi r^2 each [m^2] */
  double liquid;     /* the liquid they hold [m^3] */
} gs_dem_spray_class;
/* The per-class sums of the live particles (out: nclass entries). */
void gs_dem_spray_classes(const gs_dem *d, int nclass, gs_dem_spray_class *out);
int gs_dem_spray_classes_write(const gs_dem_case *c, const char *dir, gs_error *err);

#endif
