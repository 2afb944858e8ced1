/* Closed forms of the bundled CoriMix example (examples/corimix-continuous.yaml)
 * that every way of advancing it must meet: each solid fed into the first of
 * the compartments in series with one transfer rate k fills them as tanks in
 * series, and the liquid sprayed into every compartment from SPRAY_START on
 * as a sum of such sources.  Shared by test_corimix (shared steps) and
 * test_compartment_steps (per-compartment steps). */
#ifndef GRANSIM_CORIMIX_TESTLIB_H
#define GRANSIM_CORIMIX_TESTLIB_H

#include <gsl/gsl_sf_gamma.h>

#include "pbm_testlib.h"

#define K_TRANSFER (7.7551e-3 / 0.095)
#define SPRAY_RATE 3.645833e-7
#define SPRAY_START 10.0

/* A file's whole text (malloc'ed; empty if unreadable), or NULL when it
 * cannot be opened. */
static char *cx_read_text(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  rewind(fp);
  char *s = calloc((size_t)n + 1, 1);
  if (fread(s, 1, (size_t)n, fp) != (size_t)n) s[0] = '\0';
  fclose(fp);
  return s;
}

/* The worst errors seen over a walk (maxima, and the most negative density). */
typedef struct {
  double solid, liquid, ledger, lost, most_negative;
} cx_worst;

/* Advance y from *t through the case's output times with advance(ctx, ...)
 * (tl_advance_to), and at each compare the state with the closed forms, F
 * the solid volume fed per second of each axis.  Errors are relative to the
 * closed form (relative = 1) or to the steady hold-up F/k (relative = 0).
 * Returns the first failure of an advance, its message printed. */
static int cx_walk(gs_case *c, double *y, double *t, const double F[2], tl_advance_fn advance,
                   void *ctx, int relative, cx_worst *w) {
  const gs_model *m = &c->model;
  double switched = NAN;
  gs_error err = {0};
  for (size_t i = 1; i < c->ntimes; i++) {
    int rc = tl_advance_to(m, &c->eval, t, c->times[i], &switched, advance, ctx, &err);
    if (rc) {
      fprintf(stderr, "%s\n", err.msg);
      return rc;
    }
    tl_state_checks(m, c->y0, y, &w->most_negative, &w->ledger, &w->lost);
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
      for (int k = 0; k < 2; k++) { /* each solid component: tanks in series */
        const double want = F[k] / K_TRANSFER * gsl_sf_gamma_inc_P((double)comp + 1, K_TRANSFER * *t);
        const double scale = relative ? fabs(want) : F[k] / K_TRANSFER;
        w->solid = fmax(w->solid, fabs(gs_model_held(m, y, comp, k) - want) / scale);
      }
      if (*t > SPRAY_START) { /* sprayed liquid: a source in every compartment */
        double want = 0;
        for (size_t j = 1; j <= comp + 1; j++)
          want += SPRAY_RATE / K_TRANSFER * gsl_sf_gamma_inc_P((double)j, K_TRANSFER * (*t - SPRAY_START));
        const double scale = relative ? fabs(want) : SPRAY_RATE / K_TRANSFER;
        w->liquid = fmax(w->liquid, fabs(gs_model_held(m, y, comp, 2) - want) / scale);
      }
    }
  }
  return GS_OK;
}

#endif
