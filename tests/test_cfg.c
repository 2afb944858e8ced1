/* Tests for the YAML configuration tree (src/cfg/cfg.c): structure, lines,
 * paths, every accessor's success and failure messages, unknown keys,
 * duplicate keys, syntax errors and file loading. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp, rmdir */
#include "gransim/cfg.h"

#include "cfg/nearest.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"

/* Line numbers below are relied on by the checks: keep the layout. */
static const char *const CASE_TEXT =
    "# a sample case\n"              /* 1 */
    "name: demo\n"                   /* 2 */
    "grid:\n"                        /* 3 */
    "  axes:\n"                      /* 4 */
    "    - name: v\n"                /* 5 */
    "      cells: 40\n"              /* 6 */
    "      ratio: 1.5\n"             /* 7 */
    "    - name: w\n"                /* 8 */
    "      ratio: abc\n"             /* 9 */
    "      ratoi: 2\n"               /* 10 */
    "  flag: yes\n"                  /* 11 */
    "times: [0, 1.5, 2e3]\n"         /* 12 */
    "single: 4.5\n"                  /* 13 */
    "mode: fast\n"                   /* 14 */
    "bad_times: [1, x, 3]\n"         /* 15 */
    "count: 12\n"                    /* 16 */
    "frac: 0.25\n"                   /* 17 */
    "empty:\n"                       /* 18 */
    "text: \"hello world\"\n";       /* 19 */

static int has(const gs_error *e, const char *sub) {
  if (strstr(e->msg, sub)) return 1;
  fprintf(stderr, "  message \"%s\"\n  lacks \"%s\"\n", e->msg, sub);
  return 0;
}

/* Expect rc to be an error whose message contains every given substring. */
#define CHECK_ERR(rc, e, want_code, ...)                                     \
  do {                                                                       \
    const char *subs_[] = {__VA_ARGS__, NULL};                               \
    CHECK((rc) == (want_code));                                              \
    CHECK((e).code == (want_code));                                          \
    for (int k_ = 0; subs_[k_]; k_++) CHECK(has(&(e), subs_[k_]));           \
  } while (0)

static gs_cfg *load(const char *text, gs_error *e) {
  gs_cfg *c = gs_cfg_load_string(text, "case.yaml", e);
  if (!c) fprintf(stderr, "unexpected load failure: %s\n", e->msg);
  return c;
}

