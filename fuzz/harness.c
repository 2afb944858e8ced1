/* Input files and text for the harnesses (harness.h). */
#include "harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char path[4096];

static void remove_input(void) { unlink(path); }

const char *fuzz_input_file(const uint8_t *data, size_t size, const char *suffix) {
  const char *dir = getenv("TMPDIR");
  if (!path[0]) atexit(remove_input); /* one file per process, gone when it ends */
  snprintf(path, sizeof path, "%s/gransim-fuzz-%ld%s", dir && *dir ? dir : "/tmp", (long)getpid(), suffix);
  FILE *f = fopen(path, "wb");
  if (!f) return NULL;
  size_t put = size ? fwrite(data, 1, size, f) : 0;
  if (fclose(f) || put != size) return NULL;
  return path;
}

char *fuzz_input_text(const uint8_t *data, size_t size) {
  char *s = malloc(size + 1);
  if (!s) return NULL;
  if (size) memcpy(s, data, size);
  s[size] = '\0';
  return s;
}
