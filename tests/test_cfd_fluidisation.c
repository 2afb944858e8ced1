/* Long (label `long`): a poured bed fluidised by the gas phase (src/cfd).
 * The minimum fluidisation velocity from the pressure-drop curve against Wen &
 * Yu (1966) within 10 %, and the bed expanding as the gas velocity rises. */
#include <stdio.h>

#include "check.h"
#include "gransim/cfd.h"

int main(void) {
  gs_cfd_check c[4];
  gs_error err = {0};
  int rc = gs_cfd_check_fluidisation(c, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == GS_OK);
  if (!rc) {
    fprintf(stderr, "%s: got %.4g %s, want %.4g (%.1f %%); %s\n", c[0].name, c[0].got, c[0].unit, c[0].want,
            100 * (c[0].got / c[0].want - 1), c[0].detail);
    CHECK_REL(c[0].got, c[0].want, c[0].tol);
    for (int k = 1; k < 4; k++) {
      fprintf(stderr, "%s: %.4g m after %.4g m; %s\n", c[k].name, c[k].got, c[k].want, c[k].detail);
      CHECK(c[k].got > c[k].want);
    }
  }
  TEST_EXIT();
}
