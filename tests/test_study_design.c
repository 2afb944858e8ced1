/* Study designs (src/study/design.c): parsing --set and --range and their
 * errors, the full grid's count and order, the Latin hypercube's strata
 * (each of N strata hit exactly once per dimension), its log ranges and its
 * reproducibility from the seed. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/study.h"

static int has(const gs_error *e, const char *sub) {
  if (strstr(e->msg, sub)) return 1;
  fprintf(stderr, "  message \"%s\"\n  lacks \"%s\"\n", e->msg, sub);
  return 0;
}

/* arg must be refused with a message holding sub. */
static void parse_fails(int range, const char *arg, const char *sub) {
  gs_study_axis a;
  gs_error e = {0};
  int rc = range ? gs_study_parse_range(arg, &a, &e) : gs_study_parse_set(arg, &a, &e);
  CHECK(rc == GS_EINPUT);
  CHECK(has(&e, sub));
  gs_study_axis_free(&a);
}

static void test_parse(void) {
  gs_study_axis a;
  gs_error e = {0};
  CHECK(gs_study_parse_set("solver.rtol=1e-6,1e-8,rk45", &a, &e) == GS_OK);
  CHECK(!strcmp(a.key, "solver.rtol") && a.nvalues == 3);
  CHECK(!strcmp(a.values[0], "1e-6") && !strcmp(a.values[2], "rk45"));
  gs_study_axis_free(&a);
  CHECK(gs_study_parse_range("output.end=0.5:2", &a, &e) == GS_OK);
  CHECK(a.lo == 0.5 && a.hi == 2 && !a.log && !a.values);
  gs_study_axis_free(&a);
  CHECK(gs_study_parse_range("k=1e-3:10:log", &a, &e) == GS_OK);
  CHECK(a.log && a.lo == 1e-3);
  gs_study_axis_free(&a);

  static const struct {
    int range;
    const char *arg, *msg;
  } bad[] = {
      {0, "beta0", "expected KEY=V1,V2"},
      {0, "=1,2", "expected KEY=V1,V2"},
      {0, "a.b=", "empty value"},
      {0, "a.b=1,,2", "empty value"},
      {0, "a.b=1,", "empty value"},
      {0, "a b=1", "space"},
      {1, "a=1", "two numbers"},
      {1, "a=x:2", "two numbers"},
      {1, "a=1:", "two numbers"},
      {1, "a=2:1", "LO must be below HI"},
      {1, "a=1:1", "LO must be below HI"},
      {1, "a=0:1:log", "LO > 0"},
      {1, "a=1:2:lin", "only ':log'"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) parse_fails(bad[i].range, bad[i].arg, bad[i].msg);
}

static void test_grid(void) {
  gs_study_axis ax[3];
  gs_error e = {0};
  CHECK(!gs_study_parse_set("a=1,2,3", &ax[0], &e));
  CHECK(!gs_study_parse_set("b=x,y", &ax[1], &e));
  CHECK(!gs_study_parse_set("c.0=7,8,9,10", &ax[2], &e));
  gs_design d;
  CHECK(gs_design_grid(ax, 3, &d, &e) == GS_OK);
  CHECK(d.nruns == 24 && d.nkeys == 3 && !d.unit);
  /* the first axis slowest, the last fastest; every combination once */
  CHECK(!strcmp(d.values[0], "1") && !strcmp(d.values[1], "x") && !strcmp(d.values[2], "7"));
  CHECK(!strcmp(d.values[3 * 1 + 2], "8"));
  CHECK(!strcmp(d.values[3 * 4 + 1], "y") && !strcmp(d.values[3 * 4 + 0], "1"));
  CHECK(!strcmp(d.values[3 * 23 + 0], "3") && !strcmp(d.values[3 * 23 + 2], "10"));
  for (size_t r = 0; r < d.nruns; r++)
    for (size_t q = 0; q < r; q++) {
      int same = 1;
      for (size_t k = 0; k < 3; k++) same &= !strcmp(d.values[r * 3 + k], d.values[q * 3 + k]);
      CHECK(!same);
    }
  gs_design_free(&d);
  /* the same key twice, and ranges in a grid */
  gs_study_axis twice[2];
  CHECK(!gs_study_parse_set("a=1", &twice[0], &e) && !gs_study_parse_set("a=2", &twice[1], &e));
  CHECK(gs_design_grid(twice, 2, &d, &e) == GS_EINPUT && has(&e, "varied twice"));
  gs_design_free(&d);
  gs_study_axis r;
  CHECK(!gs_study_parse_range("a=1:2", &r, &e));
  CHECK(gs_design_grid(&r, 1, &d, &e) == GS_EINPUT && has(&e, "needs a list"));
  gs_design_free(&d);
  CHECK(gs_design_grid(ax, 0, &d, &e) == GS_EINPUT && has(&e, "nothing to vary"));
  gs_design_free(&d);
  CHECK(gs_design_lhs(ax, 1, 4, 1, &d, &e) == GS_EINPUT && has(&e, "needs a range"));
  gs_design_free(&d);
  gs_study_axis_free(&r);
  for (int i = 0; i < 2; i++) gs_study_axis_free(&twice[i]);
  for (int i = 0; i < 3; i++) gs_study_axis_free(&ax[i]);
}

static void test_lhs(void) {
  gs_study_axis ax[3];
  gs_error e = {0};
  CHECK(!gs_study_parse_range("a=0:1", &ax[0], &e));
  CHECK(!gs_study_parse_range("b=-5:15", &ax[1], &e));
  CHECK(!gs_study_parse_range("c=1e-3:1e3:log", &ax[2], &e));
  for (size_t n = 1; n <= 64; n = n * 3 + 1) {
    gs_design d;
    CHECK(gs_design_lhs(ax, 3, n, 42, &d, &e) == GS_OK);
    CHECK(d.nruns == n && d.nkeys == 3 && d.unit);
    for (size_t k = 0; k < 3; k++) {
      int *hit = calloc(n, sizeof *hit);
      for (size_t r = 0; r < n; r++) {
        double u = d.unit[r * 3 + k];
        CHECK(u >= 0 && u < 1);
        hit[(size_t)floor(u * (double)n)]++;
        /* the value set into the case is the point, in the stratum (in log for c) */
        double v = strtod(d.values[r * 3 + k], NULL), lo = ax[k].lo, hi = ax[k].hi;
        CHECK(v >= lo && v <= hi);
        double s = k == 2 ? (log(v) - log(lo)) / (log(hi) - log(lo)) : (v - lo) / (hi - lo);
        CHECK_ABS(s, u, 1e-12);
      }
      for (size_t i = 0; i < n; i++) CHECK(hit[i] == 1);
      free(hit);
    }
    /* the same seed, the same design; another seed, another pairing */
    gs_design same, other;
    CHECK(gs_design_lhs(ax, 3, n, 42, &same, &e) == GS_OK);
    CHECK(gs_design_lhs(ax, 3, n, 43, &other, &e) == GS_OK);
    int differ = 0;
    for (size_t i = 0; i < n * 3; i++) {
      CHECK(!strcmp(d.values[i], same.values[i]));
      differ |= strcmp(d.values[i], other.values[i]) != 0;
    }
    CHECK(differ);
    gs_design_free(&d);
    gs_design_free(&same);
    gs_design_free(&other);
  }
  gs_design d;
  CHECK(gs_design_lhs(ax, 3, 0, 1, &d, &e) == GS_EINPUT && has(&e, "N >= 1"));
  gs_design_free(&d);
  for (int i = 0; i < 3; i++) gs_study_axis_free(&ax[i]);
}

int main(void) {
  test_parse();
  test_grid();
  test_lhs();
  TEST_EXIT();
}
