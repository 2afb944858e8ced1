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
#include <stdio.h>
#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_model gs_model;

typedef struct gs_eval gs_eval;

/* ---- mechanisms ---------------------------------------------------------- */
/* A mechanism provides the rates of one compartment: the model owns the loop
 * over compartments, the threads and the timing (gs_model_rhs), so a
 * mechanism's author needs to know one compartment, the ledger and the time
 * window (gs_window_on), nothing about MPI blocks, views or threads.  Vectors
 * are reached through gs_eval_numbers/carried/upstream/ledger. */
typedef struct gs_mech_type {
  const char *name;    /* key used in case files: "aggregation", "breakage", ... */
  const char *summary; /* one line for `gransim list` */
  /* Read parameters from node (a map; "type" already consumed) and prepare
   * all tables.  Must call gs_cfg_check_unused on the maps it reads. */
  int (*create)(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err);
  /* Add compartment comp's rates to dydt and dledger.  Writes only comp's
   * entries (reads comp's state, and the compartment upstream through
   * gs_eval_upstream_c), so compartments may be evaluated at once. */
  void (*rates)(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                const double *y, double *dydt, double *dledger);
  /* Optional: compartment comp's total number formation (birth) and
   * depletion (death) rates, for the 0.5 / 2 identities.  NULL if not
   * meaningful. */
  void (*number_rates)(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                       const double *y, double *birth, double *death);
  void (*free)(void *self);
  /* Optional: apply in place to compartment comp's numbers of z, and to its
   * ledger entries zledger (laid out as in rates), an approximate inverse of
   * (I - gamma J_m), J_m the Jacobian of this mechanism's rate at (t, y).
   * Mechanisms whose rates are stiff and cheap to invert (growth along an
   * axis: a bidiagonal J_m) provide it; the model composes them into the
   * preconditioner of implicit integrators.  The ledger rows must be solved
   * with the numbers' (an inverse that conserves volume as the rates do):
   * otherwise each inexact Krylov solve breaks the volume balance.  NULL:
   * treated as identity. */
  void (*precondition)(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                       const double *y, double gamma, double *z, double *zledger);
  /* Optional: the first time > t at which this mechanism's rate jumps (the
   * start or end of a time window), or INFINITY.  The run stops there. */
  double (*next_switch)(void *self, double t);
  /* Optional, for flow between compartments: the rate k (1/s) at which
   * compartment comp's particles flow into comp + 1 (the inflow of comp + 1
   * is k times comp's numbers and carried totals).  Per-compartment steps
   * need it to hand each compartment's discharge to the next. */
  double (*outflow_rate)(void *self, size_t comp);
  /* Pages (GS_APART) it keeps per compartment, for the memory a case is
   * estimated to need before it is built (limits.memory_gb). */
  int pages_per_compartment;
  /* Optional, for the same estimate: bytes it will hold for the grid as a
   * whole (tables over pairs of cells), from its case node, before it is
   * built.  NULL: none. */
  double (*grid_bytes)(gs_cfg_node *node, const gs_grid *g);
  /* 1: its rates read the state of any compartment (an exchange network),
   * not only comp's and the one upstream, so it runs with shared steps on
   * one process (the other strategies pack compartments apart). */
  int couples_all;
  /* ---- scalar state (optional) ----
   * A mechanism may carry scalars per compartment in the ODE state (a fluid
   * bed's enthalpy and vapour, and the integrals of its flows, which make
   * its balances checkable like the volume ledger).  Its scalars are
   * m->nscalar as create sees it, onwards (gs_eval_scalars); nscalars says
   * how many it took (called once after create). */
  int (*nscalars)(void *self);
  /* Compartment comp's scalars s at the start, from the initial state y
   * (full layout), and the absolute accuracy each is integrated to (its
   * absolute tolerance, in its own unit). */
  void (*initial)(void *self, const gs_model *m, size_t comp, const double *y, double *s,
                  double *accuracy);
  /* Summary columns it adds (summary.csv, result.h5 /summary), ended by
   * {NULL}, and their values for compartment comp of the full state y. */
  const struct gs_mech_column *columns;
  void (*report)(void *self, const gs_model *m, size_t comp, double t, const double *y,
                 double *values);
  /* Its own balances in compartment comp of the full state y: the largest
   * relative error, and in msg (n bytes) what it is. */
  double (*balance)(void *self, const gs_model *m, size_t comp, const double *y, char *msg,
                    size_t n);
  /* Optional: what the run log and result.h5 should say about how it was
   * set up (a choice made for the case, e.g. aggregation's low-rank kernel
   * form and its rank), written into msg (n bytes); 0 when there is nothing. */
  int (*describe)(void *self, char *msg, size_t n);
} gs_mech_type;

