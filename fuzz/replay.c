/* main() of the harnesses built without libFuzzer: replays every file named
 * on the command line, or found in a folder named there, through
 * LLVMFuzzerTestOneInput (in name order, so that a failure is reproducible),
 * and prints how many it replayed.  A crash, a sanitizer report or a non-zero
 * return fails the run. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "harness.h"

static int replay_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: cannot read %s\n", path);
    return 1;
  }
  size_t cap = 1 << 16, n = 0;
  uint8_t *buf = malloc(cap);
  size_t got;
  while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
    n += got;
    if (n == cap) {
      uint8_t *more = realloc(buf, cap *= 2);
      if (!more) free(buf);
      buf = more;
    }
  }
  fclose(f);
  if (!buf) {
    fprintf(stderr, "replay: out of memory reading %s\n", path);
    return 1;
  }
  int rc = LLVMFuzzerTestOneInput(buf, n);
  free(buf);
  if (rc) fprintf(stderr, "replay: %s: harness returned %d\n", path, rc);
  return rc != 0;
}

static int by_name(const struct dirent **a, const struct dirent **b) { return strcmp((*a)->d_name, (*b)->d_name); }

int main(int argc, char **argv) {
  size_t count = 0;
  int failed = 0;
  for (int i = 1; i < argc; i++) {
    struct stat st;
    if (stat(argv[i], &st)) {
      fprintf(stderr, "replay: no such file or folder: %s\n", argv[i]);
      return 1;
    }
    if (!S_ISDIR(st.st_mode)) {
      failed |= replay_file(argv[i]);
      count++;
      continue;
    }
    struct dirent **list;
    int n = scandir(argv[i], &list, NULL, by_name);
    for (int k = 0; k < n; k++) {
      char path[4096];
      snprintf(path, sizeof path, "%s/%s", argv[i], list[k]->d_name);
      if (list[k]->d_name[0] != '.' && !stat(path, &st) && S_ISREG(st.st_mode)) {
        failed |= replay_file(path);
        count++;
      }
      free(list[k]);
    }
    free(list);
  }
  printf("replayed %zu inputs%s\n", count, failed ? ", some failed" : "");
  return failed || !count;
}
