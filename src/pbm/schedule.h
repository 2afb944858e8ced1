/* Schedules: phases [start, end) in time order, not overlapping, each with
 * values (a spray's rate; an inlet air's temperature, humidity and flow);
 * outside every phase there is none (value 0).  A recipe's spraying,
 * pulses and pauses (`liquid_addition`'s `schedule`, `fluid_bed`'s `air`). */
#ifndef GRANSIM_PBM_SCHEDULE_H
#define GRANSIM_PBM_SCHEDULE_H
#include "gransim/pbm.h"

#define GS_PHASE_VALUES 4
typedef struct {
  double start, end, value[GS_PHASE_VALUES];
} gs_phase;

/* A value of every phase: its key, required or its default, and its range [lo, hi]. */
typedef struct {
  const char *key;
  int required;
  double def, lo, hi;
} gs_phase_key;

typedef struct {
  gs_phase *phase;
  size_t n;
} gs_schedule;

/* Read the list `list` of maps {start, end, <keys>} (nkeys <= GS_PHASE_VALUES).
 * Phases must be in time order and may not overlap (an error names the
 * phase's `start`, its line and the phase it overlaps). */
int gs_schedule_read(gs_cfg_node *list, const gs_phase_key *keys, int nkeys, gs_schedule *s,
                     gs_error *err);
void gs_schedule_free(gs_schedule *s);
/* The phase on at t (the midpoint of ev's interval when it has one,
 * gs_window_on; ev NULL: t itself, or the phase that ends at t), or NULL. */
const gs_phase *gs_schedule_at(const gs_schedule *s, const gs_eval *ev, double t);
/* Its first value at t, 0 outside every phase. */
double gs_schedule_value(const gs_schedule *s, const gs_eval *ev, double t);
/* The first phase start or end after t, or INFINITY. */
double gs_schedule_next_switch(const gs_schedule *s, double t);
/* The integral of the first value over all phases. */
double gs_schedule_integral(const gs_schedule *s);
/* liquid_addition's `schedule` (node: the mechanism's map): phases with a
 * `rate` each (m^3/s), or, with `liquid_solid_ratio` and `solid_mass` (and
 * `liquid_density`), phases with a relative `weight` sharing the liquid
 * ratio * solid_mass / liquid_density by weight x duration.  *q: one factor
 * per compartment (1: every compartment sprays the schedule), allocated. */
int gs_spray_schedule(gs_cfg_node *node, const gs_grid *g, double **q, size_t *nq, gs_schedule *s,
                      gs_error *err);
#endif