static void test_structure(void) {
  gs_error e = {0};
  gs_cfg *c = load(CASE_TEXT, &e);
  CHECK(c != NULL);
  if (!c) return;
  CHECK(strcmp(gs_cfg_name(c), "case.yaml") == 0);
  CHECK(strcmp(gs_cfg_dir(c), ".") == 0);
  CHECK(strcmp(gs_cfg_source(c), CASE_TEXT) == 0);

  gs_cfg_node *root = gs_cfg_root(c);
  CHECK(gs_cfg_kind_of(root) == GS_CFG_MAP);
  CHECK(strcmp(gs_cfg_path(root), "") == 0);
  CHECK(gs_cfg_line(root) == 2);
  CHECK(strcmp(gs_cfg_file(root), "case.yaml") == 0);
  CHECK(gs_cfg_size(root) == 10);
  CHECK(strcmp(gs_cfg_key_at(root, 0), "name") == 0); /* order kept */
  CHECK(strcmp(gs_cfg_key_at(root, 1), "grid") == 0);
  CHECK(strcmp(gs_cfg_key_at(root, 9), "text") == 0);
  CHECK(gs_cfg_key_at(root, 10) == NULL);
  CHECK(gs_cfg_scalar(root) == NULL);

  gs_cfg_node *grid = gs_cfg_get(root, "grid");
  CHECK(gs_cfg_kind_of(grid) == GS_CFG_MAP);
  CHECK(strcmp(gs_cfg_path(grid), "grid") == 0);
  CHECK(gs_cfg_line(grid) == 4);

  gs_cfg_node *axes = gs_cfg_get(grid, "axes");
  CHECK(gs_cfg_kind_of(axes) == GS_CFG_SEQ);
  CHECK(strcmp(gs_cfg_path(axes), "grid.axes") == 0);
  CHECK(gs_cfg_size(axes) == 2);
  CHECK(gs_cfg_item(axes, 2) == NULL);
  CHECK(gs_cfg_item(grid, 0) == NULL); /* not a sequence */

  gs_cfg_node *a1 = gs_cfg_item(axes, 1);
  CHECK(strcmp(gs_cfg_path(a1), "grid.axes[1]") == 0);
  CHECK(gs_cfg_line(a1) == 8);
  gs_cfg_node *ratio = gs_cfg_get(gs_cfg_item(axes, 0), "ratio");
  CHECK(gs_cfg_kind_of(ratio) == GS_CFG_SCALAR);
  CHECK(strcmp(gs_cfg_path(ratio), "grid.axes[0].ratio") == 0);
  CHECK(strcmp(gs_cfg_scalar(ratio), "1.5") == 0);
  CHECK(gs_cfg_line(ratio) == 7);
  CHECK(gs_cfg_size(ratio) == 0);

  gs_cfg_node *times = gs_cfg_get(root, "times");
  CHECK(strcmp(gs_cfg_path(gs_cfg_item(times, 2)), "times[2]") == 0);
  CHECK(gs_cfg_line(gs_cfg_item(times, 2)) == 12);
  CHECK(strcmp(gs_cfg_scalar(gs_cfg_get(root, "empty")), "") == 0);
  CHECK(strcmp(gs_cfg_scalar(gs_cfg_get(root, "text")), "hello world") == 0);
  CHECK(gs_cfg_get(root, "nope") == NULL);
  CHECK(gs_cfg_get(ratio, "x") == NULL); /* not a map */
  gs_cfg_free(c);
}

static void test_root_sequence_paths(void) {
  gs_error e = {0};
  gs_cfg *c = load("- a: 1\n- [x, y]\n", &e);
  if (!c) return;
  gs_cfg_node *r = gs_cfg_root(c);
  CHECK(gs_cfg_kind_of(r) == GS_CFG_SEQ);
  CHECK(strcmp(gs_cfg_path(gs_cfg_get(gs_cfg_item(r, 0), "a")), "[0].a") == 0);
  CHECK(strcmp(gs_cfg_path(gs_cfg_item(gs_cfg_item(r, 1), 1)), "[1][1]") == 0);
  CHECK(gs_cfg_line(gs_cfg_item(r, 1)) == 2);
  gs_cfg_free(c);
}

