/* Minimal test assertions for gransim's test executables.
 * Each failed CHECK prints file:line and the expression and counts a failure;
 * TEST_EXIT() returns non-zero if anything failed. */
#ifndef GRANSIM_TEST_CHECK_H
#define GRANSIM_TEST_CHECK_H
#include <math.h>
#include <stdio.h>

static int check_failures = 0;

#define CHECK(cond)                                                                 \
  do {                                                                              \
    if (!(cond)) {                                                                  \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);      \
      check_failures++;                                                             \
    }                                                                               \
  } while (0)

/* |got - want| <= tol * max(|want|, tiny) */
#define CHECK_REL(got, want, tol)                                                   \
  do {                                                                              \
    double g_ = (got), w_ = (want), t_ = (tol);                                     \
    double s_ = fabs(w_) > 1e-300 ? fabs(w_) : 1e-300;                              \
    if (!(fabs(g_ - w_) <= t_ * s_)) {                                              \
      fprintf(stderr, "%s:%d: CHECK_REL failed: %s = %.15g, want %.15g (rel err %.3g > %.3g)\n", \
              __FILE__, __LINE__, #got, g_, w_, fabs(g_ - w_) / s_, t_);             \
      check_failures++;                                                             \
    }                                                                               \
  } while (0)

#define CHECK_ABS(got, want, tol)                                                   \
  do {                                                                              \
    double g_ = (got), w_ = (want), t_ = (tol);                                     \
    if (!(fabs(g_ - w_) <= t_)) {                                                   \
      fprintf(stderr, "%s:%d: CHECK_ABS failed: %s = %.15g, want %.15g (abs err %.3g > %.3g)\n", \
              __FILE__, __LINE__, #got, g_, w_, fabs(g_ - w_), t_);                 \
      check_failures++;                                                             \
    }                                                                               \
  } while (0)

#define TEST_EXIT()                                                                 \
  do {                                                                              \
    if (check_failures) fprintf(stderr, "%d check(s) failed\n", check_failures);    \
    else fprintf(stderr, "all checks passed\n");                                    \
    return check_failures ? 1 : 0;                                                  \
  } while (0)
#endif
