/* The progress line of a long run on a terminal: simulated time reached, the
 * share of the run, the rate (simulated seconds per wall second) and the time
 * left, rewritten in place on standard error at most a few times a second.
 * The caller decides whether to show one (a terminal, no --quiet); every
 * update is cheap when it is not due (one clock read). */
#ifndef GRANSIM_CORE_PROGRESS_H
#define GRANSIM_CORE_PROGRESS_H

#include <stddef.h>
#include <stdio.h>

/* wall seconds between two rewrites of the line */
#define GS_PROGRESS_EVERY 0.25

typedef struct gs_progress {
  const char *label;  /* "gransim", "gransim swa", ... */
  const char *unit;   /* unit of the simulated time: "s", "run-s" */
  double t0, t_end;   /* the simulated span */
  double next_wall;   /* the next rewrite is due then */
  /* two anchors (simulated, wall) a few seconds apart: the rate is measured
   * from the older, so that it follows a run that speeds up or slows down */
  double anchor_t[2], anchor_wall[2];
  double t_shown;     /* largest time shown (evaluations may try a later one) */
  int shown;          /* a line is on the terminal */
  FILE *out;          /* stderr; a test may point it elsewhere */
} gs_progress;

double gs_progress_clock(void); /* monotonic wall seconds */

void gs_progress_start(gs_progress *p, const char *label, const char *unit, double t0,
                       double t_end);
/* Rewrite the line with time t when a rewrite is due (or force); extra (may
 * be NULL) is appended, e.g. "1234 steps". */
void gs_progress_update(gs_progress *p, double t, const char *extra, int force);
/* End the line (a newline when one was shown). */
void gs_progress_end(gs_progress *p);

/* The line's text without the carriage return: "t = 12.5 of 120 s (10%),
 * 0.85 s/s, 2 min 18 s left".  rate <= 0 or not finite: not known yet. */
void gs_progress_format(char *buf, size_t size, const char *unit, double t, double t0,
                        double t_end, double rate, const char *extra);
/* "45 s", "3 min 05 s", "2 h 07 min", "12 d 3 h" */
void gs_progress_duration(char *buf, size_t size, double seconds);

#endif
