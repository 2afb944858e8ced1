/* gransim — the sectional population-balance model.
 *
 * State: y[comp * ncells + cell] = number of particles represented by the
 * pivot of `cell` in compartment `comp` (a number, not a density).
 *
 * Ledger: the model also integrates, alongside y, the external exchange of
 * every volume coordinate's total (the dim axes, then the carried
 * quantities: nvol in all), per compartment:
 *   ledger[comp * 2*nvol + k]        = volume of coordinate k brought in (feed,
 *                                      transfer in, growth) minus taken out
 *                                      (transfer out, product), integrated in time;
 *   ledger[comp * 2*nvol + nvol + k] = volume of coordinate k lost through the
 *                                      grid boundaries (aggregates beyond the
 *                                      last pivot, fragments below the first).
 * Because the ledger is a linear functional of dy/dt, every integrator
 * (Runge–Kutta, BDF, Euler) preserves
 *     M1_k(y(t)) - M1_k(y(0)) = ledger_in_out_k(t) - ledger_lost_k(t)
 * to round-off.  The run checks this identity after every output step, which
 * turns any mechanism that creates or destroys mass into a hard error.
 *
 * Mechanisms (aggregation, breakage, growth, feed, transfer...) are
 * registered types (gs_mech_type) selected by name from the case file. */
#ifndef GRANSIM_PBM_H
#define GRANSIM_PBM_H

#include <assert.h>
#include <stddef.h>
#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_model gs_model;

/* ---- mechanisms ---------------------------------------------------------- */
typedef struct gs_mech_type {
  const char *name;    /* key used in case files: "aggregation", "breakage", ... */
  const char *summary; /* one line for `gransim list` */
  /* Read parameters from node (a map; "type" already consumed) and prepare
   * all tables.  Must call gs_cfg_check_unused on the maps it reads. */
  int (*create)(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err);
  /* Add this mechanism's rate to dydt (all compartments) and to dledger. */
  void (*rhs)(void *self, const gs_model *m, double t, const double *y, double *dydt,
              double *dledger);
  /* Optional: total number formation (birth) and depletion (death) rates per
   * compartment, for the 0.5 / 2 identities.  NULL if not meaningful. */
  void (*number_rates)(void *self, const gs_model *m, double t, const double *y, double *birth,
                       double *death);
  void (*free)(void *self);
  /* Optional: apply in place an approximate inverse of (I - gamma J_m) to z
   * (nstate numbers), J_m the Jacobian of this mechanism's rate at (t, y).
   * Mechanisms whose rates are stiff and cheap to invert (growth along an
   * axis: a bidiagonal J_m) provide it; the model composes them into the
   * preconditioner of implicit integrators.  NULL: treated as identity. */
  void (*precondition)(void *self, const gs_model *m, double t, const double *y, double gamma,
                       double *z);
  /* Optional: the first time > t at which this mechanism's rate jumps (the
   * start or end of a time window), or INFINITY.  The run stops there. */
  double (*next_switch)(void *self, double t);
} gs_mech_type;

typedef struct gs_mechanism {
  const gs_mech_type *type;
  void *self;
  char label[64]; /* "mechanisms[i] (type)" for messages */
} gs_mechanism;

const gs_mech_type *gs_mech_lookup(const char *name);
/* NULL-terminated list of all registered mechanism types. */
const gs_mech_type *const *gs_mech_types(void);

/* ---- the model ----------------------------------------------------------- */
/* Carried quantities: besides the number N of every cell, the state may hold
 * the total volume of some quantity carried by the particles of the cell
 * (seed 000: liquid and gas per solid bin), so a particle of cell c carries
 * Q_q[c] / N[c].  Every mechanism moves them with the particles. */
#define GS_MAX_CARRIED 2
#define GS_MAX_VOL (GS_MAX_DIM + GS_MAX_CARRIED)

