/* The progress line (src/core/progress.c): its text (share, rate, time
 * left), the durations, the throttle, and the line ended by a newline. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "core/progress.h"

static void test_format(void) {
  char b[256];
  gs_progress_format(b, sizeof b, "s", 30, 0, 120, 0.5, "12 steps");
  /* 90 s left at 0.5 s/s: 180 wall seconds */
  CHECK(!strcmp(b, "t = 30 of 120 s (25%), 0.5 s/s, 3 min 00 s left, 12 steps"));
  gs_progress_format(b, sizeof b, "s", 10, 10, 120, 0, NULL);
  CHECK(!strcmp(b, "t = 10 of 120 s (0%), time left ?"));
  gs_progress_format(b, sizeof b, "run-s", 50, 0, 40, 2, "");
  CHECK(!strcmp(b, "t = 50 of 40 run-s (100%), 2 run-s/s, 0 s left")); /* never past 100 % */
  gs_progress_duration(b, sizeof b, 59.4);
  CHECK(!strcmp(b, "59 s"));
  gs_progress_duration(b, sizeof b, 3 * 3600 + 7 * 60 + 59);
  CHECK(!strcmp(b, "3 h 07 min"));
  gs_progress_duration(b, sizeof b, 2 * 86400 + 5 * 3600);
  CHECK(!strcmp(b, "2 d 5 h"));
  gs_progress_duration(b, sizeof b, -1);
  CHECK(!strcmp(b, "?"));
}

static void test_line(void) {
  gs_progress p;
  gs_progress_start(&p, "gransim", "s", 0, 100);
  char *text = NULL;
  size_t len = 0;
  p.out = open_memstream(&text, &len);
  CHECK(p.out != NULL);
  if (!p.out) return;
  gs_progress_update(&p, 5, NULL, 0); /* not due yet: nothing */
  fflush(p.out);
  CHECK(len == 0);
  /* the rate from the older anchor: 20 simulated seconds in 10 wall seconds */
  p.anchor_wall[0] -= 10;
  p.anchor_wall[1] -= 10; /* and the window moves on at this update */
  gs_progress_update(&p, 20, "x", 1);
  fflush(p.out);
  CHECK(strstr(text, "\rgransim: t = 20 of 100 s (20%), 2 s/s, 40 s left, x\033[K") != NULL);
  gs_progress_update(&p, 15, NULL, 1); /* an earlier evaluation: the line does not go back */
  fflush(p.out);
  CHECK(strstr(text, "t = 15") == NULL);
  gs_progress_end(&p);
  fflush(p.out);
  CHECK(len > 0 && text[len - 1] == '\n');
  fclose(p.out);
  free(text);
}

int main(void) {
  test_format();
  test_line();
  TEST_EXIT();
}
