/* gransim — particle distributions for initial conditions and feeds.
 *
 * A distribution spec is a case-file map with a `type` and `number` (total
 * number; for feeds, number per second):
 *   point        at: [x per axis]                 all particles at one point
 *   cell         index: [i per axis] (1-based)    all particles in one cell
 *   exponential  mean: [m per axis]               product of exponentials
 *   gamma        mean: [m per axis], shape: [k per axis]   product of Gamma(k, m/k)
 *   lognormal, normal, table   a mass of solid with a size distribution by
 *                mass over the diameter (d50 and gsd or sigma; or class
 *                edges and mass fractions), `mass` instead of `number`
 *                (src/pbm/distribution_mass.c)
 * Continuous distributions are discretised axis by axis so that, per cell,
 * number and first moment are conserved (each cell's content is placed on
 * the neighbouring pivots by the lever rule).  The spec must be covered by
 * the grid: if more than `coverage` (default 1e-6) of the number or volume
 * along an axis lies outside the grid's edges, it is an error.
 *
 * What the grid holds is compared with what was asked (number, volume of
 * every axis, mean size): a cell whose content has its mean below the first
 * pivot (or above the last) can only be put on that pivot, which changes
 * the volume.  Each comparison is kept in a gs_disc_log (reported by
 * `gransim check`, at the start of a run and in result.h5), and a relative
 * error above the log's tolerance (`discretisation.tolerance`) refuses the
 * case naming the distribution's key, the requested and the represented
 * value. */
#ifndef GRANSIM_DISTRIBUTION_H
#define GRANSIM_DISTRIBUTION_H

#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One distribution as asked and as the grid holds it. */
typedef struct gs_disc_report {
  char key[160];                  /* "file:line: path" of the distribution */
  int dim;
  double number[2];               /* requested, represented (per second for feeds) */
  double volume[GS_MAX_DIM][2];   /* of every axis: requested, represented */
} gs_disc_report;

/* The largest relative error of a report: number, volume of every axis and
 * mean size of every axis (volume / number). */
double gs_disc_error(const gs_disc_report *r);

/* The reports of a case's distributions and the tolerance they are held to
 * (default: 1 %, well above the error of a grid that resolves the
 * distribution and well below the factors a too coarse one gives). */
#define GS_DISC_TOLERANCE 0.01
typedef struct gs_disc_log {
  double tolerance;
  gs_disc_report *r;
  size_t n;
} gs_disc_log;
void gs_disc_log_free(gs_disc_log *log);
/* A report as one line for people: the key, what the grid holds against
 * what was asked, the largest relative error and the tolerance. */
void gs_disc_format(const gs_disc_report *r, const gs_grid *g, double tolerance, char *buf,
                    size_t len);

/* Discretise the spec in node onto the cells of one compartment and ADD it to
 * dst (ncells entries).  Calls gs_cfg_check_unused(node) unless keep_open.
 * With log, appends the comparison to it and refuses an error above its
 * tolerance; NULL compares nothing (callers that sample the spec as is). */
int gs_distribution_add(gs_cfg_node *node, const gs_grid *g, double *dst, int keep_open,
                        gs_disc_log *log, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
