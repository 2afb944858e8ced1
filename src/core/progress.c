/* See core/progress.h. */
#include "core/progress.h"

#include <math.h>
#include <string.h>
#include <time.h>

/* the rate is measured over the last 5 to 10 wall seconds */
#define GS_PROGRESS_WINDOW 5.0

double gs_progress_clock(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void gs_progress_start(gs_progress *p, const char *label, const char *unit, double t0,
                       double t_end) {
  memset(p, 0, sizeof *p);
  p->label = label;
  p->unit = unit;
  p->t0 = p->t_shown = t0;
  p->t_end = t_end;
  const double now = gs_progress_clock();
  p->next_wall = now + GS_PROGRESS_EVERY;
  for (int k = 0; k < 2; k++) {
    p->anchor_t[k] = t0;
    p->anchor_wall[k] = now;
  }
  p->out = stderr;
}

void gs_progress_duration(char *buf, size_t size, double s) {
  if (!isfinite(s) || s < 0) snprintf(buf, size, "?");
  else if (s < 60) snprintf(buf, size, "%.0f s", s);
  else if (s < 3600) snprintf(buf, size, "%.0f min %02.0f s", floor(s / 60), fmod(floor(s), 60));
  else if (s < 86400) snprintf(buf, size, "%.0f h %02.0f min", floor(s / 3600), floor(fmod(s, 3600) / 60));
  else snprintf(buf, size, "%.0f d %.0f h", floor(s / 86400), floor(fmod(s, 86400) / 3600));
}

void gs_progress_format(char *buf, size_t size, const char *unit, double t, double t0,
                        double t_end, double rate, const char *extra) {
  const double span = t_end - t0;
  const double share = span > 0 ? 100.0 * fmin(fmax((t - t0) / span, 0.0), 1.0) : 100.0;
  char left[96] = "time left ?";
  if (rate > 0 && isfinite(rate)) {
    char d[32];
    gs_progress_duration(d, sizeof d, fmax(t_end - t, 0.0) / rate);
    snprintf(left, sizeof left, "%.3g %s/s, %s left", rate, unit, d);
  }
  snprintf(buf, size, "t = %.6g of %.6g %s (%.0f%%), %s%s%s", t, t_end, unit, share, left,
           extra && extra[0] ? ", " : "", extra ? extra : "");
}

void gs_progress_update(gs_progress *p, double t, const char *extra, int force) {
  const double now = gs_progress_clock();
  if (!force && now < p->next_wall) return;
  p->next_wall = now + GS_PROGRESS_EVERY;
  if (t > p->t_shown) p->t_shown = t;
  if (now - p->anchor_wall[1] >= GS_PROGRESS_WINDOW) { /* move the window on */
    p->anchor_t[0] = p->anchor_t[1];
    p->anchor_wall[0] = p->anchor_wall[1];
    p->anchor_t[1] = p->t_shown;
    p->anchor_wall[1] = now;
  }
  const double dw = now - p->anchor_wall[0];
  const double rate = dw > 0 ? (p->t_shown - p->anchor_t[0]) / dw : 0;
  char line[256];
  gs_progress_format(line, sizeof line, p->unit, p->t_shown, p->t0, p->t_end, rate, extra);
  /* ESC[K clears what a longer line before left on the terminal */
  fprintf(p->out, "\r%s: %s\033[K", p->label, line);
  fflush(p->out);
  p->shown = 1;
}

void gs_progress_end(gs_progress *p) {
  if (p->shown) fputc('\n', p->out);
  fflush(p->out);
  p->shown = 0;
}
