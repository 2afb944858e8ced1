/* Bad input and numerical failure.  Every invalid case file must give
 * GS_EINPUT (GS_EIO for an unreadable table) with a message that names the
 * file, the line, the key path, the offending value and what was expected;
 * every numerical failure of a run must give GS_ENUMERIC with a message that
 * says what broke, where (time, compartment, cell or axis) and which setting
 * governs it; and a run that fails leaves no result files.  Conversely, runs
 * whose identities hold must pass even with a tiny checks.mass_tolerance. */
#include <dirent.h>
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_sf_gamma.h>

#include "gransim/distribution.h"
#include "pbm_testlib.h"

/* The case must fail to build with code `code` and a message containing
 * every string of the NULL-terminated list. */

#define GRID1 "grid: {axes: [{name: v, type: geometric, min: 0.01, ratio: 1.5, cells: 20}]}\n"

static void test_case_errors(void) {
  /* unknown key in a mechanism: lists the expected keys */
  EXPECT_INPUT(GRID1 "output: {end: 1}\n"
                     "mechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: 1}, redistrib: fixed_pivot}\n",
               "bad.yaml:4:", "unknown key 'redistrib'", "mechanisms[0]", "expected one of", "redistribution");
  /* unknown key in a kernel */
  EXPECT_INPUT(GRID1 "output: {end: 1}\n"
                     "mechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: 1, gamma: 2}}\n",
               "bad.yaml:4:", "unknown key 'gamma'", "mechanisms[0].kernel", "beta0");
  /* unknown mechanism, kernel, selection and daughter types list the known ones */
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: agregation}\n",
               "bad.yaml:4:", "mechanisms[0].type = 'agregation'", "aggregation, breakage, growth, liquid_addition, consolidation, feed, transfer");
  EXPECT_INPUT(GRID1 "output: {end: 1}\n"
                     "mechanisms:\n  - type: aggregation\n    kernel: {type: ballistic, beta0: 1}\n",
               "bad.yaml:5:", "mechanisms[0].kernel.type = 'ballistic'", "unknown kernel type", "constant, sum, product, madec, table, brownian");
  EXPECT_INPUT(GRID1 "output: {end: 1}\n"
                     "mechanisms:\n  - {type: breakage, selection: {type: cubic, s0: 1}, daughters: {type: uniform}}\n",
               "bad.yaml:4:", "mechanisms[0].selection.type = 'cubic'", "power, shear");
  EXPECT_INPUT(GRID1 "output: {end: 1}\n"
                     "mechanisms:\n  - {type: breakage, selection: {type: power, s0: 1}, daughters: {type: thirds}}\n",
               "bad.yaml:4:", "mechanisms[0].daughters.type = 'thirds'", "uniform, halves, power, beta");
  /* missing required key */
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: aggregation, kernel: {type: sum}}\n",
               "bad.yaml:4:", "missing key 'beta0'", "mechanisms[0].kernel");
  /* negative or zero sizes */
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: geometric, min: -1, ratio: 1.5, cells: 20}\noutput: {end: 1}\n",
               "bad.yaml:3:", "grid.axes[0].min = '-1'", "> 0");
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: geometric, min: 0, ratio: 1.5, cells: 20}\noutput: {end: 1}\n",
               "bad.yaml:3:", "grid.axes[0].min = '0'", "> 0");
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: linear, min: 3, max: 2, cells: 4}\noutput: {end: 1}\n",
               "bad.yaml:3:", "grid.axes[0].max = '2'", "> 3");
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: edges, edges: [0, 1, 2, 3], pivots: [0.5, 2.5, 2.7]}\noutput: {end: 1}\n",
               "bad.yaml:3:", "grid.axes[0]", "pivot 1 = 2.5", "[1, 2]");
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0, max: 1, cells: 3}, {name: v, type: linear, min: 0, max: 1, cells: 3}]}\n"
               "output: {end: 1}\n",
               "bad.yaml:1:", "grid.axes", "two axes are both named 'v'");
  /* a grid that does not cover the initial distribution */
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: linear, min: 0, max: 2, cells: 20}\n"
               "initial: {type: exponential, number: 1, mean: 1}\noutput: {end: 1}\n",
               "bad.yaml:4:", "initial", "axis 'v' [0, 2]", "does not cover", "coverage");
  EXPECT_INPUT("grid: {axes: [{name: v, type: linear, min: 0, max: 4, cells: 4}]}\n"
               "initial: {type: cell, number: 1, index: [5]}\noutput: {end: 1}\n",
               "bad.yaml:2:", "initial.index", "index 5", "from 1 to 4");
  /* missing output section */
  EXPECT_INPUT(GRID1, "bad.yaml:1:", "missing key 'output'");
  /* wrong type: a string for a number */
  EXPECT_INPUT("grid:\n  axes:\n    - {name: v, type: linear, min: 0, max: abc, cells: 20}\noutput: {end: 1}\n",
               "bad.yaml:3:", "grid.axes[0].max = 'abc'", "expected a number");
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: fast}}\n",
               "bad.yaml:4:", "mechanisms[0].kernel.beta0 = 'fast'", "expected a number");
  /* values out of range */
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: transfer, rate: -1}\n",
               "bad.yaml:4:", "mechanisms[0].rate = '-1'", "> 0");
  EXPECT_INPUT("grid: {compartments: 2, axes: [{name: v, type: linear, min: 0, max: 4, cells: 4}]}\n"
               "output: {end: 1}\nmechanisms:\n  - {type: feed, compartment: 3, distribution: {type: point, number: 1, at: [1.5]}}\n",
               "bad.yaml:4:", "mechanisms[0].compartment = '3'", "between 1 and 2");
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: growth, axis: liquid, constant: 1}\n",
               "bad.yaml:4:", "mechanisms[0].axis = 'liquid'", "name of a grid axis");
  EXPECT_INPUT(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: aggregation, kernel: {type: madec, beta0: 1}}\n",
               "bad.yaml:4:", "mechanisms[0].kernel", "liquid");
  EXPECT_INPUT(GRID1 "output: {end: 1}\nsolver: {method: rk, rtol: 2}\n", "bad.yaml:3:", "solver.rtol = '2'", "< 1");
  EXPECT_INPUT(GRID1 "output: {end: 1}\nchecks: {mass_tolerance: 0}\n", "bad.yaml:3:", "checks.mass_tolerance = '0'", "> 0");
  EXPECT_INPUT(GRID1 "output: {end: 1, count: 1}\n", "bad.yaml:2:", "output.count = '1'", "between 2 and");
  /* YAML itself: syntax error and duplicate key */
  EXPECT_INPUT(GRID1 "output: {end: 1\n", "bad.yaml");
  EXPECT_INPUT(GRID1 "output: {end: 1}\noutput: {end: 2}\n", "bad.yaml:3", "output");
}