struct gs_model {
  gs_grid grid;
  size_t nnum;    /* ncomp * ncells: the numbers, y[comp * ncells + cell] */
  size_t nstate;  /* nnum * (1 + ncarried): numbers, then carried totals (gs_model_carried) */
  size_t nledger; /* ncomp * 2 * nvol */
  int ncarried;
  char carried[GS_MAX_CARRIED][GS_NAME_LEN];
  /* Volume coordinates: the dim axes, then the carried quantities.  The
   * ledger holds per compartment nvol exchanged volumes, then nvol lost. */
  int nvol;
  gs_mechanism *mech;
  size_t nmech;
  int size_axes;  /* bitmask of axes summed into the granule volume for sizes (d10/d50/d90) */
  double *size_volume; /* ncells: granule volume used for diameters */
  char dir[1024];      /* directory of the case file, for relative paths in it ("." default) */
  /* 1 while an implicit integrator forms Jacobian-vector difference
   * quotients: mechanisms keep the discrete choices (cells taking part) of
   * their last evaluation instead of making them again from y. */
  int hold;
  /* 1 while an integrator evaluates f: mechanisms may then make their
   * discrete choices once per time value, so that the Newton iterations of
   * an implicit step (same t, several y) see one smooth function. */
  int in_integrator;
  /* Compartments this process evaluates, [comp_lo, comp_hi): all of them,
   * except under MPI, where each rank owns a contiguous block (the rates of
   * the others are left 0).  Transfer reads compartment comp_lo - 1 too. */
  size_t comp_lo, comp_hi;
  /* Numbers at or below this are integration noise (the solver's absolute
   * tolerance); mechanisms may skip cells holding no more than it. */
  double noise_floor;
  /* Where compartment c's state lies in the vectors mechanisms are given
   * (read and written only through gs_model_numbers, gs_model_carried and
   * gs_model_ledger): numbers at (c - view_lo) * ncells, carried totals from
   * view_carried, ledger at (c - view_lo) * 2 nvol.  The full layout:
   * view_lo 0, view_carried nnum.  Under MPI a rank's right-hand side works
   * on its packed local vector directly (view_lo its first compartment; no
   * copy into a full-size vector and back), the compartment before its
   * block, which transfer reads, in `halo` (numbers, then carried). */
  size_t view_lo, view_carried;
  const double *halo;
  /* The interval [switch_lo, switch_hi] being integrated, which holds no
   * switch (gs_model_next_switch) inside it, or switch_lo > switch_hi for
   * none.  Mechanisms active over a time window decide on or off at its
   * midpoint (gs_window_on), so that an evaluation at an end that is a
   * switch time sees the interval's rates: RK stages and the end-of-step
   * derivative fall on t + h exactly, and with the rate after the switch
   * there the step ending at the switch failed its error test at every
   * size above ~1e-4 s (the seed-000 example: 17 rejected steps creeping
   * up to the spray's start). */
  double switch_lo, switch_hi;
  /* NULL, or ncomp seconds: the work of each compartment whose cost depends
   * on its contents (aggregation's pair loop, breakage), which mechanisms
   * add with gs_model_clock/gs_model_charge; the MPI rebalancing reads it to
   * follow the costs as the granulation front moves downstream. */
  double *comp_seconds;
  /* Threads that evaluate different compartments at the same time
   * (per-compartment steps, src/run/compartment_steps.c) each pass their own
   * copy of the model, with its own view and slot in [0, nslots): mechanisms
   * keep one set of scratch per slot (nslots = OpenMP's maximum threads when
   * the model was built) and, given a slot, evaluate serially in it.  -1:
   * no slot (one caller; a mechanism may split a compartment over a team). */
  int slot, nslots;
};

