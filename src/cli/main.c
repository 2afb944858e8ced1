/* The gransim command: subcommands run, check, list, validate, sweep, fit, sensitivity, optimise, dem, dem-reduce. */
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
#include "gransim/case.h"
#include "gransim/run.h"
#include "gransim/kernel.h"
#include "gransim/parallel.h"
#include "gransim/swa.h"

#ifndef GRANSIM_VERSION
#define GRANSIM_VERSION "unknown"
#endif

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
          "  fit CASE --data FILE --params KEY=LO:HI ...\n"
          "                         fit case parameters to measured d50, M0, ... over time\n"
          "  sensitivity CASE --range KEY=LO:HI ... --outputs COLS --method sobol:N|morris:R --out DIR\n"
          "                         global sensitivity: Sobol' indices or Morris screening\n"
          "  optimise CASE --target FILE --controls KEY=LO:HI ... [--method nelder-mead|bounded]\n"
          "                         choose controls so that outputs come closest to a target\n"
          "  dem CASE --out DIR     run a DEM case (collision and impact tables for the PBM)\n"
          "  dem-reduce DIR         reduce LIGGGHTS dumps to collision/impact rates (--out TABLE)\n"
          "  couple CASE --out DIR  run a coupled PBM-DEM case (coupling: {mode: one_way}): the DEM\n"
          "                         with classes from the PBM grid, then the PBM with its tables\n\n"
          "options: --help, --version; `gransim <command> --help` for details.\n"
          "Case file format: docs/case-files.md\n",
          GRANSIM_VERSION);
}

/* A coupled case (a `coupling:` key at the top level).  The keys are scanned,
 * not asked for, so that other cases' unknown-key messages do not offer it. */
static int is_coupled(gs_cfg *cfg) {
  gs_cfg_node *root = gs_cfg_root(cfg);
  for (size_t i = 0; gs_cfg_kind_of(root) == GS_CFG_MAP && i < gs_cfg_size(root); i++)
    if (!strcmp(gs_cfg_key_at(root, i), "coupling")) return 1;
  return 0;
}

static int cmd_run(int argc, char **argv) {
  const char *path = NULL, *out = NULL;
  gs_run_options opt = {.progress = -1};
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
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
             "(with --threads 1).\n");
      return 0;
    } else if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
    else if (!strcmp(argv[i], "--resume")) opt.resume = 1;
    else if (!strcmp(argv[i], "--quiet")) opt.progress = 0;
    else if (!strcmp(argv[i], "--progress")) opt.progress = 1;
    else if (!strcmp(argv[i], "--timings")) opt.timings = 1;
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      int n = atoi(argv[++i]);
      if (n < 1) {
        fprintf(stderr, "gransim run: --threads needs a positive integer, got '%s'\n", argv[i]);
        return 2;
      }
      omp_set_num_threads(n);
    } else if (argv[i][0] == '-') {
      fprintf(stderr, "gransim run: unknown option '%s' (see gransim run --help)\n", argv[i]);
      return 2;
    } else if (!path) path = argv[i];
    else {
      fprintf(stderr, "gransim run: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (!path || !out) {
    fprintf(stderr, "usage: gransim run CASE --out DIR (see gransim run --help)\n");
    return 2;
  }
  opt.out_dir = out;
  gs_error err = {0};
  gs_case c;
  gs_cfg *cfg = gs_cfg_load_file(path, &err);
  if (cfg && gs_swa_case_wanted(cfg)) return gs_cmd_run_swa(cfg, path, out, opt.progress, opt.resume);
  if (cfg && is_coupled(cfg)) {
    fprintf(stderr, "gransim: %s is a coupled PBM-DEM case (a `coupling:` section): run it with "
            "`gransim couple %s --out %s`\n", path, path, out);
    gs_cfg_free(cfg);
    return 1;
  }
  memset(&c, 0, sizeof c);
  if (!cfg || gs_case_from_cfg(cfg, &c, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    gs_case_free(&c);
    return 1;
  }
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
            "evaluations of one compartment's rates in all); results in %s/result.h5 and "
            "%s/summary.csv; largest volume-balance error %.2g, loss through grid boundaries "
            "%.2g\n",
            path, rep.t_end, rep.wall_seconds, rep.stats.steps, rep.stats.rhs_evals, out, out,
            rep.max_balance_error, rep.max_loss);
  else if (!rc && rank == 0)
    fprintf(stderr,
            "gransim: %s: done to t = %g in %.4f s (%ld steps, %ld rhs evaluations%s); results in "
            "%s/result.h5 and %s/summary.csv; largest volume-balance error %.2g, loss through "
            "grid boundaries %.2g\n",
            path, rep.t_end, rep.wall_seconds, rep.stats.steps, rep.stats.rhs_evals, moved, out,
            out, rep.max_balance_error, rep.max_loss);
  gs_case_free(&c);
  return rc ? 1 : 0;
}

