/* Subcommands implemented in their own files.  Each takes the arguments
 * after `gransim`: argv[0] is the subcommand's name (getopt_long skips it,
 * messages name it; src/cli/options.h). */
#ifndef GRANSIM_CLI_COMMANDS_H
#define GRANSIM_CLI_COMMANDS_H
int gs_cmd_validate(int argc, char **argv);
int gs_cmd_validate_cfd(int argc, char **argv); /* src/cli/validate_cfd.c */
int gs_cmd_validate_fit(int argc, char **argv); /* src/cli/validate_fit.c */
int gs_cmd_dem(int argc, char **argv);
int gs_cmd_dem_reduce(int argc, char **argv); /* src/cli/dem_reduce.c */
int gs_cmd_compartments(int argc, char **argv); /* src/cli/compartments.c */
int gs_cmd_sweep(int argc, char **argv);      /* src/cli/sweep.c */
int gs_cmd_fit(int argc, char **argv);        /* src/cli/fit.c */
/* Coupled PBM-DEM cases (src/cli/couple_cmd.c). */
int gs_cmd_couple(int argc, char **argv);
int gs_cmd_couple_check(const char *path);
int gs_cmd_sensitivity(int argc, char **argv); /* src/cli/sensitivity.c */
int gs_cmd_optimise(int argc, char **argv);   /* src/cli/optimise.c */
int gs_cmd_plot(int argc, char **argv);       /* src/cli/plot.c */
int gs_cmd_geometry(int argc, char **argv);   /* src/cli/geometry.c */
/* Cases with solver.method = swa (src/cli/swa_cmd.c); both take over cfg. */
typedef struct gs_cfg gs_cfg;
int gs_cmd_run_swa(gs_cfg *cfg, const char *path, const char *out, int progress, int resume);
#endif
