/* Long (label `long`): the qualitative results of Sen et al. (2014) on the
 * sprayed lab bed (src/cfd/validate_sen.c, `gransim validate-cfd
 * --qualitative`): heterogeneous particle speeds (p90/p10 above 3), a spray
 * zone wetter than the rest by more than 5 times, and a larger mean diameter
 * at the higher spray rate and at the higher gas velocity. */
#include <stdio.h>

#include "check.h"
#include "gransim/cfd.h"

int main(void) {
  gs_cfd_check c[4];
  gs_error err = {0};
  int rc = gs_cfd_check_sen(c, &err);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  CHECK(rc == GS_OK);
  if (!rc)
    for (int k = 0; k < 4; k++) {
      fprintf(stderr, "%s: %.4g %s against %.4g; %s\n", c[k].name, c[k].got, c[k].unit, c[k].want, c[k].detail);
      CHECK(c[k].tol == 0);
      CHECK(c[k].got > c[k].want);
    }
  /* the thresholds: a trend, not a tie (a bed with uniform speeds or a spray
   * wetting everyone alike gives ratios near 1) */
  CHECK(GS_SEN_SPEED_RATIO > 1.5 && GS_SEN_ZONE_RATIO > 1.5);
  TEST_EXIT();
}