typedef struct gs_mech_column {
  const char *name, *unit; /* a summary column: name, SI unit ("1": dimensionless) */
} gs_mech_column;

typedef struct gs_mechanism {
  const gs_mech_type *type;
  void *self;
  char label[64]; /* "mechanisms[i] (type)" for messages */
  size_t scalar_first; /* its first scalar in a compartment's (m->nscalar at create) */
  int nscalar;         /* how many */
} gs_mechanism;

const gs_mech_type *gs_mech_lookup(const char *name);
/* NULL-terminated list of all registered mechanism types. */
const gs_mech_type *const *gs_mech_types(void);
/* The sharing rules of sprayed liquid (share.type of liquid_addition and
 * spray), one "  name  summary" line each (for `gransim list`). */
void gs_liquid_share_list(FILE *fp);

/* ---- the model ----------------------------------------------------------- */
/* Carried quantities: besides the number N of every cell, the state may hold
 * the total volume of some quantity carried by the particles of the cell
 * (Sampat et al. 2018: liquid and gas per solid bin), so a particle of cell c carries
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
  /* Scalars per compartment that mechanisms carry (gs_mech_type.nscalars),
   * in the state after the carried totals: y[scalar_at + comp * nscalar + i]
   * (scalar_at = nnum (1 + ncarried); nstate includes them).  They run with
   * shared steps on one process only (the other strategies pack
   * compartments without them). */
  size_t nscalar, scalar_at;
  gs_mechanism *mech;
  size_t nmech;
  int size_axes;  /* bitmask of axes summed into the granule volume for sizes (d10/d50/d90) */
  double *size_volume; /* ncells: granule volume used for diameters */
  char dir[1024];      /* directory of the case file, for relative paths in it ("." default) */
  /* The case's distributions (initial, feeds) as asked and as the grid holds
   * them, and the tolerance they are held to (distribution.h).  Behind a
   * pointer: feeds report while they are built from a const model. */
  struct gs_disc_log *disc;
  /* Scratch sets each mechanism keeps (OpenMP's maximum threads when the
   * model was built): an evaluation context's slot picks one, so that
   * threads evaluating different compartments at once never share scratch. */
  int nslots;
};

/* ---- evaluation context -------------------------------------------------- */
/* Who evaluates the rates, of which compartments, where the state lies and
 * over which interval: everything that changes from one evaluation to the
 * next, kept out of the model so that the model is never mutated during a
 * run and several evaluators (threads, MPI ranks) share one model. */
