/* gransim validate: placeholder removed below once the study is written. */
#include <stdio.h>
#include "cli/commands.h"
int gs_cmd_validate(int argc, char **argv) {
  (void)argc; (void)argv;
  fprintf(stderr, "gransim validate: unavailable in this build\n");
  return 1;
}
