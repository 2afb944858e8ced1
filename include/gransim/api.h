/* gransim — one entry point for every kind of case, for programs and other
 * languages (the Python package loads libgransim.so and calls these).
 *
 * A case is loaded from a file or from text, keys are changed by dotted paths
 * as in `gransim sweep` ("mechanisms.0.kernel.beta0"), and it is checked or
 * run whatever its kind: sectional, stochastic (solver.method: swa), DEM (a
 * top-level `dem:` section without a grid) or coupled (a `coupling:` section).
 * Every function reports failure through a gs_error and returns; nothing
 * exits the process, and a failed run leaves no result files.  `gransim check`
 * is gs_api_case_check. */
#ifndef GRANSIM_API_H
#define GRANSIM_API_H

#include <stddef.h>

#include "gransim/cfg.h"
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { GS_API_SECTIONAL = 0, GS_API_SWA = 1, GS_API_DEM = 2, GS_API_COUPLED = 3 } gs_api_kind;

typedef struct gs_api_case gs_api_case;

/* Load a case file (relative paths in it resolve against its folder), or a
 * case given as YAML text (JSON is YAML too) called name in messages, whose
 * relative paths resolve against the current folder.  NULL and err on failure. */
gs_api_case *gs_api_case_load(const char *path, gs_error *err);
gs_api_case *gs_api_case_from_text(const char *text, const char *name, gs_error *err);
void gs_api_case_free(gs_api_case *c);

/* Set the scalar at a dotted path to value (as if the file said so); the path
 * must exist (gs_cfg_set).  The value is validated when the case is checked
 * or run, with the file and line of the key in the message. */
int gs_api_case_set(gs_api_case *c, const char *dotted, const char *value, gs_error *err);

/* The kind of the case as it stands (solver.method may have been changed). */
gs_api_kind gs_api_case_kind(const gs_api_case *c);
const char *gs_api_kind_name(gs_api_kind kind); /* "sectional", "swa", "dem", "coupled" */
/* The kind of a loaded case file, from its top-level keys (nothing marked used). */
gs_api_kind gs_api_kind_of_cfg(gs_cfg *cfg);

/* Read and validate the case as a run would, without running it; desc gets
 * one line saying what it describes. */
int gs_api_case_check(const gs_api_case *c, char *desc, size_t n, gs_error *err);

/* Run the case into out_dir (created if needed): result.h5 and summary.csv of
 * a sectional or stochastic case, the tables of a DEM case, both stages of a
 * coupled case.  progress: 1 progress lines on stderr, 0 none, -1 when stderr
 * is a terminal.  Runs on this process (no MPI ranks). */
int gs_api_case_run(const gs_api_case *c, const char *out_dir, int progress, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
