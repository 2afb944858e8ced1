/* The gransim command: subcommands run, check, list, validate, validate-cfd, validate-fit, sweep, fit, sensitivity, optimise, dem, dem-reduce, compartments, geometry, ... */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef __GLIBC__ /* defined by the headers above */
#include <malloc.h>
#include <stdint.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

#ifdef __linux__
#include <unistd.h> /* execv */
#endif

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/api.h"
#include "gransim/cfd.h"
#include "gransim/case.h"
#include "gransim/distribution.h"
#include "gransim/run.h"
#include "gransim/kernel.h"
#include "gransim/dem.h"
#include "gransim/parallel.h"
#include "gransim/swa.h"
#include "gransim/version.h"


static void usage(FILE *fp) {
  fprintf(fp,
          "gransim %s — population balance simulation of wet granulation\n\n"
          "usage: gransim <command> [options]\n\n"
          "commands:\n"
          "  run CASE --out DIR     run a case file; writes DIR/result.h5 and DIR/summary.csv\n"
          "  check CASE             validate a case file without running it\n"
          "  plot DIR [--times T,..] PNG and SVG plots of a run, DEM or coupled result folder\n"
          "  list                   list mechanisms, kernels, selection functions, daughter\n"
          "                         distributions and integrators\n"
          "  validate [--out FILE] [--quick] [--only IDS]\n"
          "                         grid-refinement study against analytical solutions;\n"
          "                         writes a markdown report (default: standard output)\n"
          "  sweep CASE --set KEY=V1,V2,... | --design lhs:N --range KEY=LO:HI ... --out DIR\n"
          "                         many runs of a case over a grid or a Latin hypercube of\n"
          "                         variations; one row per run in DIR/sweep.csv\n"
          "  fit CASE --data FILE|--batches FILE --params KEY=LO:HI ...\n"
          "                         fit case parameters to measured sieve fractions, d50,\n"
          "                         porosity, ... of one or several batches\n"
          "  sensitivity CASE --range KEY=LO:HI ... --outputs COLS --method sobol:N|morris:R --out DIR\n"
          "                         global sensitivity: Sobol' indices or Morris screening\n"
          "  optimise CASE --target FILE --controls KEY=LO:HI ... [--method nelder-mead|bounded]\n"
          "                         choose controls so that outputs come closest to a target\n"
          "  validate-cfd [--long] [--out FILE]\n"
          "                         the gas phase against Ergun, terminal velocities, Wen & Yu;\n"
          "                         a markdown report (docs/validation-cfd.md)\n"
          "  validate-fit CASE [--quick] [--out FILE]\n"
          "                         the thesis's recipe-recovery study (docs/validation-fit.md)\n"
          "  dem CASE --out DIR     run a DEM case (collision and impact tables for the PBM);\n"
          "                         with a `gas` section, a CFD-DEM run of a fluid bed\n"
          "  dem-reduce DIR         reduce LIGGGHTS dumps to collision/impact rates (--out TABLE)\n"
          "  compartments FRAMES --out FRAGMENT.yaml\n"
          "                         zones and exchange rates from DEM particle frames (k-means)\n"
          "  geometry CASE --out DIR  write a case's generated walls (bowl, impeller) as STL\n"
          "  couple CASE --out DIR  run a coupled PBM-DEM case (coupling: {mode: one_way}): the DEM\n"
          "                         with classes from the PBM grid, then the PBM with its tables\n\n"
          "options: --help, --version; `gransim <command> --help` for details.\n"
          "Case file format: docs/case-files.md\n",
          gs_version());
}

/* How the grid holds each distribution of the case (distribution.h). */
static void print_discretisation(FILE *fp, const gs_model *m) {
  char line[1024];
  for (size_t i = 0; m->disc && i < m->disc->n; i++) {
    gs_disc_format(&m->disc->r[i], &m->grid, m->disc->tolerance, line, sizeof line);
    fprintf(fp, "  discretisation: %s\n", line);
  }
}

