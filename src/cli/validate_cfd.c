/* `gransim validate-cfd`: the gas phase and its coupling against textbook
 * results (src/cfd/validate.c), as the markdown report docs/validation-cfd.md. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli/commands.h"
#include "gransim/cfd.h"

static void row(FILE *fp, const gs_cfd_check *c, int *failed) {
  int ok;
  if (c->tol > 0) {
    ok = fabs(c->got - c->want) <= c->tol * fabs(c->want);
    fprintf(fp, "| %s | %.5g %s | %.5g %s | %+.2f %% | %.0f %% | %s | %s |\n", c->name, c->got, c->unit, c->want,
            c->unit, 100 * (c->got / c->want - 1), 100 * c->tol, ok ? "yes" : "**no**", c->detail);
  } else { /* a trend: got must exceed want */
    ok = c->got > c->want;
    fprintf(fp, "| %s | %.5g %s | > %.5g %s | %+.2f %% | higher | %s | %s |\n", c->name, c->got, c->unit, c->want,
            c->unit, 100 * (c->got / c->want - 1), ok ? "yes" : "**no**", c->detail);
  }
  if (!ok) (*failed)++;
}

int gs_cmd_validate_cfd(int argc, char **argv) {
  const char *out = NULL;
  int longer = 0;
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      printf("usage: gransim validate-cfd [--long] [--out FILE]\n\n"
             "Runs the gas phase's validation cases and writes a markdown report (default: stdout):\n"
             "terminal velocities of a falling sphere (both drag laws), the pressure drop of a packed\n"
             "bed against Ergun; with --long also the minimum fluidisation velocity against Wen & Yu\n"
             "and the bed expansion (a few minutes).  Exit status 1 if a figure misses its tolerance.\n");
      return 0;
    } else if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
    else if (!strcmp(argv[i], "--long")) longer = 1;
    else {
      fprintf(stderr, "gransim validate-cfd: unknown argument '%s' (see --help)\n", argv[i]);
      return 2;
    }
  }
  gs_cfd_check c[8];
  int nc = 0, rc = 0;
  gs_error err = {0};
  const char *drags[] = {"di_felice", "gidaspow"};
  for (int k = 0; k < 2 && !rc; k++) rc = gs_cfd_check_terminal(drags[k], &c[nc++], &err);
  const double us[] = {0.3, 0.8};
  for (int k = 0; k < 2 && !rc; k++) rc = gs_cfd_check_ergun("gidaspow", us[k], &c[nc++], &err);
  if (!rc && longer) {
    rc = gs_cfd_check_fluidisation(&c[nc], &err);
    nc += 4;
  }
  if (rc) {
    fprintf(stderr, "gransim validate-cfd: %s\n", err.msg);
    return 1;
  }
  FILE *fp = out ? fopen(out, "w") : stdout;
  if (!fp) {
    fprintf(stderr, "gransim validate-cfd: %s: %s\n", out, strerror(errno));
    return 1;
  }
  int failed = 0;
  fprintf(fp, "| check | simulated | reference | deviation | tolerance | within | set-up |\n"
              "|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < nc; k++) row(fp, &c[k], &failed);
  if (out) fclose(fp);
  return failed ? 1 : 0;
}
