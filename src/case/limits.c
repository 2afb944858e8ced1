/* See limits.h. */
#include "case/limits.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Vectors of the state (numbers, carried totals, ledger) a run holds at
 * least: the case's initial state, the run's state, an output row, and
 * the integrator's stages and error estimate (Runge-Kutta-Fehlberg: 6
 * stages, y0, yerr, two derivatives; CVODE holds more). */
#define STATE_VECTORS 12
/* Characters of a summary.csv value: 10 significant digits, sign, point,
 * exponent, separator. */
#define CSV_CHARS 17

static double machine_memory_gb(void) {
  long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || size <= 0) return HUGE_VAL; /* unknown: no limit */
  return 0.8 * (double)pages * (double)size / 1e9;
}

int gs_limits_read(gs_cfg_node *root, gs_limits *lim, gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(root, "limits");
  lim->node = n;
  int rc = n ? gs_cfg_require_kind(n, GS_CFG_MAP, err) : GS_OK;
  if (!rc) rc = gs_cfg_double_range(n, "memory_gb", 0, machine_memory_gb(), 0, 1, HUGE_VAL, 0, &lim->memory_gb, err);
  if (!rc) rc = gs_cfg_double_range(n, "output_gb", 0, 10, 0, 1, HUGE_VAL, 0, &lim->output_gb, err);
  if (!rc && n) rc = gs_cfg_check_unused(n, err);
  return rc;
}

double gs_limits_memory_bytes(const gs_model *m, int pages) {
  const double per_comp = (double)m->grid.ncells * (1 + m->ncarried) + 2.0 * m->nvol;
  return (double)m->grid.ncomp * (STATE_VECTORS * 8 * per_comp + pages * (double)GS_APART);
}

double gs_limits_output_bytes(const gs_model *m, size_t ntimes) {
  /* per output time and compartment: /number and /carried, /ledger, the
   * summary columns (time .. d90, mean and total of every coordinate) in
   * result.h5 and in summary.csv */
  const double cols = 8 + 2.0 * m->nvol;
  const double h5 = 8 * ((double)m->grid.ncells * (1 + m->ncarried) + 2.0 * m->nvol + cols);
  return (double)ntimes * (8 + (double)m->grid.ncomp * (h5 + CSV_CHARS * cols));
}

int gs_limits_check_memory(const gs_limits *lim, gs_cfg_node *root, const gs_model *m,
                           gs_error *err) {
  /* the pages the mechanisms keep per compartment (their types as named:
   * an unknown one is reported when the mechanisms are read) */
  gs_cfg_node *mech = gs_cfg_get(root, "mechanisms");
  int pages = 0;
  for (size_t i = 0; gs_cfg_kind_of(mech) == GS_CFG_SEQ && i < gs_cfg_size(mech); i++) {
    gs_cfg_node *item = gs_cfg_item(mech, i);
    const char *type = gs_cfg_kind_of(item) == GS_CFG_MAP ? gs_cfg_scalar(gs_cfg_get(item, "type")) : NULL;
    const gs_mech_type *t = type ? gs_mech_lookup(type) : NULL;
    if (t) pages += t->pages_per_compartment;
    /* a table over pairs of cells: refused at the mechanism that asks for it */
    const double tables = t && t->grid_bytes ? t->grid_bytes(item, &m->grid) / 1e9 : 0;
    if (!(tables + gs_limits_memory_bytes(m, 0) / 1e9 > lim->memory_gb)) continue;
    char axes[96] = "";
    for (int k = 0; k < m->grid.dim; k++)
      snprintf(axes + strlen(axes), sizeof axes - strlen(axes), "%s%zu", k ? " x " : "",
               m->grid.axis[k].n);
    return gs_cfg_fail(item, err,
                         "its tables over pairs of cells need %.3g GB (axes of %s cells), more than "
                         "limits.memory_gb = %.3g GB%s: use fewer cells, another of its methods "
                         "(docs/case-files.md, %s) or raise limits.memory_gb on a larger machine",
                         tables, axes, lim->memory_gb,
                         lim->node ? "" : " (80 % of this machine's memory)", type);
  }
  const double need = gs_limits_memory_bytes(m, pages) / 1e9;
  if (need <= lim->memory_gb) return GS_OK;
  return gs_cfg_fail(gs_cfg_get(root, "grid"), err,
                     "a run of this case needs at least %.3g GB of memory (%zu compartments x %zu "
                     "cells; the state's vectors and %d pages per compartment that the mechanisms "
                     "keep), more than limits.memory_gb = %.3g GB%s: use fewer compartments or "
                     "cells, or raise limits.memory_gb on a larger machine",
                     need, m->grid.ncomp, m->grid.ncells, pages, lim->memory_gb,
                     lim->node ? "" : " (80 % of this machine's memory)");
}

int gs_limits_check_output(const gs_limits *lim, gs_cfg_node *root, const gs_model *m,
                           size_t ntimes, gs_error *err) {
  const double bytes = gs_limits_output_bytes(m, ntimes) / 1e9;
  if (bytes <= lim->output_gb) return GS_OK;
  return gs_cfg_fail(gs_cfg_get(root, "output"), err,
                     "%zu output times of %zu compartments x %zu cells would write %.3g GB "
                     "(result.h5 before compression and summary.csv), more than limits.output_gb "
                     "= %.3g GB: write fewer output times (output.count or output.times) or raise "
                     "limits.output_gb",
                     ntimes, m->grid.ncomp, m->grid.ncells, bytes, lim->output_gb);
}
