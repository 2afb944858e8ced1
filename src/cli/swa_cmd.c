/* `gransim run` for cases with solver.method = swa. */
#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "cli/commands.h"
#include "gransim/parallel.h"
#include "gransim/swa.h"

/* Under mpirun every rank runs its share of the runs (gs_swa_case_run) and
 * returns the same status; only rank 0 prints. */
int gs_cmd_run_swa(gs_cfg *cfg, const char *path, const char *out, int progress, int resume) {
  gs_error err = {0};
  gs_swa_case c;
  int root = gs_parallel_rank() == 0;
  if (resume) {
    if (root)
      fprintf(stderr, "gransim: %s: --resume is not available with the swa solver (runs are rerun from their seeds)\n", path);
    gs_cfg_free(cfg);
    return 2;
  }
  int rc = gs_swa_case_from_cfg(cfg, &c, &err);
  for (size_t i = 0; !rc && root && progress != 0 && i < c.ndisc; i++) {
    char line[2048];
    gs_swa_disc_format(&c, &c.disc[i], line, sizeof line);
    fprintf(stderr, "  discretisation: %s\n", line);
  }
  gs_swa_report rep = {0};
  if (!rc) rc = gs_swa_case_run(&c, out, progress < 0 ? isatty(2) : progress, NULL, NULL, &rep, &err);
  if (root && rc) fprintf(stderr, "gransim: %s\n", err.msg);
  else if (root)
    fprintf(stderr,
            "gransim: %s: swa, %zu runs of %zu particles done to t = %g in %.3f s (%llu jumps, %.3g per "
            "second, %llu fictitious, %llu doublings, %llu contractions); results in %s/result.h5 and "
            "%s/summary.csv\n",
            path, rep.runs, c.model.nmax, c.times[c.ntimes - 1], rep.wall_seconds,
            (unsigned long long)rep.stats.jumps, (double)rep.stats.jumps / fmax(rep.wall_seconds, 1e-9), (unsigned long long)rep.stats.fictitious,
            (unsigned long long)rep.stats.doublings, (unsigned long long)rep.stats.contractions, out, out);
  gs_swa_report_free(&rep);
  gs_swa_case_free(&c);
  return rc ? 1 : 0;
}
