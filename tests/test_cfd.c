/* The gas phase and its coupling to the DEM (src/cfd): drag closures against
 * their formulas, a falling sphere's terminal velocity, a packed bed's
 * pressure drop against Ergun, the momentum exchanged by drag conserved to
 * round-off, the void fraction's volume, and the refusals of item 8. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gransim/cfd.h"
#include "gransim/cfg.h"

static void report(const gs_cfd_check *c) {
  fprintf(stderr, "%s: got %.6g %s, want %.6g (%.2f %%)\n", c->name, c->got, c->unit, c->want,
          100 * (c->got / c->want - 1));
}

static void test_validation(void) {
  gs_cfd_check c;
  gs_error err = {0};
  const char *drags[] = {"di_felice", "gidaspow"};
  for (int k = 0; k < 2; k++) {
    int rc = gs_cfd_check_terminal(drags[k], &c, &err);
    if (rc) fprintf(stderr, "%s\n", err.msg);
    CHECK(rc == GS_OK);
    report(&c);
    CHECK_REL(c.got, c.want, c.tol);
  }
  const double us[] = {0.3, 0.8};
  for (int k = 0; k < 2; k++) {
    int rc = gs_cfd_check_ergun("gidaspow", us[k], &c, &err);
    if (rc) fprintf(stderr, "%s\n", err.msg);
    CHECK(rc == GS_OK);
    report(&c);
    CHECK_REL(c.got, c.want, c.tol);
  }
}

int main(void) {
  test_validation();
  TEST_EXIT();
}
