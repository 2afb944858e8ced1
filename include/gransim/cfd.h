/* gransim — gas phase of a fluid bed coupled to the embedded DEM (unresolved
 * CFD-DEM, src/cfd).
 *
 * The gas is incompressible and volume-averaged (model A of Zhou et al. 2010):
 * void fraction eps from the particles on a uniform Cartesian grid over a box,
 * interstitial velocity u on the cell faces (staggered), pressure p at the
 * cell centres.  Gas enters through the plane z = lo[2] at a superficial
 * velocity (the distributor), leaves through z = hi[2] at p = 0, and the four
 * side planes are no-slip walls.  Each gas step is a projection: the
 * momentum predictor (drag implicit, first-order upwind convection and
 * viscous stress with their diagonals implicit), then a pressure equation solved
 * with hypre (PCG preconditioned by PFMG multigrid).  docs/models.md, section
 * "CFD-DEM", has the equations; docs/case-files.md the `gas:` keys.
 *
 * The DEM takes the drag and pressure-gradient forces through gs_dem_hooks:
 * they are computed once per gas step and held over the DEM steps between,
 * so the momentum the gas loses to drag is exactly what the particles gain.
 * Units are SI.  Functions return GS_OK or an error code with err filled. */
#ifndef GRANSIM_CFD_H
#define GRANSIM_CFD_H

#include <stddef.h>

#include "gransim/dem.h"
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A drag closure: the coefficient beta [kg/s] of one particle, whose drag is
 * beta (u - v), from the local void fraction and the slip speed. */
typedef struct {
  double eps;  /* void fraction at the particle, (0, 1] */
  double d;    /* particle diameter [m] */
  double slip; /* |u - v|, interstitial gas velocity minus particle velocity [m/s] */
  double rho;  /* gas density [kg/m^3] */
  double mu;   /* gas viscosity [Pa s] */
} gs_cfd_drag_in;
typedef struct {
  const char *name;
  const char *summary; /* one line for `gransim list` */
  double (*beta)(const gs_cfd_drag_in *in);
} gs_cfd_drag_type;
/* NULL-terminated registry: di_felice, gidaspow (src/cfd/drag.c). */
extern const gs_cfd_drag_type *const gs_cfd_drags[];

/* How the gas and the particles act on each other. */
enum {
  GS_CFD_TWO_WAY = 0, /* drag on the particles and its reaction on the gas, eps from the particles */
  GS_CFD_ONE_WAY = 1  /* the gas moves the particles but feels neither them nor their volume */
};

typedef struct {
  double lo[3], hi[3];   /* the gas domain, a box [m] */
  int n[3];              /* cells per axis */
  double rho, mu;        /* gas density [kg/m^3] and viscosity [Pa s] */
  double u_inlet;        /* superficial gas velocity through the plane z = lo[2] [m/s] */
  double dt;             /* gas time step = coupling interval [s]; a whole number of DEM steps */
  double gravity[3];     /* [m/s^2] (the gas has weight too) */
  const gs_cfd_drag_type *drag;
  int coupling;          /* GS_CFD_TWO_WAY / GS_CFD_ONE_WAY */
  double tol;            /* relative residual of the pressure solve (0: 1e-10) */
  int max_iter;          /* its iteration limit (0: 500) */
} gs_cfd_params;

typedef struct gs_cfd gs_cfd;

gs_cfd *gs_cfd_create(const gs_cfd_params *p, gs_error *err);
/* Frees g and removes its hooks from the DEM it is attached to, so free g
 * before that DEM. */
void gs_cfd_free(gs_cfd *g);

/* Couple g to the DEM d (installs d's hooks; d's time step must divide the
 * gas step).  The first gas step is taken with the particles present at
 * d's next step; then one every dt of gas time.  Refuses a grid whose cells
 * are smaller than 2 or larger than 50 diameters of the particles present
 * (checked again as particles enter) and a DEM step above 40 % of the
 * Rayleigh time. */
int gs_cfd_attach(gs_cfd *g, gs_dem *d, gs_error *err);

/* One coupling step on the particles of v (what the hooks call): void
 * fraction, drag coefficients, the gas step, the forces on the particles.
 * Stops, naming the step, cell or particle and the figure, on a particle
 * outside the domain, a void fraction <= 0, a time step above the gas or
 * particle limit, a cell too small or too large for the particles, or a
 * pressure solve that does not converge. */
int gs_cfd_step(gs_cfd *g, const gs_dem_view *v, gs_error *err);

/* Write DIR/gas.csv (a row every `every` seconds of gas time) and, if
 * vtk_every > 0, the gas fields as DIR/vtk/gas_NNNNNN.vtr with the ParaView
 * series DIR/gas.pvd (DIR must exist). */
