/* Internal state of the gas phase (src/cfd).  Uniform Cartesian cells,
 * i fastest; face arrays per axis a hold (n[a] + 1) faces along a, so the
 * x faces are indexed i + (n0 + 1) * (j + n1 * k), and so on. */
#ifndef GRANSIM_CFD_INTERNAL_H
#define GRANSIM_CFD_INTERNAL_H

#include <stdio.h>

#include "gransim/cfd.h"

typedef struct gs_cfd_psolver gs_cfd_psolver;

/* One particle's interpolation stencil: 8 (index, weight) pairs per lattice. */
typedef struct {
  long idx[8];
  double w[8];
} gs_cfd_stencil;

struct gs_cfd {
  gs_cfd_params prm;
  int n[3];
  double h[3], vol;
  size_t ncell, nface[3];
  double *eps, *eps_old;  /* cells */
  double *p;              /* cells */
  double *u[3];           /* interstitial velocity on the faces of each axis */
  double *ef[3];          /* void fraction on the faces (mean of the two cells, or the one) */
  double *k[3], *kv[3];   /* drag: sum of w beta / V, and sum of w beta v / V, per face */
  double *a[3];           /* eps_f / A_f: velocity per pressure gradient, per face */
  double *dg[3], *ex[3];  /* convection and viscous stress per face: the implicit (diagonal)
                             coefficient and the explicit part (neighbours at step n) */
  double *nb, *diag;      /* the pressure equation: 6 couplings and the outlet's diagonal per cell */
  double *rhs;            /* cells */
  gs_cfd_psolver *ps;
  long steps;
  double t;
  int its;
  double res;
  /* per particle (by id): the force held until the next step */
  double *force;
  long force_cap;
  /* per particle of the current step (view order): beta, stencils */
  double *beta, *epsp;    /* drag coefficient and void fraction at each particle */
  gs_cfd_stencil *st_cell, *st_face[3];
  size_t pcap;
  double ex_part[3], ex_gas[3];
  /* coupling to a DEM */
  gs_dem *dem;
  long dem_steps_per_gas, dem_count;
  /* fewest particles for which the per-particle loops use threads: the
   * DEM's dem.threads_from once attached (one setting for both phases) */
  size_t par_min;
  int started;
  int failed;
  gs_error fail;
  /* outputs (output.c) */
  char out_dir[4096];
  FILE *csv;
  double out_every, vtk_every, next_out, next_vtk;
  double *vtk_t;
  int nvtk;
};

/* gas.c */
int gs_cfd_gas_step(gs_cfd *g, gs_error *err);
/* transport.c: dg and ex of every face from u, eps and ef (boundary faces
 * set first). */
void gs_cfd_transport(gs_cfd *g);
/* Fill ef from eps. */
void gs_cfd_face_void_fractions(gs_cfd *g);
size_t gs_cfd_face_index(const gs_cfd *g, int axis, int i, int j, int k);
/* The face of axis a is moved by the gas (not a wall or the inlet). */
int gs_cfd_face_solved(const gs_cfd *g, int axis, int i, int j, int k);

/* pressure.c: the pressure equation with hypre's structured solvers */
gs_cfd_psolver *gs_cfd_pressure_create(const int n[3], gs_error *err);
void gs_cfd_pressure_free(gs_cfd_psolver *ps);
/* Solve sum_f coef_f (p_c - p_nb) + diag_c p_c = rhs_c (coefficients per
 * cell: 6 neighbour couplings -x +x -y +y -z +z, 0 where no neighbour, and
 * the extra diagonal of the outlet).  x: start in, solution out. */
int gs_cfd_pressure_solve(gs_cfd_psolver *ps, const double *nb, const double *diag,
                          const double *rhs, double *x, double tol, int max_iter, int *its,
                          double *res);

/* output.c: the rows and field files due at the current time */
int gs_cfd_write_outputs(gs_cfd *g, const gs_dem_view *v, gs_error *err);

/* particles.c: trilinear weights of point x on the lattice of cell centres
 * (axis = -1) or of the faces of one axis. */
void gs_cfd_stencil_at(const gs_cfd *g, int axis, const double x[3], gs_cfd_stencil *s);

#endif