struct gs_eval {
  /* Compartments evaluated, [comp_lo, comp_hi): all of them, or under MPI
   * the rank's block, or one under per-compartment steps. */
  size_t comp_lo, comp_hi;
  /* Where compartment c's state lies in the vectors given: numbers at
   * (c - view_lo) * ncells, carried totals from view_carried, ledger at
   * (c - view_lo) * 2 nvol.  The full layout: view_lo 0, view_carried nnum.
   * A packed part of the state (an MPI rank's block, one compartment) has
   * the compartment before it, which transfer reads, in `halo` (numbers,
   * then carried). */
  size_t view_lo, view_carried;
  size_t view_scalars; /* where compartment view_lo's scalars begin */
  const double *halo;
  /* The interval [switch_lo, switch_hi] being integrated, which holds no
   * switch (gs_model_next_switch) inside it, or switch_lo > switch_hi for
   * none.  Mechanisms active over a time window decide on or off at its
   * midpoint (gs_window_on), so that an evaluation at an end that is a
   * switch time sees the interval's rates: Runge-Kutta stages and the
   * end-of-step derivative fall on t + h exactly, and with the rate after
   * the switch there a step ending at the switch fails its error test. */
  double switch_lo, switch_hi;
  /* Numbers at or below this are integration noise (the solver's absolute
   * tolerance); mechanisms may skip cells holding no more than it. */
  double noise_floor;
  /* NULL, or ncomp seconds to which the model adds each compartment's rate
   * evaluation (the MPI rebalancing follows the costs with them). */
  double *comp_seconds;
  /* The scratch set in [0, m->nslots) of a caller that evaluates its
   * compartments serially beside other callers; -1: one caller, and the
   * model may spread compartments, and a mechanism a compartment, over a
   * team of threads. */
  int slot;
  /* 1 while an implicit integrator forms Jacobian-vector difference
   * quotients: mechanisms keep the discrete choices (cells taking part) of
   * their last evaluation instead of making them again from y. */
  int hold;
  /* 1 while an integrator evaluates f: mechanisms may then make their
   * discrete choices once per time value, so that the Newton iterations of
   * an implicit step (same t, several y) see one smooth function. */
  int in_integrator;
  /* Counts the output times passed: a choice is kept only within one era,
   * so that the first evaluation after an output time chooses from the
   * state there, as a run resumed from that time does (a Runge-Kutta stage
   * evaluated at the output time with another y may have chosen before). */
  unsigned long era;
};

/* The context of an evaluation of the whole model in the full layout,
 * outside any integrator. */
void gs_eval_init(gs_eval *ev, const gs_model *m);