static int cmd_run(int argc, char **argv) {
  const char *path = NULL, *out = NULL;
  gs_run_options opt = {.progress = -1};
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP}, {"out", required_argument, NULL, 'o'},
      {"resume", no_argument, NULL, 'r'},      {"quiet", no_argument, NULL, 'q'},
      {"progress", no_argument, NULL, 'p'},    {"timings", no_argument, NULL, 'T'},
      {"threads", required_argument, NULL, 't'}, {0}};
  gs_cli_begin();
  for (int o, n; (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP:
      printf("usage: gransim run CASE --out DIR [--resume] [--quiet] [--threads N] [--timings]\n\n"
             "Runs CASE and writes DIR/result.h5 (HDF5: grid, times, numbers per cell and\n"
             "compartment, ledger, summary, case echo) and DIR/summary.csv (one row per output\n"
             "time and compartment).  Files are written under temporary names and renamed\n"
             "only when the run succeeds.  --resume continues a killed run from the partial\n"
             "files in DIR.  --threads sets the OpenMP threads (default: OMP_NUM_THREADS or all);\n"
             "waiting threads sleep rather than spin unless OMP_WAIT_POLICY or GOMP_SPINCOUNT is set.\n"
             "--timings prints, at the end, the seconds each MPI rank spent in the rates, the\n"
             "exchange between ranks, the integrator's own work, waiting for the other ranks at\n"
             "step agreements, the outputs and the final write, and the compartments it held\n"
             "at the end (they move to balance the ranks); on one rank also the rates of each\n"
             "compartment and the most a split of them over 2, 3, ... ranks could gain\n"
             "(with --threads 1).  Options take their value as --out DIR or --out=DIR.\n");
      return 0;
    case 'o': out = optarg; break;
    case 'r': opt.resume = 1; break;
    case 'q': opt.progress = 0; break;
    case 'p': opt.progress = 1; break;
    case 'T': opt.timings = 1; break;
    case 't':
      if (gs_cli_positive("run", "threads", optarg, &n)) return 2;
      omp_set_num_threads(n);
      break;
    default: return 2;
    }
  for (int i = optind; i < argc; i++) {
    if (path) {
      fprintf(stderr, "gransim run: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
    path = argv[i];
  }
  if (!path || !out) {
    fprintf(stderr, "usage: gransim run CASE --out DIR (see gransim run --help)\n");
    return 2;
  }
  opt.out_dir = out;
  gs_error err = {0};
  gs_case c;
  gs_cfg *cfg = gs_cfg_load_file(path, &err);
  const gs_api_kind kind = cfg ? gs_api_kind_of_cfg(cfg) : GS_API_SECTIONAL;
  char context[1024];
  if (kind == GS_API_SWA)
    snprintf(context, sizeof context, "case %s, results in %s: nothing was written (the swa solver writes its results at the end); run it again", path, out);
  else
    snprintf(context, sizeof context, "case %s, results in %s: the output times committed before the error are kept in %s/.result.journal; continue with `gransim run %s --out %s --resume`", path, out, out, path, out);
  gs_parallel_context(context);
  if (kind == GS_API_SWA) return gs_cmd_run_swa(cfg, path, out, opt.progress, opt.resume);
  if (kind == GS_API_COUPLED || kind == GS_API_DEM) {
    fprintf(stderr, "gransim: %s is a %s: run it with `gransim %s %s --out %s`\n", path,
            kind == GS_API_DEM ? "DEM case (a `dem:` section and no grid)"
                               : "coupled PBM-DEM case (a `coupling:` section)",
            kind == GS_API_DEM ? "dem" : "couple", path, out);
    gs_cfg_free(cfg);
    return 1;
  }
  memset(&c, 0, sizeof c);
  if (!cfg || gs_case_from_cfg(cfg, &c, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    gs_case_free(&c);
    return 1;
  }
  if (opt.progress != 0 && gs_parallel_rank() == 0 && !opt.resume) print_discretisation(stderr, &c.model);
  gs_run_report rep;
  int rc = gs_case_run(&c, &opt, NULL, &rep, &err);
  /* under MPI rank 0 speaks for all; another rank only for its own failure */
  const int rank = gs_parallel_rank();
  char moved[64] = "";
  if (!rc && rep.rebalanced)
    snprintf(moved, sizeof moved, "; compartments moved between ranks %ld time%s", rep.rebalanced,
             rep.rebalanced == 1 ? "" : "s");
  if (rc && rank == 0) fprintf(stderr, "gransim: %s\n", err.msg);
  else if (rc && !strstr(err.msg, "on another MPI rank"))
    fprintf(stderr, "gransim (MPI rank %d): %s\n", rank, err.msg);
  else if (!rc && rank == 0 && rep.per_compartment)
    fprintf(stderr,
            "gransim: %s: done to t = %g in %.4f s (per-compartment steps: %ld steps and %ld "
            "evaluations of one compartment's rates in all%s); results in %s/result.h5 and "
            "%s/summary.csv; largest volume-balance error %.2g, loss through grid boundaries "
            "%.2g\n",
            path, rep.t_end, rep.wall_seconds, rep.stats.steps, rep.stats.rhs_evals, moved, out, out,
            rep.max_balance_error, rep.max_loss);
  else if (!rc && rank == 0)
    fprintf(stderr,
            "gransim: %s: done to t = %g in %.4f s (%ld steps, %ld rhs evaluations%s); results in "
            "%s/result.h5 and %s/summary.csv; largest volume-balance error %.2g, loss through "
            "grid boundaries %.2g\n",
            path, rep.t_end, rep.wall_seconds, rep.stats.steps, rep.stats.rhs_evals, moved, out,
            out, rep.max_balance_error, rep.max_loss);
  char note[512]; /* solver auto: when and why it switched */
  const gs_integrator_type *it = c.integrator.type;
  if (!rc && rank == 0 && it->describe && it->describe(c.integrator.self, note, sizeof note))
    fprintf(stderr, "gransim: %s\n", note);
  char notes[4096]; /* the mechanisms' choices (aggregation: the rank of a low-rank kernel) */
  if (!rc && rank == 0 && gs_model_notes(&c.model, notes, sizeof notes) > 0)
    for (char *line = strtok(notes, "\n"); line; line = strtok(NULL, "\n")) fprintf(stderr, "gransim: %s\n", line);
  gs_case_free(&c);
  return rc ? 1 : 0;
}

static int cmd_check(int argc, char **argv) {
  static const struct option opts[] = {{"help", no_argument, NULL, GS_CLI_HELP}, {0}};
  int help = 0;
  gs_cli_begin();
  for (int o; (o = gs_cli_next(argc, argv, opts)) != -1;)
    if (o == GS_CLI_HELP) help = 1;
    else return 2;
  if (help || argc - optind != 1) {
    printf("usage: gransim check CASE\n\nReads and validates CASE of any kind (sectional, stochastic with\n"
           "solver.method: swa, DEM, coupled) without running it; prints what it describes.\n"
           "A misspelt key is reported at its line with the nearest valid key.\n");
    return help ? 0 : 2;
  }
  argv += optind;
  gs_error err = {0};
  char desc[8192];
  gs_api_case *c = gs_api_case_load(argv[0], &err);
  int rc = c ? gs_api_case_check(c, desc, sizeof desc, &err) : err.code;
  if (rc) fprintf(stderr, "gransim: %s\n", err.msg);
  else printf("%s: valid. %s\n", argv[0], desc);
  gs_api_case_free(c);
  return rc ? 1 : 0;
}

static int cmd_list(void) {
  printf("mechanisms:\n");
  for (const gs_mech_type *const *t = gs_mech_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("liquid sharing rules (share.type of liquid_addition and spray):\n");
  fflush(stdout);
  gs_liquid_share_list(stdout);
  printf("aggregation kernels:\n");
  for (const gs_kernel_type *const *t = gs_kernel_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("breakage selection functions:\n");
  for (const gs_selection_type *const *t = gs_selection_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("daughter distributions:\n");
  for (const gs_daughter_type *const *t = gs_daughter_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("integrators (solver.method):\n");
  for (const gs_integrator_type *const *t = gs_integrator_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("swa solver processes (the mechanisms of cases with solver.method: swa):\n");
  for (const gs_swa_process_type *const *t = gs_swa_process_types(); *t; t++) printf("  %-20s %s\n", (*t)->name, (*t)->summary);
  printf("drag laws (gas.drag of a DEM case's gas phase):\n");
  for (const gs_cfd_drag_type *const *t = gs_cfd_drags; *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
  printf("generated walls (walls[].generate of a DEM case):\n");
  fflush(stdout);
  gs_dem_list_generators(stdout);
  return 0;
}

/* Blocks up to 32 MiB come from the heap and stay mapped once freed, so that
 * a block of about the same size allocated later reuses pages already
 * touched: a fresh page's first touch (a page fault) and unmapping both
 * cost time, and an MPI rebalancing move frees one rank's integrator and
 * allocates another of about the same size.  The heap also grows 64 MiB at
 * a time (address space only) and asks for transparent huge pages there,
 * whose first touch costs far less per byte than 4 KiB pages; all threads
 * share that heap (one malloc arena: gransim's loops do not allocate).  The
 * measurements are in docs/performance.md ("page faults").  glibc and Linux
 * only; elsewhere a no-op. */
static void keep_freed_memory(void) {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  mallopt(M_TOP_PAD, 64 << 20);
  mallopt(M_ARENA_MAX, 1);
#ifdef MADV_HUGEPAGE
  char *first = malloc(1 << 20); /* more than the heap's top holds: it grows, 64 MiB past this */
  if (first) {
    const uintptr_t huge = (uintptr_t)2 << 20;
    char *from = (char *)(((uintptr_t)first + huge - 1) & ~(huge - 1)), *to = sbrk(0);
    if (to != (char *)-1 && to > from) madvise(from, (size_t)(to - from), MADV_HUGEPAGE);
    free(first);
  }
#endif
#endif
}

/* Threads that wait for their team by sleeping, not spinning.  libgomp
 * spins for a while (about 300 000 rounds by default) at every barrier
 * before it sleeps; when another process occupies a core, a spinning thread
 * takes the time slices that the thread it waits for needs, and a run on
 * all cores becomes several times slower than on one (docs/performance.md,
 * "Threads on a busy machine").  Waiting passively costs a wake-up per
 * barrier instead, small at gransim's grain (one parallel region per
 * compartment or per right-hand side).  libgomp reads OMP_WAIT_POLICY and
 * GOMP_SPINCOUNT once, when it is loaded, before main: so the variable is
 * set and the program executes itself again, once (the variable then set is
 * the guard).  Setting it earlier, from .preinit_array, did not reach
 * libgomp (glibc 2.36: the setting was gone when libgomp read its
 * environment, which the C library sets up after .preinit_array).  A user's own
 * setting of either is kept; where re-executing fails (no /proc) the run
 * goes on with the runtime's default. */
static void wait_passively(int argc, char **argv) {
#ifdef __linux__
  if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT")) return;
  /* one thread never waits for another: no need to pay a second start */
  int threads = omp_get_max_threads();
  for (int i = 2; i < argc; i++)
    if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[i + 1]);
    else if (!strncmp(argv[i], "--threads=", 10)) threads = atoi(argv[i] + 10);
  if (threads < 2) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1)) return;
  execv("/proc/self/exe", argv);
  unsetenv("OMP_WAIT_POLICY"); /* not re-executed: the runtime kept its default */
#else
  (void)argc;
  (void)argv;
#endif
}

int main(int argc, char **argv) {
  if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    usage(stdout);
    return argc < 2 ? 2 : 0;
  }
  if (!strcmp(argv[1], "--version")) {
    printf("gransim %s\nMPI: %s\n", gs_version(), gs_parallel_have_mpi() ? "yes" : "no");
    return 0;
  }
  /* the commands that run threads */
  if (!strcmp(argv[1], "run") || !strcmp(argv[1], "validate") || !strcmp(argv[1], "dem") || !strcmp(argv[1], "couple"))
    wait_passively(argc, argv);
  if (!strcmp(argv[1], "run")) {
    keep_freed_memory();
    /* MPI only for runs, and only when launched by mpirun (gransim/parallel.h) */
    gs_parallel_init(&argc, &argv);
    int rc = cmd_run(argc - 1, argv + 1);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "check")) return cmd_check(argc - 1, argv + 1);
  if (!strcmp(argv[1], "list")) return cmd_list();
  if (!strcmp(argv[1], "validate")) return gs_cmd_validate(argc - 1, argv + 1);
  if (!strcmp(argv[1], "validate-cfd")) return gs_cmd_validate_cfd(argc - 1, argv + 1);
  if (!strcmp(argv[1], "validate-fit")) return gs_cmd_validate_fit(argc - 1, argv + 1);
  if (!strcmp(argv[1], "dem")) return gs_cmd_dem(argc - 1, argv + 1);
  if (!strcmp(argv[1], "dem-reduce")) return gs_cmd_dem_reduce(argc - 1, argv + 1);
  if (!strcmp(argv[1], "compartments")) return gs_cmd_compartments(argc - 1, argv + 1);
  if (!strcmp(argv[1], "geometry")) return gs_cmd_geometry(argc - 1, argv + 1);
  if (!strcmp(argv[1], "sweep")) { /* under mpirun the ranks share the runs */
    gs_parallel_init(&argc, &argv);
    int rc = gs_cmd_sweep(argc - 1, argv + 1);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "fit")) return gs_cmd_fit(argc - 1, argv + 1);
  if (!strcmp(argv[1], "couple")) {
    /* MPI started only to see the ranks: gransim couple refuses more than one */
    gs_parallel_init(&argc, &argv);
    int rc = gs_cmd_couple(argc - 1, argv + 1);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "sensitivity")) return gs_cmd_sensitivity(argc - 1, argv + 1);
  if (!strcmp(argv[1], "optimise")) return gs_cmd_optimise(argc - 1, argv + 1);
  if (!strcmp(argv[1], "plot")) return gs_cmd_plot(argc - 1, argv + 1);
  fprintf(stderr, "gransim: unknown command '%s'\n\n", argv[1]);
  usage(stderr);
  return 2;
}