/* Allocate an empty model around a grid (grid is moved in). */
int gs_model_init(gs_model *m, gs_grid *grid, gs_error *err);
/* Declare carried quantities (before any mechanism is added). */
int gs_model_set_carried(gs_model *m, const char *const *names, int n, gs_error *err);
/* Index of a carried quantity by name, or -1. */
int gs_model_carried_index(const gs_model *m, const char *name);
/* Numbers of compartment comp in state y (see gs_model.view_lo). */
static inline double *gs_model_numbers(const gs_model *m, double *y, size_t comp) {
  return y + (comp - m->view_lo) * m->grid.ncells;
}
static inline const double *gs_model_numbers_c(const gs_model *m, const double *y, size_t comp) {
  return y + (comp - m->view_lo) * m->grid.ncells;
}
/* Totals of carried quantity q in compartment comp of state y. */
static inline double *gs_model_carried(const gs_model *m, double *y, size_t comp, int q) {
  return y + m->view_carried +
         ((comp - m->view_lo) * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
static inline const double *gs_model_carried_c(const gs_model *m, const double *y, size_t comp,
                                               int q) {
  return y + m->view_carried +
         ((comp - m->view_lo) * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
/* The compartment before comp, which flows into it (transfer): in y, or
 * under MPI the halo when comp is the first of the rank's block (numbers
 * for q < 0, else carried quantity q). */
static inline const double *gs_model_upstream_c(const gs_model *m, const double *y, size_t comp,
                                                int q) {
  assert(!(comp == m->view_lo && m->view_lo > 0) || m->halo); /* a view needs its halo */
  if (comp == m->view_lo && m->view_lo > 0)
    return m->halo + (q < 0 ? 0 : (1 + (size_t)q) * m->grid.ncells);
  return q < 0 ? gs_model_numbers_c(m, y, comp - 1) : gs_model_carried_c(m, y, comp - 1, q);
}
/* Ledger of compartment comp: [0, nvol) exchanged, [nvol, 2 nvol) lost. */
static inline double *gs_model_ledger(const gs_model *m, double *ledger, size_t comp) {
  return ledger + (comp - m->view_lo) * 2 * (size_t)m->nvol;
}
/* Name of volume coordinate k (axis or carried quantity). */
const char *gs_model_vol_name(const gs_model *m, int k);
/* Held volume of coordinate k in compartment comp. */
double gs_model_held(const gs_model *m, const double *y, size_t comp, int k);
/* The rate k (1/s) at which compartment comp's particles flow into the next
 * one (the sum over the model's transfer mechanisms; 0 without any).  The
 * inflow of comp + 1 is k times comp's numbers and carried totals. */
double gs_model_transfer_rate(const gs_model *m, size_t comp);
/* Add a mechanism by type name, reading its parameters from node. */
int gs_model_add_mechanism(gs_model *m, const char *type, gs_cfg_node *node, const char *label,
                           gs_error *err);
void gs_model_free(gs_model *m);

/* Timing of one compartment's work for m->comp_seconds (no clock is read
 * when it is NULL): start = gs_model_clock(m); ...; gs_model_charge(m, comp, start). */
double gs_model_seconds(void);
static inline double gs_model_clock(const gs_model *m) {
  return m->comp_seconds ? gs_model_seconds() : 0;
}
static inline void gs_model_charge(const gs_model *m, size_t comp, double start) {
  if (m->comp_seconds) m->comp_seconds[comp] += gs_model_seconds() - start;
}

/* Full right-hand side: dydt (nstate) and dledger (nledger) are overwritten. */
void gs_model_rhs(const gs_model *m, double t, const double *y, double *dydt, double *dledger);
/* The first time > t at which some mechanism's rate jumps, or INFINITY. */
double gs_model_next_switch(const gs_model *m, double t);
/* Helper for mechanisms active in [start, end). */
double gs_window_next_switch(double start, double end, double t);
/* 1 if a mechanism active in [start, end) is on for an evaluation at t: at
 * t itself, or, while an interval m->switch_lo..switch_hi is set, at its
 * midpoint. */
int gs_window_on(const gs_model *m, double start, double end, double t);
/* 1 if some mechanism provides a preconditioner. */
int gs_model_has_preconditioner(const gs_model *m);
/* Approximate solution of (I - gamma J) z = r over the numbers and the
 * ledger (n = nstate + nledger): the product of the mechanisms' inverses,
 * identity on the ledger. */
void gs_model_precondition(const gs_model *m, double t, const double *y, double gamma,
                           const double *r, double *z);

/* ---- moments and size statistics ---------------------------------------- */
typedef struct gs_summary {
  double m0;                  /* number */
  double m1;                  /* total granule volume  sum N v */
  double m2;                  /* sum N v^2 */
  double d10, d50, d90;       /* volume-weighted percentiles of the volume-equivalent diameter */
  double mean[GS_MAX_VOL];    /* number-mean of each volume coordinate (axes, carried) */
  double total[GS_MAX_VOL];   /* total volume of each: sum N x_k, or the carried total */
} gs_summary;

/* Statistics of compartment comp of state y. */
void gs_summarize(const gs_model *m, const double *y, size_t comp, gs_summary *s);
/* Mixed moment sum N x_0^p0 x_1^p1 x_2^p2 over compartment comp. */
double gs_moment(const gs_model *m, const double *y, size_t comp, const int *powers);

#ifdef __cplusplus
}
#endif
#endif
