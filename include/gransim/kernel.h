/* gransim — aggregation kernels, breakage selection functions and daughter
 * distributions, each a registry of named types.
 *
 * Kernels are evaluated between cells of a grid, once, when a mechanism is
 * created (kernel tables are precomputed; nothing is evaluated in the
 * right-hand side).  A kernel type prepares per-cell features in create() and
 * fills a row of beta(a, b) for one cell a against a range of cells b. */
#ifndef GRANSIM_KERNEL_H
#define GRANSIM_KERNEL_H

#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- aggregation kernels ------------------------------------------------- */
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
