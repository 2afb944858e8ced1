/* Harness: a folder of LIGGGHTS dumps as `gransim dem-reduce` reduces it
 * (src/demdata/dem_data.c): a per-atom snapshot (collision<STEP>.atom), its
 * pair contacts (ppcoll<STEP>.atom) and wall contacts (impact<STEP>.atom),
 * given in that order in the input, separated by lines "%%"; the fixed
 * materials of the default options. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gransim/dem_data.h"
#include "harness.h"

static char dir[256];

static void clean(void) {
  static const char *const names[] = {"collision100.atom", "ppcoll100.atom", "impact100.atom"};
  char path[512];
  for (int k = 0; k < 3; k++) {
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    unlink(path);
  }
  rmdir(dir);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const char *const names[] = {"collision100.atom", "ppcoll100.atom", "impact100.atom"};
  if (!dir[0]) {
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/gransim-fuzz-dumps-%ld", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    if (mkdir(dir, 0777)) abort();
    atexit(clean);
  }
  const char *at = (const char *)data, *end = at + size;
  for (int part = 0; part < 3; part++) {
    const char *sep = NULL;
    for (const char *p = at; p + 3 <= end && !sep; p++)
      if ((p == at || p[-1] == '\n') && !memcmp(p, "%%\n", 3)) sep = p;
    const char *stop = sep ? sep : end;
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, names[part]);
    FILE *f = fopen(path, "wb");
    if (f) {
      if (stop > at) fwrite(at, 1, (size_t)(stop - at), f);
      fclose(f);
    }
    at = sep ? sep + 3 : end;
  }
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  opt.quiet = 1;
  gs_error err = {0};
  gs_dem_data d;
  if (!gs_dem_data_read(dir, &opt, &d, &err)) gs_dem_data_free(&d);
  else if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "%s\n", err.msg);
  return 0;
}
