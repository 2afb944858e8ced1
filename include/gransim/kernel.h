/* gransim — aggregation kernels, breakage selection functions and daughter
 * distributions, each a registry of named types.
 *
 * Kernels are evaluated between cells of a grid, once, when a mechanism is
 * created (kernel tables are precomputed; nothing is evaluated in the
 * right-hand side).  A kernel type prepares per-cell features in create() and
 * fills a row of beta(a, b) for one cell a against a range of cells b.
 *
 * The stochastic solver (src/swa) evaluates the same kernels at particle
 * states instead of cells, through two optional fields: `at` (beta between
 * two points) and `form` (a majorant of product form that pairs can be
 * selected from in O(log N); beta / majorant is the acceptance probability
 * when the form is not exact).  beta0 is a number or one per compartment. */
#ifndef GRANSIM_KERNEL_H
#define GRANSIM_KERNEL_H

#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- aggregation kernels ------------------------------------------------- */
/* Product forms of a majorant beta^(x, y) >= beta(x, y), u the sum of a set
 * of grid axes of a particle: */
enum {
  GS_KERNEL_FORM_CONSTANT, /* beta^ = coef                 */
  GS_KERNEL_FORM_SUM,      /* beta^ = coef (u(x) + u(y))   */
  GS_KERNEL_FORM_PRODUCT   /* beta^ = coef u(x) u(y)       */
};

typedef struct gs_kernel_form {
  int kind;           /* GS_KERNEL_FORM_* */
  const double *coef; /* per compartment; owned by the kernel */
  unsigned axes;      /* bit k: grid axis k is summed into u */
  int exact;          /* 1: beta equals the form (nothing to reject) */
} gs_kernel_form;

/* A kernel that is exactly a short sum of separable terms over the cells,
 *   beta(a, b) = coef[comp] sum_t c[t] phi_m1[t](a) phi_m2[t](b),
 * for fast aggregation schemes (src/pbm/aggregation_fft.c). */
#define GS_KERNEL_MAX_TERMS 16
typedef struct gs_kernel_terms {
  int nphi, nterm;
  double *phi;        /* nphi x ncells (phi_m(c) at phi[m * ncells + c]); the caller frees it */
  const double *coef; /* per compartment; owned by the kernel */
  double c[GS_KERNEL_MAX_TERMS];
  int m1[GS_KERNEL_MAX_TERMS], m2[GS_KERNEL_MAX_TERMS];
} gs_kernel_terms;

typedef struct gs_kernel_type {
  const char *name;
  const char *summary;
  /* node: the kernel map ("type" consumed).  dir: directory of the case file
   * for relative paths.  Must call gs_cfg_check_unused(node). */
  int (*create)(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                gs_error *err);
  /* out[b - b0] = beta(cell a, cell b) in compartment comp, for b in [b0, b1). */
  void (*row)(const void *self, size_t comp, size_t a, size_t b0, size_t b1, double *out);
  void (*free)(void *self);
  /* Optional: 1 if beta differs between compartments (NULL: it does not), so
   * callers keep one table for all compartments when it does not. */
  int (*per_compartment)(const void *self);
  /* Optional: 1 if a row costs about what reading it from memory would (a
   * few arithmetic operations per pair on per-cell arrays, no pow or
   * lookups), so callers evaluate rows where they need them and keep no
   * table of beta (NULL: tables pay; see table_limit_mb of aggregation). */
  int (*cheap_row)(const void *self);
  /* Optional, for solvers of particles (points, not cells): beta in
   * compartment comp between particles x and y, one coordinate per grid
   * axis.  Must agree with row() at the pivots. */
  double (*at)(const void *self, size_t comp, const double *x, const double *y);
  /* Optional, with at: the majorant of product form (see above), a true
   * upper bound of at() for every pair of states the grid's axes can hold. */
  void (*form)(const void *self, gs_kernel_form *out);
  /* Optional: beta as separable terms (above) over the ncells cells of the
   * grid: returns the number of terms written, 0 if the kernel has none for
   * its parameters, -1 if out of memory. */
  int (*terms)(const void *self, size_t ncells, gs_kernel_terms *out);
} gs_kernel_type;

typedef struct gs_kernel {
  const gs_kernel_type *type;
  void *self;
} gs_kernel;

/* Reads node's "type" and creates the kernel; errors list the known types. */
int gs_kernel_create(gs_cfg_node *node, const gs_grid *g, const char *dir, gs_kernel *k,
                     gs_error *err);
void gs_kernel_free(gs_kernel *k);
const gs_kernel_type *const *gs_kernel_types(void); /* NULL-terminated registry */

/* ---- breakage selection functions S(cell) [1/s] ---------------------------- */
typedef struct gs_selection_type {
  const char *name;
  const char *summary;
  /* dir: directory of the case file, for relative paths. */
  int (*create)(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self, gs_error *err);
  /* Rate of breakage of a particle at the pivot of cell (coordinates x). */
  double (*rate)(const void *self, const gs_grid *g, size_t cell);
  void (*free)(void *self);
} gs_selection_type;

typedef struct gs_selection {
  const gs_selection_type *type;
  void *self;
} gs_selection;

int gs_selection_create(gs_cfg_node *node, const gs_grid *g, const char *dir, gs_selection *s,
                        gs_error *err);
void gs_selection_free(gs_selection *s);
const gs_selection_type *const *gs_selection_types(void);

/* ---- daughter distributions ---------------------------------------------------
 * Fragments keep the composition of their parent: a fragment is a fraction
 * z in (0, 1) of the parent (every coordinate scaled by z).  b(z) is the
 * number density of fragments over z with  int b = nu (fragments per event)
 * and  int z b = 1 (mass conservation). */
typedef struct gs_daughter_type {
  const char *name;
  const char *summary;
  int (*create)(gs_cfg_node *node, void **self, gs_error *err);
  double (*count_below)(const void *self, double z); /* int_0^z b(z') dz'    */
  double (*mass_below)(const void *self, double z);  /* int_0^z z' b(z') dz' */
  /* Interior points where b has atoms (delta functions), so integration can
   * split there; *n set to their number (<= 4). */
  void (*atoms)(const void *self, double *z, int *n);
  void (*free)(void *self);
} gs_daughter_type;

typedef struct gs_daughter {
  const gs_daughter_type *type;
  void *self;
} gs_daughter;

int gs_daughter_create(gs_cfg_node *node, gs_daughter *d, gs_error *err);
void gs_daughter_free(gs_daughter *d);
const gs_daughter_type *const *gs_daughter_types(void);

#ifdef __cplusplus
}
#endif
#endif