/* Kernel tables read from CSV files: errors name the case file, its key and
 * the table's own file and line. */
static void test_table_errors(void) {
  char dir[] = "/tmp/gransim_tables_XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK(0);
    return;
  }
  static const struct {
    const char *name, *text;
    int code;
    const char *part1, *part2;
  } T[] = {
      {"bad_row.csv", "edges, 0, 1, 2\n1, 2\n2, x\n", GS_EINPUT, "bad_row.csv:3:", "'x' is not a number"},
      {"nonsym.csv", "# not symmetric\nedges, 0, 1, 2\n1, 2\n3, 1\n", GS_EINPUT, "not symmetric", "C[1][0] = 3 but C[0][1] = 2"},
      {"long_row.csv", "edges, 0, 1, 2\n1, 2, 3\n2, 1\n", GS_EINPUT, "long_row.csv:2:", "row has 3 values, expected 2"},
      {"short.csv", "edges, 0, 1, 2\n1, 2\n", GS_EINPUT, "short.csv", "1 rows, expected 2"},
      {"negative.csv", "edges, 0, 1, 2\n1, -2\n-2, 1\n", GS_EINPUT, "negative.csv:2:", "negative"},
      {"noedges.csv", "1, 2\n2, 1\n", GS_EINPUT, "noedges.csv:1:", "edges"},
      {"missing.csv", NULL, GS_EIO, "missing.csv", "cannot open"},
  };
  for (size_t i = 0; i < sizeof T / sizeof T[0]; i++) {
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, T[i].name);
    if (T[i].text) {
      FILE *f = fopen(path, "w");
      fputs(T[i].text, f);
      fclose(f);
    }
    char *yaml = tl_fmt(GRID1 "output: {end: 1}\nmechanisms:\n  - {type: aggregation, kernel: {type: table, file: %s}}\n", path);
    tl_expect_input(yaml, T[i].code,
                       (const char *const[]){"bad.yaml:4:", "mechanisms[0].kernel.file", T[i].part1, T[i].part2, NULL});
    free(yaml);
    if (T[i].text) unlink(path);
  }
  rmdir(dir);
}

/* ---- numerical failures ------------------------------------------------------------------ */
static void expect_run_error(const char *yaml, const gs_run_options *opt, const char *const *parts) {
  gs_case c;
  if (tl_case(yaml, &c)) return;
  gs_error err;
  memset(&err, 0, sizeof err);
  size_t n = c.model.nstate + c.model.nledger;
  double *y = calloc(n, sizeof(double));
  gs_run_report rep;
  int rc = gs_case_run(&c, opt, y, &rep, &err);
  if (rc != GS_ENUMERIC) {
    fprintf(stderr, "expected GS_ENUMERIC, got %d (%s) for:\n%s\n", rc, rc ? err.msg : "ok", yaml);
    check_failures++;
  }
  for (size_t i = 0; rc && parts[i]; i++)
    if (!strstr(err.msg, parts[i])) {
      fprintf(stderr, "message lacks '%s':\n  %s\n", parts[i], err.msg);
      check_failures++;
    }
  free(y);
  gs_case_free(&c);
}
#define EXPECT_RUN(yaml, opt, ...) expect_run_error(yaml, opt, (const char *const[]){__VA_ARGS__, NULL})

