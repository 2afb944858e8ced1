/* `gransim dem-reduce`: LIGGGHTS dumps -> collision/impact rates and a kernel table
 * (include/gransim/dem_data.h; docs/models.md, "DEM data reduction"). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/dem_data.h"

static void reduce_usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim dem-reduce DIR [--out TABLE.csv] [--impacts IMPACTS.csv] [--E PA] [--nu NU] [--rho KG_M3] [--e E]\n"
          "                          [--wall-E PA] [--wall-nu NU] [--contact-time S] [--min-speed M_S]\n"
          "                          [--edges E0,E1,...] [--measure diameter|volume] [--prefix c_cc_]\n"
          "                          [--contacts auto|ppcoll|cc|cc-partner]\n\n"
          "Reads every collision<STEP>.atom / impact<STEP>.atom pair (and ppcoll<STEP>.atom) in DIR,\n"
          "averages over the snapshots and prints classes, counts, contact times, the collision\n"
          "frequency diagonal C_ii, wall impact rates and lognormal fits of the impact speeds.\n"
          "--out writes C_ij as a table for the PBM kernel `table`; --impacts writes the wall-impact\n"
          "rates and impact-speed fits per class for the breakage selection `dem_impact`.  Defaults are the CoriMix\n"
          "materials: E 8e6 Pa, nu 0.2, rho 500 kg/m^3, e 0.4, wall E 9.99e8 Pa, min speed 1e-3 m/s;\n"
          "--contact-time replaces the Hertz durations.  --edges gives the table's class edges\n"
          "(nclass + 1 values, --measure says what they measure); without them the edges lie between\n"
          "the classes' diameters, which must then increase.  --contacts picks where the current\n"
          "contacts come from (default auto: the ppcoll pair dumps when every snapshot has one, else\n"
          "the per-type contact columns read as LAMMPS compute contact/atom tallies them).\n");
}

static int num_arg(const char *opt, const char *s, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end || errno || !isfinite(v)) {
    fprintf(stderr, "gransim dem-reduce: %s needs a number, got '%s'\n", opt, s);
    return 2;
  }
  *out = v;
  return 0;
}

static int edges_arg(const char *s, double **out, size_t *n) {
  size_t cap = 1;
  for (const char *p = s; *p; p++) cap += *p == ',';
  double *e = malloc(cap * sizeof(double));
  if (!e) return 2;
  char *copy = strdup(s), *save = NULL;
  *n = 0;
  for (char *tok = strtok_r(copy, ",", &save); tok; tok = strtok_r(NULL, ",", &save))
    if (num_arg("--edges", tok, &e[(*n)++])) { free(copy); free(e); return 2; }
  free(copy);
  *out = e;
  return 0;
}

int gs_cmd_dem_reduce(int argc, char **argv) {
  const char *dir = NULL, *out = NULL, *impacts = NULL;
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  double *edges = NULL;
  size_t nedges = 0;
  int rc = 0;
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP},      {"out", required_argument, NULL, 'o'},
      {"impacts", required_argument, NULL, 'i'},     {"E", required_argument, NULL, 'E'},
      {"nu", required_argument, NULL, 'n'},          {"rho", required_argument, NULL, 'r'},
      {"e", required_argument, NULL, 'e'},           {"wall-E", required_argument, NULL, 'W'},
      {"wall-nu", required_argument, NULL, 'w'},     {"contact-time", required_argument, NULL, 'T'},
      {"min-speed", required_argument, NULL, 's'},   {"prefix", required_argument, NULL, 'p'},
      {"edges", required_argument, NULL, 'g'},       {"contacts", required_argument, NULL, 'c'},
      {"measure", required_argument, NULL, 'm'},     {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: reduce_usage(stdout); free(edges); return 0;
    case 'o': out = optarg; break;
    case 'i': impacts = optarg; break;
    case 'E': rc = num_arg("--E", optarg, &opt.youngs); break;
    case 'n': rc = num_arg("--nu", optarg, &opt.poisson); break;
    case 'r': rc = num_arg("--rho", optarg, &opt.density); break;
    case 'e': rc = num_arg("--e", optarg, &opt.restitution); break;
    case 'W': rc = num_arg("--wall-E", optarg, &opt.wall_youngs); break;
    case 'w': rc = num_arg("--wall-nu", optarg, &opt.wall_poisson); break;
    case 'T': rc = num_arg("--contact-time", optarg, &opt.contact_time); break;
    case 's': rc = num_arg("--min-speed", optarg, &opt.min_speed); break;
    case 'p': opt.contact_prefix = optarg; break;
    case 'g': free(edges); rc = edges_arg(optarg, &edges, &nedges); break;
    case 'c': {
      static const char *const names[] = {"auto", "ppcoll", "cc", "cc-partner"};
      int k = 0;
      while (k < 4 && strcmp(optarg, names[k])) k++;
      if (k == 4) { fprintf(stderr, "gransim dem-reduce: --contacts: expected auto, ppcoll, cc or cc-partner, got '%s'\n", optarg); rc = 2; }
      else opt.contacts_from = k;
      break;
    }
    case 'm':
      if (!strcmp(optarg, "volume")) opt.edges_volume = 1;
      else if (!strcmp(optarg, "diameter")) opt.edges_volume = 0;
      else { fprintf(stderr, "gransim dem-reduce: --measure: expected diameter or volume, got '%s'\n", optarg); rc = 2; }
      break;
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!dir) dir = argv[i];
    else { fprintf(stderr, "gransim dem-reduce: unexpected argument '%s'\n", argv[i]); rc = 2; }
  if (!rc && !dir) { fprintf(stderr, "usage: gransim dem-reduce DIR [--out TABLE.csv] (see --help)\n"); rc = 2; }
  if (rc) { free(edges); return rc; }

  gs_error err = {0};
  gs_dem_data d;
  if (gs_dem_data_read(dir, &opt, &d, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    free(edges);
    return 1;
  }
  size_t n = d.nclass;
  if (edges && nedges != n + 1) {
    fprintf(stderr, "gransim dem-reduce: --edges has %zu values, expected %zu (nclass + 1)\n", nedges, n + 1);
    free(edges);
    gs_dem_data_free(&d);
    return 2;
  }
  d.edges = edges; /* owned by d from here */
  d.edges_volume = opt.edges_volume;

  printf("%s: %zu snapshots (steps %ld..%ld), %zu classes\n", dir, d.nsnap, d.steps[0], d.steps[d.nsnap - 1], n);
  if (opt.contact_time > 0) printf("contact time: given, %.4g s\n", d.contact_time);
  else
    printf("contact time (Hertz, e = %g): pairs %.4g s at v = %.4g m/s (%s, %zu samples); "
           "walls %.4g s at v = %.4g m/s (%zu wall contacts)\n",
           opt.restitution, d.contact_time, d.v_pair, d.v_pair_source, d.nv_pair, d.wall_contact_time[0],
           d.v_wall, d.nv_wall);
  static const char *const src[] = {"auto", "ppcoll pair dumps", "per-type contact columns (LAMMPS tally)",
                                    "per-type contact columns (naive reading)"};
  double ktot = 0;
  for (size_t i = 0; i < n; i++)
    for (size_t j = i; j < n; j++) ktot += d.contacts[i * n + j];
  printf("current contacts: %.1f per snapshot, from the %s; like-type share %.1f %% (ppcoll) vs %.1f %% "
         "(contact columns); per-type sums S_ij vs S_ji differ by %.1f %%\n", ktot, src[d.contacts_from],
         100 * d.like_share_pp, 100 * d.like_share_cc, 100 * d.asymmetry);
  printf("impact speeds: %zu samples, %zu resting contacts (< %g m/s) left out; pooled lognormal mu = %.4f, "
         "sigma = %.4f (median %.4g m/s)\n", d.all_nvel, d.nresting, opt.min_speed, d.all_mu, d.all_sigma,
         exp(d.all_mu));
  printf("%5s %9s %8s %7s %11s %11s %10s %10s %10s %10s %6s %8s %8s\n", "class", "d[m]", "N", "sd", "C_ii[1/s]",
         "sd", "sum_j C_ij", "impact/s", "sd", "impeller", "n_u", "mu", "sigma");
  for (size_t i = 0; i < n; i++) {
    double row = 0;
    for (size_t j = 0; j < n; j++) row += d.collision[i * n + j];
    printf("%5zu %9.4g %8.2f %7.2f %11.4g %11.3g %10.4g %10.4g %10.3g %10.4g %6zu %8.4f %8.4f\n", i + 1,
           d.diameter[i], d.count[i], d.count_sd[i], d.collision[i * n + i], d.collision_sd[i * n + i], row,
           d.impact_rate[i], d.impact_rate_sd[i], d.impeller_rate[i], d.nvel[i], d.vel_mu[i], d.vel_sigma[i]);
  }
  rc = 0;
  if (out) {
    if (gs_dem_data_write_table(&d, out, &err)) {
      fprintf(stderr, "gransim: %s\n", err.msg);
      rc = 1;
    } else printf("wrote %s\n", out);
  }
  if (impacts && !rc) {
    if (gs_dem_data_write_impacts(&d, impacts, &err)) {
      fprintf(stderr, "gransim: %s\n", err.msg);
      rc = 1;
    } else printf("wrote %s\n", impacts);
  }
  gs_dem_data_free(&d);
  return rc;
}