static int cmd_check(int argc, char **argv) {
  if (argc != 1 || argv[0][0] == '-') {
    printf("usage: gransim check CASE\n\nReads and validates CASE; prints what it describes.\n");
    return argc == 1 && !strcmp(argv[0], "--help") ? 0 : 2;
  }
  gs_error err = {0};
  gs_case c;
  gs_cfg *cfg = gs_cfg_load_file(argv[0], &err);
  if (cfg && gs_swa_case_wanted(cfg)) return gs_cmd_check_swa(cfg, argv[0]);
  if (cfg && is_coupled(cfg)) { /* checked stage by stage */
    gs_cfg_free(cfg);
    return gs_cmd_couple_check(argv[0]);
  }
  memset(&c, 0, sizeof c);
  int rc = cfg ? gs_case_from_cfg(cfg, &c, &err) : err.code;
  if (rc) fprintf(stderr, "gransim: %s\n", err.msg);
  else {
    const gs_grid *g = &c.model.grid;
    printf("%s: valid. %d axes, %zu cells x %zu compartments, %zu mechanisms, %zu output times "
           "from %g to %g, integrator %s\n",
           argv[0], g->dim, g->ncells, g->ncomp, c.model.nmech, c.ntimes, c.times[0],
           c.times[c.ntimes - 1], c.integrator.type->name);
  }
  gs_case_free(&c);
  return rc ? 1 : 0;
}

static int cmd_list(void) {
  printf("mechanisms:\n");
  for (const gs_mech_type *const *t = gs_mech_types(); *t; t++) printf("  %-16s %s\n", (*t)->name, (*t)->summary);
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
  for (int i = 2; i + 1 < argc; i++)
    if (!strcmp(argv[i], "--threads")) threads = atoi(argv[i + 1]);
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
    printf("gransim %s\nMPI: %s\n", GRANSIM_VERSION, gs_parallel_have_mpi() ? "yes" : "no");
    return 0;
  }
  /* the commands that run threads */
  if (!strcmp(argv[1], "run") || !strcmp(argv[1], "validate") || !strcmp(argv[1], "dem")) wait_passively(argc, argv);
  if (!strcmp(argv[1], "run")) {
    keep_freed_memory();
    /* MPI only for runs, and only when launched by mpirun (gransim/parallel.h) */
    gs_parallel_init(&argc, &argv);
    int rc = cmd_run(argc - 2, argv + 2);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "check")) return cmd_check(argc - 2, argv + 2);
  if (!strcmp(argv[1], "list")) return cmd_list();
  if (!strcmp(argv[1], "validate")) return gs_cmd_validate(argc - 2, argv + 2);
  if (!strcmp(argv[1], "dem")) return gs_cmd_dem(argc - 2, argv + 2);
  if (!strcmp(argv[1], "dem-reduce")) return gs_cmd_dem_reduce(argc - 2, argv + 2);
  if (!strcmp(argv[1], "sweep")) { /* under mpirun the ranks share the runs */
    gs_parallel_init(&argc, &argv);
    int rc = gs_cmd_sweep(argc - 2, argv + 2);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "fit")) return gs_cmd_fit(argc - 2, argv + 2);
  if (!strcmp(argv[1], "couple")) {
    /* MPI started only to see the ranks: gransim couple refuses more than one */
    gs_parallel_init(&argc, &argv);
    int rc = gs_cmd_couple(argc - 2, argv + 2);
    gs_parallel_finalize();
    return rc;
  }
  if (!strcmp(argv[1], "sensitivity")) return gs_cmd_sensitivity(argc - 2, argv + 2);
  if (!strcmp(argv[1], "optimise")) return gs_cmd_optimise(argc - 2, argv + 2);
  if (!strcmp(argv[1], "plot")) return gs_cmd_plot(argc - 2, argv + 2);
  fprintf(stderr, "gransim: unknown command '%s'\n\n", argv[1]);
  usage(stderr);
  return 2;
}