static int dir_is_empty(const char *path) {
  DIR *d = opendir(path);
  if (!d) return 1; /* not created at all: nothing left behind */
  struct dirent *e;
  int empty = 1;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
      fprintf(stderr, "left behind: %s/%s\n", path, e->d_name);
      empty = 0;
    }
  closedir(d);
  return empty;
}

static void test_run_errors(void) {
  /* products leave a grid that is too small: the loss check names the axis,
   * the setting and the remedy; and no result files remain */
  char dir[] = "/tmp/gransim_fail_XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  char out[300];
  snprintf(out, sizeof out, "%s/out", dir);
  gs_run_options opt = {.out_dir = out};
  EXPECT_RUN("grid: {axes: [{name: solid, type: linear, min: 0, max: 10, cells: 20}]}\n"
             "initial: {type: point, number: 1, at: [1.25]}\n"
             "mechanisms:\n  - {type: aggregation, kernel: {type: constant, beta0: 1}}\n"
             "output: {end: 100, count: 11}\n",
             &opt, "max_loss", "axis 'solid'", "lost beyond the last pivot", "Extend axis 'solid'", "[0, 10]", "t = ");
  CHECK(dir_is_empty(out));
  rmdir(out);
  rmdir(dir);
  /* breakage of the first cell: fragments clamped onto the first pivot create
   * volume without bound (S = 1/v is largest there) */
  EXPECT_RUN("grid: {axes: [{name: v, type: geometric, min: 0.01, ratio: 1.5, cells: 40, zero_first: true}]}\n"
             "initial: {type: exponential, number: 1, mean: 1}\n"
             "mechanisms:\n  - {type: breakage, selection: {type: power, s0: 1, exponent: -1}, daughters: {type: uniform}}\n"
             "output: {end: 5}\n",
             NULL, "created below the first pivot", "max_loss", "axis 'v'");
  /* overflowing kernel: non-finite rates are located */
  EXPECT_RUN("grid: {axes: [{name: v, type: geometric, min: 0.01, ratio: 1.5, cells: 20, zero_first: true}]}\n"
             "initial: {type: exponential, number: 1, mean: 1}\n"
             "mechanisms:\n  - {type: aggregation, kernel: {type: product, beta0: 1.0e308}}\n"
             "output: {end: 1}\n",
             NULL, "not finite", "compartment 1, cell (", "t = 0");
}

/* The identities hold to round-off, so a tiny mass tolerance passes: 2-D
 * aggregation (madec) + breakage + growth, 24 x 24, ~300 steps; measured
 * largest balance errors 5e-16 to 3.2e-15 (both schemes, builds differ)
 * against checks.mass_tolerance = 1e-14. */
static void test_tight_tolerance(void) {
  static const char *schemes[] = {"cell_average", "fixed_pivot"};
  for (int s = 0; s < 2; s++) {
    char *yaml = tl_fmt("grid: {axes: [{name: solid, type: geometric, min: 1.0e-4, ratio: 2, cells: 24, zero_first: true},"
                        " {name: liquid, type: geometric, min: 1.0e-4, ratio: 2, cells: 24, zero_first: true}]}\n"
                        "initial: {type: gamma, number: 1, mean: [0.5, 0.2], shape: [3, 3]}\n"
                        "mechanisms:\n"
                        "  - {type: aggregation, redistribution: %s, kernel: {type: madec, beta0: 1.0e-4}}\n"
                        "  - {type: breakage, redistribution: %s, selection: {type: power, s0: 0.1}, daughters: {type: beta, fragments: 3, shape: 2}}\n"
                        "  - {type: growth, axis: liquid, linear: 0.1}\n"
                        "output: {end: 2, count: 5}\n"
                        "checks: {mass_tolerance: 1.0e-14}\n",
                        schemes[s], schemes[s]);
    gs_case c;
    gs_run_report rep;
    double *y = tl_build_run(yaml, &c, &rep);
    if (y) {
      printf("tight mass tolerance, %s: largest balance error %.3g\n", schemes[s], rep.max_balance_error);
      CHECK(rep.max_balance_error < 1e-14);
      free(y);
      gs_case_free(&c);
    }
    free(yaml);
  }
}

