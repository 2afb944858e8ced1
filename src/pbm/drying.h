/* Drying of granules in a fluid bed (Chaudhury 2015, eqs. 2.19-2.22):
 * evaporation from each granule's liquid driven by the humidity difference
 * between saturated air at the bed temperature and the bed's air, with the
 * bed's temperature and humidity fixed or from its quasi-steady balances.
 * The mechanism `drying` (growth.c: negative growth along the liquid axis)
 * takes its per-cell rates from here. */
#ifndef GRANSIM_PBM_DRYING_H
#define GRANSIM_PBM_DRYING_H
#include "gransim/pbm.h"

/* Saturation humidity (kg water / kg dry air) at temperature T (K) and total
 * pressure P (Pa): x = 0.622 p / (P - p), p the vapour pressure of water from
 * Buck's (1996) equation (0-100 C). */
double gs_saturation_humidity(double T, double P);
/* The vapour pressure of water (Pa) at T (K), Buck (1996). */
double gs_vapour_pressure(double T);

/* The bed of `drying` with key `bed`: inlet air of a given temperature,
 * humidity and flow; the outlet humidity and the bed temperature (= the
 * outlet's) follow from Chaudhury's (2015) humidity and heat balances, eqs.
 * 2.18 and 2.24, with their accumulation terms dropped (quasi-steady: the
 * air's hold-up and the bed's heat capacity relax in seconds). */
typedef struct gs_bed {
  double Tin, xin, air, loss; /* inlet temperature (K), humidity, dry air flow (kg/s), heat loss (W) */
  double Tref, dH, cpa, cpv;  /* spray temperature (the reference), latent heat, heat capacities */
  double P, k0, rho_l;        /* pressure; gamma eta 2 pi D rho_air (kg/(m s)); liquid density */
  double *d;                  /* ncells: diameter of the granules that dry (0 at the first liquid pivot) */
} gs_bed;

/* Read drying's keys from node (not `type`, `liquid_axis`, `start`, `end`).
 * Fixed bed conditions: G[c] (ncells) = the rate of change of a granule's
 * liquid volume in cell c (<= 0), *bed = NULL.  With `bed`: *bed allocated
 * (free with gs_bed_free), rates from gs_bed_rates. */
int gs_drying_read(gs_cfg_node *node, const gs_model *m, int liquid, double *G, gs_bed **bed,
                   gs_error *err);
void gs_bed_free(gs_bed *b);
/* The mass-transfer keys shared by `drying` and `fluid_bed` (correction,
 * wetted_fraction, diffusivity, air_density, liquid_density, pressure):
 * *k0 = gamma eta 2 pi D rho_air (kg/(m s)), so that a granule of diameter d
 * evaporates k0 d (x_sat - x_air) kg/s. */
int gs_drying_transfer_read(gs_cfg_node *node, double *k0, double *rho_l, double *P, gs_error *err);
/* Per cell (ncells, allocated): the diameter of the granules that dry, 0 at
 * the first pivot of the liquid axis. */
double *gs_drying_diameters(const gs_model *m, int liquid, gs_error *err);
/* Bed temperature *T and outlet humidity *x for wet = sum N d over the
 * granules that dry; returns the evaporation (kg/s). */
double gs_bed_solve(const gs_bed *b, double wet, double *T, double *x);
/* Per-cell liquid rates of one compartment's numbers N into G (ncells);
 * 0 when nothing dries.  *drive: the compartment's humidity difference
 * x_sat(T) - x_out, solved afresh and stored, or, when hold is set and it
 * holds one (not NaN), kept: an implicit integrator's Jacobian-vector
 * difference quotients then see rates linear in N, not the bisection's
 * last-bit steps, and its Newton updates keep the volume balance. */
int gs_bed_rates(const gs_bed *b, size_t ncells, const double *N, int hold, double *drive,
                 double *G);
#endif
