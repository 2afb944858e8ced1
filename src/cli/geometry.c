/* `gransim geometry CASE --out DIR`: the generated walls of a DEM case (or of
 * a coupled case's `dem` section) written as STL files, to look at in
 * ParaView before running anything (docs/case-files.md, "Generated walls"). */
#include <stdio.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/cfg.h"
#include "gransim/dem.h"

static void geometry_usage(FILE *fp) {
  fprintf(fp, "usage: gransim geometry CASE --out DIR\n\n"
              "Builds the generated walls (walls[].generate: bowl, impeller) of the DEM case CASE, or of\n"
              "the `dem` section of a coupled case, checks each mesh (closed, outward normals, no\n"
              "degenerate facet) and writes it as DIR/NAME.stl in metres; prints facets, volume, area\n"
              "and bounds of each.  `gransim dem` and `gransim couple` write the same files into their\n"
              "output's geometry/ folder.\n");
}

/* The walls list of a DEM case, or of a coupled case's inline `dem` section
 * (a `dem` that names a file is loaded into *sub). */
static gs_cfg_node *find_walls(gs_cfg *cfg, gs_cfg **sub, gs_error *err) {
  gs_cfg_node *root = gs_cfg_root(cfg);
  if (!root || gs_cfg_kind_of(root) != GS_CFG_MAP) return NULL;
  gs_cfg_node *d = gs_cfg_get(root, "dem");
  if (d && gs_cfg_get(root, "coupling")) {
    if (gs_cfg_scalar(d)) {
      char path[4200];
      const char *f = gs_cfg_scalar(d);
      snprintf(path, sizeof path, "%s%s%.4000s", f[0] == '/' ? "" : gs_cfg_dir(cfg), f[0] == '/' ? "" : "/", f);
      if (!(*sub = gs_cfg_load_file(path, err))) return NULL;
      root = gs_cfg_root(*sub);
    } else {
      root = d;
    }
    if (!root || gs_cfg_kind_of(root) != GS_CFG_MAP) return NULL;
  }
  return gs_cfg_get(root, "walls");
}

int gs_cmd_geometry(int argc, char **argv) {
  const char *path = NULL, *out = NULL;
  static const struct option opts[] = {{"help", no_argument, NULL, GS_CLI_HELP}, {"out", required_argument, NULL, 'o'}, {0}};
  gs_cli_begin();
  for (int o; (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: geometry_usage(stdout); return 0;
    case 'o': out = optarg; break;
    default: return 2;
    }
  for (int i = optind; i < argc; i++) {
    if (path) {
      fprintf(stderr, "gransim geometry: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
    path = argv[i];
  }
  if (!path || !out) {
    geometry_usage(stderr);
    return 2;
  }
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_file(path, &err), *sub = NULL;
  gs_cfg_node *walls = cfg ? find_walls(cfg, &sub, &err) : NULL;
  size_t n = 0;
  int rc = !cfg || err.code ? 1 : 0;
  if (!rc && walls) rc = gs_dem_generate_walls(walls, out, stdout, &n, &err) ? 1 : 0;
  if (!rc && !n) {
    snprintf(err.msg, sizeof err.msg, "%s: no generated walls (walls[].generate) in this case", path);
    rc = 1;
  }
  if (rc) fprintf(stderr, "gransim: %s\n", err.msg);
  gs_cfg_free(sub);
  gs_cfg_free(cfg);
  return rc;
}