/* ---- distributions the grid would distort, resources beyond the limits ---------- */
/* The case: an exponential of mean 0.2 on a linear grid of cells 1
 * wide sits on the first pivot (0.5) with 2.52 times its volume; so does a
 * feed's distribution.  The message names the key, the quantity, the
 * represented and the requested value and the tolerance; a tolerance above
 * the error lets the same case build, and the log holds the comparison. */
#define GRID400 "grid: {axes: [{name: v, type: linear, min: 0, max: 400, cells: 400}]}\n"
static void test_distorted_inputs(void) {
  EXPECT_INPUT(GRID400 "initial: {type: exponential, number: 1, mean: 0.2}\noutput: {end: 1}\n",
               "bad.yaml:2: initial", "volume of axis 'v' of 0.504717 instead of the requested 0.2",
               "discretisation.tolerance = 0.01", "refine the grid");
  EXPECT_INPUT(GRID400 "output: {end: 1}\nmechanisms:\n"
                       "  - {type: feed, distribution: {type: gamma, number: 2, mean: 0.3, shape: 2}}\n",
               "bad.yaml:4: mechanisms[0].distribution", "volume of axis 'v'", "requested 0.6",
               "discretisation.tolerance = 0.01");
  EXPECT_INPUT(GRID400 "initial: {type: exponential, number: 1, mean: 0.2}\noutput: {end: 1}\n"
                       "discretisation: {tolerance: 0}\n",
               "bad.yaml:4: discretisation.tolerance = '0': expected a number > 0");
  gs_case c;
  if (!tl_case(GRID400 "initial: [{type: exponential, number: 1, mean: 0.2}, {type: exponential, number: 1, mean: 20}]\n"
                       "output: {end: 1}\ndiscretisation: {tolerance: 2}\n", &c)) {
    const gs_disc_log *log = c.model.disc;
    CHECK(log->n == 2 && log->tolerance == 2);
    if (log->n == 2) {
      CHECK(fabs(log->r[0].volume[0][1] / 0.504717 - 1) < 1e-6 && log->r[0].volume[0][0] == 0.2);
      CHECK(fabs(gs_disc_error(&log->r[0]) - 1.523585) < 1e-5);
      /* a distribution the grid resolves: the cells' first moments are kept */
      CHECK(gs_disc_error(&log->r[1]) < 1e-3 && strstr(log->r[1].key, "t.yaml:2: initial[1]"));
    }
    gs_case_free(&c);
  }
}

/* Resources: output.count 10^7 of 400 cells would write 34.7 GB; 10^6
 * compartments of 20 cells with aggregation need at least 14.4 GB (a lower
 * bound: the state's vectors and the 3 pages aggregation keeps per
 * compartment). */
static void test_limits(void) {
  EXPECT_INPUT(GRID400 "output: {end: 1, count: 10000000}\n",
               "bad.yaml:2: output", "10000000 output times of 1 compartments x 400 cells would write",
               "more than limits.output_gb = 10 GB");
  EXPECT_INPUT("grid: {compartments: 1000000, axes: [{name: v, type: geometric, min: 1, ratio: 2, cells: 20}]}\n"
               "mechanisms: [{type: aggregation, kernel: {type: constant, beta0: 1}}]\n"
               "output: {end: 1}\nlimits: {memory_gb: 4}\n",
               "bad.yaml:1: grid", "needs at least 14.4 GB", "1000000 compartments x 20 cells; the state's vectors and 3 pages",
               "more than limits.memory_gb = 4 GB");
  EXPECT_INPUT(GRID400 "output: {end: 1}\nlimits: {output: 1}\n", "unknown key 'output'", "memory_gb, output_gb");
}

/* GSL's errors: the handler libgransim installs when loaded records them and
 * returns (GSL's default aborts the process), so the caller can name the key. */
static void test_gsl_errors(void) {
  gs_gsl_clear();
  CHECK(!*gs_gsl_reason());
  gsl_sf_result r;
  CHECK(gsl_sf_beta_inc_e(-1, 1, 0.5, &r) == GSL_EDOM);
  CHECK(strstr(gs_gsl_reason(), "input domain error") && strstr(gs_gsl_reason(), "beta_inc.c"));
  gs_error e = {0};
  CHECK(gs_gsl_error(&e, GS_EINPUT, "mechanisms[0].daughters") == GS_EINPUT);
  CHECK(strstr(e.msg, "mechanisms[0].daughters: GSL: ") == e.msg);
  gs_gsl_clear();
  CHECK(!*gs_gsl_reason());
}

int main(void) {
  omp_set_num_threads(1); /* small grids: threads only add overhead */
  test_gsl_errors();
  test_case_errors();
  test_distorted_inputs();
  test_limits();
  test_table_errors();
  test_run_errors();
  test_tight_tolerance();
  TEST_EXIT();
}
