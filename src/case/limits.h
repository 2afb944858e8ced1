/* Resources a case will need, stated before they are taken: the memory of a
 * run and the size of its result files, against the case's `limits` keys
 * (docs/case-files.md).  A case above a limit is refused at check time with
 * the figure, the key and the limit. */
#ifndef GRANSIM_CASE_LIMITS_H
#define GRANSIM_CASE_LIMITS_H

#include "gransim/case.h"

typedef struct {
  double memory_gb, output_gb; /* limits.memory_gb, limits.output_gb */
  gs_cfg_node *node;           /* the limits map, or NULL */
} gs_limits;

/* Reads `limits` (defaults: 80 % of the machine's memory; 10 GB of output). */
int gs_limits_read(gs_cfg_node *root, gs_limits *lim, gs_error *err);
/* Before the mechanisms are built: the least memory a run of this grid and
 * these mechanisms needs (the state's vectors and the pages each mechanism
 * keeps per compartment, gs_mech_type.pages_per_compartment). */
int gs_limits_check_memory(const gs_limits *lim, gs_cfg_node *root, const gs_model *m,
                           gs_error *err);
/* Once the output times are known: the bytes result.h5 and summary.csv
 * will hold (before compression). */
int gs_limits_check_output(const gs_limits *lim, gs_cfg_node *root, const gs_model *m,
                           size_t ntimes, gs_error *err);
double gs_limits_output_bytes(const gs_model *m, size_t ntimes);
double gs_limits_memory_bytes(const gs_model *m, int pages);
#endif