/* Allocate an empty model around a grid (grid is moved in). */
int gs_model_init(gs_model *m, gs_grid *grid, gs_error *err);
/* Declare carried quantities (before any mechanism is added). */
int gs_model_set_carried(gs_model *m, const char *const *names, int n, gs_error *err);
/* Index of a carried quantity by name, or -1. */
int gs_model_carried_index(const gs_model *m, const char *name);
/* Numbers of compartment comp in a full state vector y. */
static inline double *gs_model_numbers(const gs_model *m, double *y, size_t comp) {
  return y + comp * m->grid.ncells;
}
static inline const double *gs_model_numbers_c(const gs_model *m, const double *y, size_t comp) {
  return y + comp * m->grid.ncells;
}
/* Totals of carried quantity q in compartment comp of a full state y. */
static inline double *gs_model_carried(const gs_model *m, double *y, size_t comp, int q) {
  return y + m->nnum + (comp * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
static inline const double *gs_model_carried_c(const gs_model *m, const double *y, size_t comp,
                                               int q) {
  return y + m->nnum + (comp * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
/* Ledger of compartment comp in a full ledger: [0, nvol) exchanged, [nvol,
 * 2 nvol) lost. */
static inline double *gs_model_ledger(const gs_model *m, double *ledger, size_t comp) {
  return ledger + comp * 2 * (size_t)m->nvol;
}

/* The same in the vectors of an evaluation (gs_eval.view_lo): what
 * mechanisms use. */
static inline double *gs_eval_numbers(const gs_model *m, const gs_eval *ev, double *y,
                                      size_t comp) {
  return y + (comp - ev->view_lo) * m->grid.ncells;
}
static inline const double *gs_eval_numbers_c(const gs_model *m, const gs_eval *ev,
                                              const double *y, size_t comp) {
  return y + (comp - ev->view_lo) * m->grid.ncells;
}
static inline double *gs_eval_carried(const gs_model *m, const gs_eval *ev, double *y, size_t comp,
                                      int q) {
  return y + ev->view_carried +
         ((comp - ev->view_lo) * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
static inline const double *gs_eval_carried_c(const gs_model *m, const gs_eval *ev,
                                              const double *y, size_t comp, int q) {
  return y + ev->view_carried +
         ((comp - ev->view_lo) * (size_t)m->ncarried + (size_t)q) * m->grid.ncells;
}
/* The compartment before comp, which flows into it (transfer): in y, or the
 * halo when comp is the first of a packed part (numbers for q < 0, else
 * carried quantity q). */
static inline const double *gs_eval_upstream_c(const gs_model *m, const gs_eval *ev,
                                               const double *y, size_t comp, int q) {
  assert(!(comp == ev->view_lo && ev->view_lo > 0) || ev->halo); /* a view needs its halo */
  if (comp == ev->view_lo && ev->view_lo > 0)
    return ev->halo + (q < 0 ? 0 : (1 + (size_t)q) * m->grid.ncells);
  return q < 0 ? gs_eval_numbers_c(m, ev, y, comp - 1) : gs_eval_carried_c(m, ev, y, comp - 1, q);
}
/* Compartment comp's scalars (gs_model.nscalar of them) in an evaluation's vectors. */
static inline double *gs_eval_scalars(const gs_model *m, const gs_eval *ev, double *y,
                                      size_t comp) {
  return y + ev->view_scalars + (comp - ev->view_lo) * m->nscalar;
}
static inline const double *gs_eval_scalars_c(const gs_model *m, const gs_eval *ev,
                                              const double *y, size_t comp) {
  return y + ev->view_scalars + (comp - ev->view_lo) * m->nscalar;
}
/* The same in a full state y. */
static inline const double *gs_model_scalars_c(const gs_model *m, const double *y, size_t comp) {
  return y + m->scalar_at + comp * m->nscalar;
}
static inline double *gs_eval_ledger(const gs_model *m, const gs_eval *ev, double *ledger,
                                     size_t comp) {
  return ledger + (comp - ev->view_lo) * 2 * (size_t)m->nvol;
}
/* Name of volume coordinate k (axis or carried quantity). */
const char *gs_model_vol_name(const gs_model *m, int k);
/* Held volume of coordinate k in compartment comp. */
double gs_model_held(const gs_model *m, const double *y, size_t comp, int k);
/* The rate k (1/s) at which compartment comp's particles flow into the next
 * one (the sum of the mechanisms' outflow_rate; 0 without any).  The inflow
 * of comp + 1 is k times comp's numbers and carried totals. */
double gs_model_transfer_rate(const gs_model *m, size_t comp);
/* 1 if some mechanism reads every compartment's state (gs_mech_type.couples_all). */
int gs_model_couples_all(const gs_model *m);
/* Add a mechanism by type name, reading its parameters from node. */
int gs_model_add_mechanism(gs_model *m, const char *type, gs_cfg_node *node, const char *label,
                           gs_error *err);
void gs_model_free(gs_model *m);

/* Monotonic wall-clock seconds. */
double gs_model_seconds(void);

/* The rates of the compartments ev selects (ev NULL: the whole model, full
 * layout, outside any integrator): those compartments' entries of dydt
 * (nstate) and dledger (nledger) are overwritten. */
void gs_model_rhs(const gs_model *m, const gs_eval *ev, double t, const double *y, double *dydt,
                  double *dledger);
/* Mechanism `mech`'s number formation and depletion rates per compartment
 * (birth, death: ncomp entries; those outside ev's compartments are left
 * alone); 0 when it provides none. */
int gs_mech_number_rates(const gs_model *m, const gs_mechanism *mech, const gs_eval *ev, double t,
                         const double *y, double *birth, double *death);
/* Mechanism `mech`'s rates alone, added to dydt and dledger. */
void gs_mech_rhs(const gs_model *m, const gs_mechanism *mech, const gs_eval *ev, double t,
                 const double *y, double *dydt, double *dledger);
/* Summary columns of the mechanisms (gs_mech_type.columns), in the order of
 * the case: how many, the i-th, and their values for compartment comp of
 * the full state y (values: gs_model_ncolumns entries). */
int gs_model_ncolumns(const gs_model *m);
const gs_mech_column *gs_model_column(const gs_model *m, int i);
void gs_model_report(const gs_model *m, size_t comp, double t, const double *y, double *values);
/* The mechanisms' notes (gs_mech_type.describe), one line each led by the
 * mechanism's label, into msg (n bytes); returns how many. */
int gs_model_notes(const gs_model *m, char *msg, size_t n);
/* Set every mechanism's initial scalars in the full state y (numbers and
 * carried already there) and their absolute accuracies (nscalar per
 * compartment, ncomp compartments, into accuracy). */
void gs_model_initial_scalars(const gs_model *m, double *y, double *accuracy);
/* The worst of the mechanisms' own balances over all compartments of y
 * (0 without any); msg says which. */
double gs_model_balance(const gs_model *m, const double *y, char *msg, size_t n);
/* The first time > t at which some mechanism's rate jumps, or INFINITY. */
double gs_model_next_switch(const gs_model *m, double t);
/* Helper for mechanisms active in [start, end). */
double gs_window_next_switch(double start, double end, double t);
/* 1 if a mechanism active in [start, end) is on for an evaluation at t: at
 * t itself, or, while an interval ev->switch_lo..switch_hi is set, at its
 * midpoint. */
int gs_window_on(const gs_eval *ev, double start, double end, double t);
/* Make v (full layout, nstate + nledger; a derivative direction of the
 * state) keep the volume balance of every compartment and coordinate: its
 * exchanged entries become the held volume's change plus the lost entries
 * (held - exchanged + lost is constant along every solution). */
void gs_model_conserve(const gs_model *m, double *v);
/* 1 if some mechanism provides a preconditioner. */
int gs_model_has_preconditioner(const gs_model *m);
/* Approximate solution of (I - gamma J) z = r over the numbers and the
 * ledger (n = nstate + nledger, full layout): the product of the
 * mechanisms' inverses, each conserving volume (ledger rows included). */
void gs_model_precondition(const gs_model *m, const gs_eval *ev, double t, const double *y,
                           double gamma, const double *r, double *z);

/* ---- moments and size statistics ---------------------------------------- */
typedef struct gs_summary {
  double m0;                  /* number */
  double m1;                  /* total granule volume  sum N v */
  double m2;                  /* sum N v^2 */
  double d10, d50, d90;       /* volume-weighted percentiles of the volume-equivalent diameter */
  double mean[GS_MAX_VOL];    /* number-mean of each volume coordinate (axes, carried) */
  double total[GS_MAX_VOL];   /* total volume of each: sum N x_k, or the carried total */
  /* Number-means of each particle's porosity (l + g)/(s + l + g) and liquid
   * content l/(s + l + g) (Chaudhury 2015, eqs. 2.38-2.39), l and g the
   * coordinates named liquid and gas (axis or carried), s the others; NaN
   * when the compartment is empty or the model has neither. */
  double porosity, liquid_content;
} gs_summary;

/* The volume coordinates (gs_model_vol_name) named liquid and gas, -1 for
 * none; returns 1 when the model has either (then porosity and liquid
 * content are reported). */
int gs_model_pore_coordinates(const gs_model *m, int *liquid, int *gas);

/* Statistics of compartment comp of state y. */
void gs_summarize(const gs_model *m, const double *y, size_t comp, gs_summary *s);
/* Volume-weighted fractions of compartment comp's granules in the sieve
 * classes [d[k], d[k+1]) of the volume-equivalent diameter, k < nclass
 * (d increasing; d[0] may be 0, d[nclass] infinite): each cell's volume
 * spread over its granule volumes as for d10/d50/d90, fractions of the whole
 * volume (what lies outside the classes counts in none); NaN when empty. */
void gs_sieve_fractions(const gs_model *m, const double *y, size_t comp, const double *d,
                        size_t nclass, double *frac);
/* Mixed moment sum N x_0^p0 x_1^p1 x_2^p2 over compartment comp. */
double gs_moment(const gs_model *m, const double *y, size_t comp, const int *powers);

#ifdef __cplusplus
}
#endif
#endif