static void test_doubles(gs_cfg_node *root) {
  gs_error e = {0};
  double v = 0;
  CHECK(gs_cfg_double_req(root, "single", &v, &e) == GS_OK);
  CHECK_REL(v, 4.5, 1e-15);
  CHECK(gs_cfg_double_req(root, "count", &v, &e) == GS_OK);
  CHECK_REL(v, 12.0, 1e-15);
  CHECK(gs_cfg_double_opt(root, "absent", 7.25, &v, &e) == GS_OK);
  CHECK_REL(v, 7.25, 1e-15);
  CHECK(gs_cfg_double_opt(root, "frac", 7.25, &v, &e) == GS_OK);
  CHECK_REL(v, 0.25, 1e-15);

  int rc = gs_cfg_double_req(root, "mode", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:14: mode = 'fast': expected a number");
  rc = gs_cfg_double_opt(root, "grid", 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:4: grid: expected a number");
  rc = gs_cfg_double_opt(root, "empty", 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:18: empty = '': expected a number");
  rc = gs_cfg_double_req(root, "missing", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: missing key 'missing' in the top level");

  gs_cfg_node *a1 = gs_cfg_item(gs_cfg_get(gs_cfg_get(root, "grid"), "axes"), 1);
  rc = gs_cfg_double_req(a1, "ratio", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:9: grid.axes[1].ratio = 'abc': expected a number");
  rc = gs_cfg_double_req(a1, "cells", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:8: missing key 'cells' in grid.axes[1]");
  rc = gs_cfg_double_req(gs_cfg_get(root, "name"), "x", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: name = 'demo': expected a map (key: value entries)");
}

/* Number syntax accepted and rejected by gs_cfg_node_double. */
static void test_number_syntax(void) {
  static const char *const good[] = {"1", "-2.5", "+3e2", "1.0e-3", ".5", NULL};
  static const double want[] = {1, -2.5, 300, 1e-3, 0.5};
  static const char *const bad[] = {"1.5x", "abc", "1,5", "\"\"", NULL};
  static const char *const infinite[] = {"inf", "-inf", "nan", ".inf", "-.Inf", ".NaN", "1e999",
                                         NULL};
  char text[64];
  for (int i = 0; good[i]; i++) {
    gs_error e = {0};
    snprintf(text, sizeof text, "x: %s\n", good[i]);
    gs_cfg *c = load(text, &e);
    double v = 0;
    CHECK(gs_cfg_node_double(gs_cfg_get(gs_cfg_root(c), "x"), &v, &e) == GS_OK);
    CHECK_REL(v, want[i], 1e-15);
    gs_cfg_free(c);
  }
  for (int i = 0; bad[i]; i++) {
    gs_error e = {0};
    snprintf(text, sizeof text, "x: %s\n", bad[i]);
    gs_cfg *c = load(text, &e);
    double v = 0;
    int rc = gs_cfg_double_req(gs_cfg_root(c), "x", &v, &e);
    CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: x = '", "expected a number");
    gs_cfg_free(c);
  }
  for (int i = 0; infinite[i]; i++) {
    gs_error e = {0};
    snprintf(text, sizeof text, "x: %s\n", infinite[i]);
    gs_cfg *c = load(text, &e);
    double v = 0;
    int rc = gs_cfg_double_req(gs_cfg_root(c), "x", &v, &e);
    CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: x = '", infinite[i], "expected a finite number");
    gs_cfg_free(c);
  }
}

static void test_double_range(gs_cfg_node *root) {
  gs_error e = {0};
  double v = 0;
  /* frac = 0.25, count = 12 */
  CHECK(gs_cfg_double_range(root, "frac", 1, 0, 0, 0, 1, 0, &v, &e) == GS_OK);
  CHECK_REL(v, 0.25, 1e-15);
  CHECK(gs_cfg_double_range(root, "absent", 0, 3.5, 0, 1, HUGE_VAL, 0, &v, &e) == GS_OK);
  CHECK_REL(v, 3.5, 1e-15);
  CHECK(gs_cfg_double_range(root, "count", 1, 0, -HUGE_VAL, 0, HUGE_VAL, 0, &v, &e) == GS_OK);

  int rc = gs_cfg_double_range(root, "frac", 1, 0, 1, 1, HUGE_VAL, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:17: frac = '0.25': expected a number > 1");
  rc = gs_cfg_double_range(root, "frac", 1, 0, 0.5, 0, HUGE_VAL, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "frac = '0.25': expected a number >= 0.5");
  rc = gs_cfg_double_range(root, "count", 1, 0, 0, 0, 1, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:16: count = '12': expected a number between 0 and 1");
  rc = gs_cfg_double_range(root, "count", 1, 0, 0, 1, 1, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected a number > 0 and <= 1");
  rc = gs_cfg_double_range(root, "count", 1, 0, -HUGE_VAL, 0, 12, 1, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected a number < 12");
  rc = gs_cfg_double_range(root, "count", 1, 0, -HUGE_VAL, 0, 10, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected a number <= 10");
  /* Boundary values: inclusive accepts, strict rejects. */
  CHECK(gs_cfg_double_range(root, "count", 1, 0, 12, 0, 12, 0, &v, &e) == GS_OK);
  rc = gs_cfg_double_range(root, "count", 1, 0, 12, 1, HUGE_VAL, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected a number > 12");
  rc = gs_cfg_double_range(root, "absent", 1, 0, 0, 0, 1, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: missing key 'absent' in the top level");
  rc = gs_cfg_double_range(root, "mode", 0, 0, 0, 0, 1, 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "mode = 'fast': expected a number");
}

static void test_long_range(gs_cfg_node *root) {
  gs_error e = {0};
  long v = 0;
  CHECK(gs_cfg_long_range(root, "count", 1, 0, 1, 100, &v, &e) == GS_OK);
  CHECK(v == 12);
  CHECK(gs_cfg_long_range(root, "absent", 0, -3, LONG_MIN, LONG_MAX, &v, &e) == GS_OK);
  CHECK(v == -3);
  int rc = gs_cfg_long_range(root, "count", 1, 0, 20, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:16: count = '12': expected an integer >= 20");
  rc = gs_cfg_long_range(root, "count", 1, 0, LONG_MIN, 5, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected an integer <= 5");
  rc = gs_cfg_long_range(root, "count", 1, 0, 1, 10, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "expected an integer between 1 and 10");
  rc = gs_cfg_long_range(root, "frac", 1, 0, LONG_MIN, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:17: frac = '0.25': expected an integer");
  rc = gs_cfg_long_range(root, "times", 0, 0, LONG_MIN, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:12: times: expected an integer");
  rc = gs_cfg_long_range(root, "nope", 1, 0, LONG_MIN, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "missing key 'nope' in the top level");

  gs_cfg *c = load("big: 99999999999999999999999\nsci: 1e3\n", &e);
  rc = gs_cfg_long_range(gs_cfg_root(c), "big", 1, 0, LONG_MIN, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: big = '99999999999999999999999': expected an integer");
  rc = gs_cfg_long_range(gs_cfg_root(c), "sci", 1, 0, LONG_MIN, LONG_MAX, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: sci = '1e3': expected an integer");
  gs_cfg_free(c);
}

static void test_bools(void) {
  static const char *const yes[] = {"true", "True", "YES", "on", NULL};
  static const char *const no[] = {"false", "FALSE", "no", "Off", NULL};
  char text[64];
  for (int pass = 0; pass < 2; pass++) {
    const char *const *words = pass ? no : yes;
    for (int i = 0; words[i]; i++) {
      gs_error e = {0};
      snprintf(text, sizeof text, "b: %s\n", words[i]);
      gs_cfg *c = load(text, &e);
      int v = -1;
      CHECK(gs_cfg_bool_opt(gs_cfg_root(c), "b", !pass, &v, &e) == GS_OK);
      CHECK(v == !pass);
      gs_cfg_free(c);
    }
  }
  gs_error e = {0};
  gs_cfg *c = load("a: 1\nb: maybe\n", &e);
  int v = -1;
  CHECK(gs_cfg_bool_opt(gs_cfg_root(c), "absent", 1, &v, &e) == GS_OK);
  CHECK(v == 1);
  int rc = gs_cfg_bool_opt(gs_cfg_root(c), "b", 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: b = 'maybe': expected true or false");
  rc = gs_cfg_bool_opt(gs_cfg_root(c), "a", 0, &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: a = '1': expected true or false");
  gs_cfg_free(c);
}

static void test_strings_enums(gs_cfg_node *root) {
  static const char *const modes[] = {"slow", "fast", "exact", NULL};
  static const char *const other[] = {"a", "b", "c", NULL};
  gs_error e = {0};
  const char *s = NULL;
  CHECK(gs_cfg_string_req(root, "name", &s, &e) == GS_OK);
  CHECK(s && strcmp(s, "demo") == 0);
  CHECK(gs_cfg_string_opt(root, "absent", "dflt", &s, &e) == GS_OK);
  CHECK(s && strcmp(s, "dflt") == 0);
  CHECK(gs_cfg_string_opt(root, "text", "dflt", &s, &e) == GS_OK);
  CHECK(s && strcmp(s, "hello world") == 0);
  int rc = gs_cfg_string_req(root, "grid", &s, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:4: grid: expected a string");
  rc = gs_cfg_string_req(root, "title", &s, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: missing key 'title' in the top level");

  int k = -1;
  CHECK(gs_cfg_enum_opt(root, "mode", modes, 0, &k, &e) == GS_OK);
  CHECK(k == 1);
  CHECK(gs_cfg_enum_opt(root, "absent", modes, 2, &k, &e) == GS_OK);
  CHECK(k == 2);
  rc = gs_cfg_enum_opt(root, "mode", other, 0, &k, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:14: mode = 'fast': expected one of: a, b, c");
  rc = gs_cfg_enum_opt(root, "times", other, 0, &k, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:12: times: expected one of: a, b, c");
}

static void test_kinds(gs_cfg_node *root) {
  gs_error e = {0};
  gs_cfg_node *n = NULL;
  CHECK(gs_cfg_map_req(root, "grid", &n, &e) == GS_OK);
  CHECK(n && strcmp(gs_cfg_path(n), "grid") == 0);
  CHECK(gs_cfg_seq_req(n, "axes", &n, &e) == GS_OK);
  CHECK(gs_cfg_size(n) == 2);
  CHECK(gs_cfg_require_kind(root, GS_CFG_MAP, &e) == GS_OK);

  int rc = gs_cfg_map_req(root, "times", &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:12: times: expected a map (key: value entries)");
  rc = gs_cfg_seq_req(root, "mode", &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:14: mode = 'fast': expected a list");
  rc = gs_cfg_seq_req(root, "nothing", &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: missing key 'nothing' in the top level");
  rc = gs_cfg_require_kind(root, GS_CFG_SEQ, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: the top level: expected a list");
  rc = gs_cfg_fail(gs_cfg_get(root, "count"), &e, "must be even, not %d", 12);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:16: count = '12': must be even, not 12");
}

static void test_doubles_list(gs_cfg_node *root) {
  gs_error e = {0};
  double *v = NULL;
  size_t n = 0;
  CHECK(gs_cfg_doubles_req(root, "times", 0, &v, &n, &e) == GS_OK);
  CHECK(n == 3);
  if (n == 3) {
    CHECK_REL(v[1], 1.5, 1e-15);
    CHECK_REL(v[2], 2000, 1e-15);
  }
  free(v);
  v = NULL;
  CHECK(gs_cfg_doubles_req(root, "single", 1, &v, &n, &e) == GS_OK);
  CHECK(n == 1 && v && v[0] == 4.5);
  free(v);
  v = NULL;
  int rc = gs_cfg_doubles_req(root, "single", 0, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:13: single = '4.5': expected a list of numbers");
  rc = gs_cfg_doubles_req(root, "bad_times", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:15: bad_times[1] = 'x': expected a number");
  rc = gs_cfg_doubles_req(root, "mode", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:14: mode = 'fast': expected a number");
  rc = gs_cfg_doubles_req(root, "grid", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:4: grid: expected a number or a list of numbers");
  rc = gs_cfg_doubles_req(root, "none", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "missing key 'none' in the top level");
  CHECK(v == NULL); /* nothing allocated on failure */

  gs_cfg *c = load("a: []\nb:\n  - 1\n  - [2]\n", &e);
  rc = gs_cfg_doubles_req(gs_cfg_root(c), "a", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: a: expected a non-empty list of numbers");
  rc = gs_cfg_doubles_req(gs_cfg_root(c), "b", 1, &v, &n, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:4: b[1]: expected a number");
  gs_cfg_free(c);
}

static void test_unused(void) {
  gs_error e = {0};
  gs_cfg *c = load(CASE_TEXT, &e);
  if (!c) return;
  gs_cfg_node *root = gs_cfg_root(c);
  gs_cfg_node *a1 = gs_cfg_item(gs_cfg_get(gs_cfg_get(root, "grid"), "axes"), 1);
  const char *s;
  long cells;
  gs_cfg_string_req(a1, "name", &s, &e);
  gs_cfg_long_range(a1, "cells", 0, 10, 1, LONG_MAX, &cells, &e); /* absent, still expected */
  gs_cfg_get(a1, "ratio");
  int rc = gs_cfg_check_unused(a1, &e);
  CHECK_ERR(rc, e, GS_EINPUT,
            "case.yaml:10: unknown key 'ratoi' in grid.axes[1]; did you mean 'ratio'? expected one of: name, "
            "cells, ratio");

  /* Nothing queried: the section takes no keys. */
  gs_cfg_node *a0 = gs_cfg_item(gs_cfg_get(gs_cfg_get(root, "grid"), "axes"), 0);
  rc = gs_cfg_check_unused(a0, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:5: unknown key 'name' in grid.axes[0]; "
                              "this section takes no keys");

  /* Root: report the first unused key in file order; value_at marks used. */
  for (size_t i = 0; i < gs_cfg_size(root); i++)
    if (strcmp(gs_cfg_key_at(root, i), "mode") != 0) gs_cfg_value_at(root, i);
  gs_cfg_get(root, "name");
  rc = gs_cfg_check_unused(root, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:14: unknown key 'mode' in the top level; "
                              "expected one of: grid, name");
  gs_cfg_get(root, "mode");
  CHECK(gs_cfg_check_unused(root, &e) == GS_OK);
  CHECK(gs_cfg_check_unused(NULL, &e) == GS_OK);
  rc = gs_cfg_check_unused(gs_cfg_get(root, "times"), &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:12: times: expected a map");
  gs_cfg_free(c);
}

static void test_load_errors(void) {
  gs_error e = {0};
  gs_cfg *c = gs_cfg_load_string("a: 1\nb: 2\na: 3\n", "dup.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "dup.yaml:3: duplicate key 'a' in the top level",
            "line 1");
  c = gs_cfg_load_string("s:\n  x: 1\n  y: 2\n  x: 3\n", "dup.yaml", &e);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "dup.yaml:4: duplicate key 'x' in s");

  c = gs_cfg_load_string("a: 1\nb: [1, 2\nc: 3\n", "syn.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "syn.yaml:3:", "YAML syntax error: ", "flow sequence");
  c = gs_cfg_load_string("a: 1\n  b: 2\n", "syn.yaml", &e);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "syn.yaml:2:4: YAML syntax error: mapping values");

  c = gs_cfg_load_string("a: &x 1\nb: *x\n", "al.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "al.yaml:1:", "anchors (&x) are not supported");
  c = gs_cfg_load_string("b: *x\n", "al.yaml", &e);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "al.yaml:1:", "aliases (*x) are not supported");
  c = gs_cfg_load_string("a: 1\n? [1, 2]\n: 3\n", "key.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "key.yaml:2:", "a key must be a single word");
  c = gs_cfg_load_string("a: 1\n---\nb: 2\n", "two.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, "two.yaml:2:", "single YAML document");

  static const char *const empties[] = {"", "# only a comment\n\n", "---\n", NULL};
  for (int i = 0; empties[i]; i++) {
    c = gs_cfg_load_string(empties[i], "empty.yaml", &e);
    CHECK(c != NULL);
    CHECK(gs_cfg_root(c) == NULL);
    CHECK(strcmp(gs_cfg_source(c), empties[i]) == 0);
    double v = 1;
    int rc = gs_cfg_double_opt(gs_cfg_root(c), "x", 2.0, &v, &e);
    CHECK(rc == GS_OK && v == 2.0);
    rc = gs_cfg_double_req(gs_cfg_root(c), "x", &v, &e);
    CHECK_ERR(rc, e, GS_EINPUT, "missing key 'x'");
    gs_cfg_free(c);
  }
}

static void test_files(void) {
  gs_error e = {0};
  gs_cfg *c = gs_cfg_load_file("/nonexistent/dir/case.yaml", &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EIO, e, GS_EIO, "/nonexistent/dir/case.yaml", "No such file or directory");

  char dir[] = "/tmp/gs_test_cfg_XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK(!"mkdtemp failed");
    return;
  }
  char path[128];
  snprintf(path, sizeof path, "%s/case.yaml", dir);
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs("# header\nx: 1\ny: oops\n", f);
  fclose(f);
  c = gs_cfg_load_file(path, &e);
  CHECK(c != NULL);
  if (c) {
    CHECK(strcmp(gs_cfg_name(c), path) == 0);
    CHECK(strcmp(gs_cfg_dir(c), dir) == 0);
    CHECK(strcmp(gs_cfg_source(c), "# header\nx: 1\ny: oops\n") == 0);
    double v;
    int rc = gs_cfg_double_req(gs_cfg_root(c), "y", &v, &e);
    char want[192];
    snprintf(want, sizeof want, "%s:3: y = 'oops': expected a number", path);
    CHECK_ERR(rc, e, GS_EINPUT, want);
    gs_cfg_free(c);
  }
  /* A syntax error in a file names the path, line and column. */
  f = fopen(path, "w");
  if (f) {
    fputs("x: 1\ny: [\n", f);
    fclose(f);
  }
  c = gs_cfg_load_file(path, &e);
  CHECK(c == NULL);
  CHECK_ERR(GS_EINPUT, e, GS_EINPUT, path, "YAML syntax error");
  remove(path);
  rmdir(dir);
}

static void test_value_excerpt(void) {
  gs_error e = {0};
  gs_cfg *c = load("long: |\n  first line\n  second line\n", &e);
  double v;
  int rc = gs_cfg_double_req(gs_cfg_root(c), "long", &v, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:1: long = 'first line...': expected a number");
  gs_cfg_free(c);
}

/* gs_cfg_set_scalar: replaces a value (a map too) or adds a key; the new
 * scalar reads through the accessors, names its path, and counts as unused
 * until asked for. */
static void test_set_scalar(void) {
  gs_error e = {0};
  gs_cfg *c = gs_cfg_load_string("k: {type: table, file: [a, b]}\n", "set.yaml", &e);
  CHECK(c != NULL);
  if (!c) return;
  gs_cfg_node *k = gs_cfg_get(gs_cfg_root(c), "k");
  const char *s = NULL;
  CHECK(gs_cfg_set_scalar(k, "file", "/tmp/t.csv", &e) == GS_OK);
  CHECK(gs_cfg_set_scalar(k, "measure", "diameter", &e) == GS_OK);
  CHECK(gs_cfg_size(k) == 3);
  CHECK(gs_cfg_string_req(k, "file", &s, &e) == GS_OK && strcmp(s, "/tmp/t.csv") == 0);
  CHECK(strcmp(gs_cfg_path(gs_cfg_get(k, "measure")), "k.measure") == 0);
  CHECK(gs_cfg_line(gs_cfg_get(k, "measure")) == 1);
  gs_cfg_node *t = gs_cfg_get(k, "type");
  (void)t;
  CHECK(gs_cfg_check_unused(k, &e) == GS_OK);
  CHECK(gs_cfg_set_scalar(k, "extra", "1", &e) == GS_OK);
  CHECK(gs_cfg_check_unused(k, &e) == GS_EINPUT && has(&e, "unknown key 'extra'"));
  CHECK(gs_cfg_set_scalar(gs_cfg_get(k, "file"), "x", "1", &e) == GS_EINPUT);
  gs_cfg_free(c);
}

/* "Did you mean ...?": the edit distance, the nearest word, an unknown key,
 * a misspelt required key reported at its own line, a dotted path and a
 * registry name. */
static void test_suggestions(void) {
  CHECK(gs_edit_distance("kernel", "kernel") == 0);
  CHECK(gs_edit_distance("kernal", "kernel") == 1); /* substitution */
  CHECK(gs_edit_distance("ratoi", "ratio") == 1);   /* two neighbours swapped */
  CHECK(gs_edit_distance("kernl", "kernel") == 1);  /* deletion */
  CHECK(gs_edit_distance("Kernel", "kernel") == 0); /* case ignored */
  CHECK(gs_edit_distance("", "abc") == 3 && gs_edit_distance("abc", "") == 3);
  CHECK(gs_edit_distance("growth", "breakage") == 7);
  const char *const keys[] = {"type", "kernel", "redistribution", "count"};
  CHECK(!strcmp(gs_nearest_word("kernal", keys, 4), "kernel"));
  CHECK(!strcmp(gs_nearest_word("redistributon", keys, 4), "redistribution"));
  CHECK(!strcmp(gs_nearest_word("cont", keys, 4), "count"));
  CHECK(gs_nearest_word("kernel", keys, 4) == NULL);  /* a valid key is no typo */
  CHECK(gs_nearest_word("colour", keys, 4) == NULL);  /* nothing near */
  CHECK(gs_nearest_word("tpye", keys, 4) != NULL);    /* swap in a short word */
  CHECK(gs_nearest_word("ab", keys, 4) == NULL);      /* never the whole word */

  gs_error e = {0};
  gs_cfg *c = load("mechanisms:\n"       /* 1 */
                   "  - type: aggregation\n" /* 2 */
                   "    kernal: {type: constnt, beta0: 1}\n" /* 3 */
                   "    redistribution: fixed_pivot\n", /* 4 */
                   &e);
  if (!c) return;
  gs_cfg_node *m = gs_cfg_item(gs_cfg_get(gs_cfg_root(c), "mechanisms"), 0);
  gs_cfg_node *k = NULL;
  const char *s;
  CHECK(gs_cfg_string_req(m, "type", &s, &e) == GS_OK);
  /* the required key is missing, the misspelt one is named at its own line */
  int rc = gs_cfg_map_req(m, "kernel", &k, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:3: unknown key 'kernal' in mechanisms[0]: did you mean 'kernel'?",
            "missing key 'kernel'");
  rc = gs_cfg_missing(m, "count", "(a number)", &e); /* nothing near: the section's line */
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:2: missing key 'count' (a number) in mechanisms[0]");
  /* an unknown key read after the others */
  gs_cfg_get(m, "kernel");
  gs_cfg_get(m, "redistribution");
  rc = gs_cfg_check_unused(m, &e);
  CHECK_ERR(rc, e, GS_EINPUT, "case.yaml:3: unknown key 'kernal' in mechanisms[0]; did you mean 'kernel'?");
  /* dotted paths */
  CHECK(gs_cfg_find(c, "mechanisms.0.kernel.beta0", &e) == NULL);
  CHECK(has(&e, "the case has no 'kernel' in mechanisms[0]") && has(&e, "did you mean 'kernal'?"));
  /* registry names */
  static const struct named { const char *name; } constant = {"constant"}, sum = {"sum"};
  const void *const types[] = {&constant, &sum, NULL};
  gs_cfg_node *kernal = gs_cfg_get(m, "kernal");
  CHECK(gs_registry_pick(kernal, types, "kernel", &e) == NULL);
  CHECK(has(&e, "unknown kernel type (did you mean 'constant'?); expected one of: constant, sum"));
  gs_cfg_free(c);
}

int main(void) {
  test_suggestions();
  test_structure();
  test_root_sequence_paths();
  test_number_syntax();
  test_bools();
  gs_error e = {0};
  gs_cfg *c = load(CASE_TEXT, &e);
  if (c) {
    gs_cfg_node *root = gs_cfg_root(c);
    test_doubles(root);
    test_double_range(root);
    test_long_range(root);
    test_strings_enums(root);
    test_kinds(root);
    test_doubles_list(root);
    gs_cfg_free(c);
  }
  test_unused();
  test_load_errors();
  test_files();
  test_value_excerpt();
  test_set_scalar();
  TEST_EXIT();
}