int gs_cfd_set_output(gs_cfd *g, const char *dir, double every, double vtk_every, gs_error *err);

/* The gas phase of a DEM case from its `gas` section (docs/case-files.md),
 * attached to the case's simulation, writing its outputs into out_dir
 * (NULL: none, for --check).  NULL with err set on bad input. */
gs_cfd *gs_cfd_case_create(gs_dem_case *c, const char *out_dir, gs_error *err);

/* Change the inlet's superficial velocity from the next gas step on. */
void gs_cfd_set_inlet_velocity(gs_cfd *g, double u);

/* ---- results (valid until the next step) -------------------------------- */
void gs_cfd_dims(const gs_cfd *g, int n[3], double h[3]);
long gs_cfd_steps(const gs_cfd *g);
double gs_cfd_time(const gs_cfd *g);
/* Cell fields, index i + n0*(j + n1*k): void fraction, pressure [Pa] (gauge,
 * 0 at the outlet plane), the gas velocity at the cell centre (mean of the two
 * faces per axis, interstitial) [m/s]. */
const double *gs_cfd_void_fraction(const gs_cfd *g);
const double *gs_cfd_pressure(const gs_cfd *g);
void gs_cfd_cell_velocity(const gs_cfd *g, size_t cell, double u[3]);
/* Area-mean pressure at the inlet plane [Pa]: the lowest cells' mean (the
 * drag of the particles in them acts on the faces above). */
double gs_cfd_inlet_pressure(const gs_cfd *g);
/* Momentum exchanged by drag in the last step, as rates [N]: the sum of the
 * drag forces on the particles, and what the gas lost (the sinks of its
 * momentum equation, and the part at wall and inlet faces where the gas does
 * not move).  Equal to round-off. */
void gs_cfd_exchange(const gs_cfd *g, double particles[3], double gas[3]);
/* The force [N] the gas exerts on particle id (drag + pressure gradient) as
 * held now; 0 for a particle not yet seen. */
void gs_cfd_particle_force(const gs_cfd *g, long id, double f[3]);
/* Iterations and relative residual of the last pressure solve. */
void gs_cfd_solver_stats(const gs_cfd *g, int *iterations, double *residual);

/* ---- validation (src/cfd/validate.c; `gransim validate-cfd`) ----------- */
/* One simulated figure against its reference. */
typedef struct {
  char name[96];    /* what was compared */
  double got, want; /* simulated and reference values */
  double tol;       /* the relative tolerance it is held to */
  char unit[16];
  char detail[200]; /* the set-up in a few words */
} gs_cfd_check;
/* A glass sphere (d = 0.3 mm) falling from rest in still air (coupling
 * GS_CFD_ONE_WAY or GS_CFD_TWO_WAY): its speed after 1.5 s against the
 * terminal velocity of the closure's single-sphere drag coefficient
 * (Dallavalle for di_felice, Schiller-Naumann for gidaspow), 2 %. */
int gs_cfd_check_terminal(const char *drag, int coupling, gs_cfd_check *out, gs_error *err);
/* A packed bed of 480 spheres (d = 2 mm, simple cubic) in a column: the
 * pressure drop at superficial velocity u against Ergun (1952) with the
 * bed's void fraction, 5 %. */
int gs_cfd_check_ergun(const char *drag, double u, gs_cfd_check *out, gs_error *err);

/* A bed of 600 spheres (d = 2 mm, 1030 kg/m3) poured into a 10 mm x 10 mm
 * column, the gas raised in steps: the minimum fluidisation velocity where
 * the packed-bed branch of the pressure drop (a U + b U^2 through the points
 * below 85 % of the bed weight) reaches the weight, against Wen & Yu (1966),
 * 10 %.  out[0] that; out[1..3] the bed heights at 1.5, 2 and 2.5 U_mf (Wen
 * & Yu) against the packed height (want: the previous height; each must be
 * higher). */
int gs_cfd_check_fluidisation(gs_cfd_check out[4], gs_error *err);

/* The qualitative results of Sen et al. (2014) on the sprayed lab bed of
 * examples/fluid-bed-cfd.yaml (src/cfd/validate_sen.c; three runs of 0.8 s,
 * a few minutes): out[0] the speed percentile ratio p90/p10 at 0.7 s against
 * GS_SEN_SPEED_RATIO; out[1] the mean liquid content l/(s+l) under the nozzle
 * over that elsewhere, against GS_SEN_ZONE_RATIO; out[2] the mean diameter at
 * 8 g/s against 4 g/s; out[3] at 1.8 m/s against 1.2 m/s.  Each is a trend
 * (tol 0): got must exceed want. */
#define GS_SEN_SPEED_RATIO 3.0
#define GS_SEN_ZONE_RATIO 5.0
int gs_cfd_check_sen(gs_cfd_check out[4], gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
