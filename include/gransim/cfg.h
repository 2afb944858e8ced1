/* gransim — configuration tree read from YAML case files (libyaml).
 *
 * A case file is loaded once into a tree of nodes that remember their source
 * file, line and path (e.g. "mechanisms[1].kernel").  Consumers read keys
 * through the typed accessors below, which validate the value where it is
 * read and produce messages of the form
 *
 *   case.yaml:12: mechanisms[0].kernel.beta0 = 'abc': expected a number
 *
 * Every key fetched from a map is marked as used; gs_cfg_check_unused() then
 * reports any key nobody asked for ("unknown key"), listing the keys that
 * were expected.  This is how typos in case files become errors instead of
 * silently ignored settings. */
#ifndef GRANSIM_CFG_H
#define GRANSIM_CFG_H

#include <stddef.h>
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_cfg gs_cfg;           /* a loaded document; owns all nodes */
typedef struct gs_cfg_node gs_cfg_node; /* one node of the tree */

typedef enum { GS_CFG_SCALAR, GS_CFG_MAP, GS_CFG_SEQ } gs_cfg_kind;

/* Load a YAML file / string.  name is used as the file name in messages.
 * Returns NULL and fills err on failure (syntax errors name line and column).
 * Anchors/aliases are rejected with a clear message; duplicate keys in a map
 * are an error. */
gs_cfg *gs_cfg_load_file(const char *path, gs_error *err);
gs_cfg *gs_cfg_load_string(const char *text, const char *name, gs_error *err);
void gs_cfg_free(gs_cfg *cfg);

/* A fresh copy of a loaded document, parsed again from its text: same name,
 * directory (relative paths resolve alike) and source, no key marked used.
 * Studies build every run's case from its own copy, so that runs on several
 * threads never share the marks the accessors set. */
gs_cfg *gs_cfg_copy(const gs_cfg *cfg, gs_error *err);

gs_cfg_node *gs_cfg_root(gs_cfg *cfg);   /* NULL for an empty document */
const char *gs_cfg_source(const gs_cfg *cfg); /* full text of the file, for the case echo */
const char *gs_cfg_name(const gs_cfg *cfg);   /* file name as given */
/* Directory of the file ("." for strings), for resolving relative paths in the case. */
const char *gs_cfg_dir(const gs_cfg *cfg);

/* --- generic node access ------------------------------------------------ */
gs_cfg_kind gs_cfg_kind_of(const gs_cfg_node *n);
int gs_cfg_line(const gs_cfg_node *n);         /* 1-based source line */
const char *gs_cfg_path(const gs_cfg_node *n); /* e.g. "grid.axes[0].ratio"; "" for root */
const char *gs_cfg_file(const gs_cfg_node *n); /* file name for messages */
const char *gs_cfg_scalar(const gs_cfg_node *n); /* text of a scalar, NULL otherwise */
size_t gs_cfg_size(const gs_cfg_node *n);       /* entries of a map or seq, 0 for scalars */
gs_cfg_node *gs_cfg_item(gs_cfg_node *seq, size_t i); /* i-th element of a sequence */
const char *gs_cfg_key_at(const gs_cfg_node *map, size_t i);
gs_cfg_node *gs_cfg_value_at(gs_cfg_node *map, size_t i); /* marks the key used */

/* Look a key up in a map and mark it used.  NULL if absent (or n not a map). */
gs_cfg_node *gs_cfg_get(gs_cfg_node *map, const char *key);

/* The node at a dotted path of map keys and 0-based sequence indices
 * ("mechanisms.0.kernel.beta0", "output.end"), or NULL with err saying which
 * part is missing and what is there instead.  Marks nothing used. */
gs_cfg_node *gs_cfg_find(gs_cfg *cfg, const char *dotted, gs_error *err);
/* Replace the text of the scalar at a dotted path by value (as if the file
 * said so); the case reader then validates it like any value it reads.  The
 * path must exist and name a scalar: setting a key the file lacks would
 * bypass the reader's unknown-key check on a typo.  gs_cfg_source (the case
 * echo) still shows the file as read.  GS_EINPUT with a message naming the
 * path otherwise. */
int gs_cfg_set(gs_cfg *cfg, const char *dotted, const char *value, gs_error *err);

/* Format an error about node n (file:line: path = 'value': message). */
int gs_cfg_fail(const gs_cfg_node *n, gs_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* --- typed accessors on map keys ----------------------------------------
 * "_req" variants fail with "FILE:LINE: missing key 'k' in PATH" when absent.
 * "_opt" variants store def when absent.  All fail with file:line:path on a
 * value of the wrong type.  Return GS_OK or GS_EINPUT. */
int gs_cfg_require_kind(const gs_cfg_node *n, gs_cfg_kind kind, gs_error *err);
int gs_cfg_map_req(gs_cfg_node *map, const char *key, gs_cfg_node **out, gs_error *err);
int gs_cfg_seq_req(gs_cfg_node *map, const char *key, gs_cfg_node **out, gs_error *err);

int gs_cfg_double_req(gs_cfg_node *map, const char *key, double *out, gs_error *err);
int gs_cfg_double_opt(gs_cfg_node *map, const char *key, double def, double *out, gs_error *err);
/* Range-checked doubles: lo/hi bounds, strict selects > / < instead of >= / <=. */
int gs_cfg_double_range(gs_cfg_node *map, const char *key, int required, double def, double lo,
                        int lo_strict, double hi, int hi_strict, double *out, gs_error *err);
int gs_cfg_long_range(gs_cfg_node *map, const char *key, int required, long def, long lo, long hi,
                      long *out, gs_error *err);
int gs_cfg_bool_opt(gs_cfg_node *map, const char *key, int def, int *out, gs_error *err);
/* String: returned pointer lives as long as the gs_cfg. */
int gs_cfg_string_req(gs_cfg_node *map, const char *key, const char **out, gs_error *err);
int gs_cfg_string_opt(gs_cfg_node *map, const char *key, const char *def, const char **out,
                      gs_error *err);
/* One of a fixed set of words (NULL-terminated list); stores the index. */
int gs_cfg_enum_opt(gs_cfg_node *map, const char *key, const char *const *choices, int def,
                    int *out, gs_error *err);
/* A sequence of numbers, or (if allow_scalar) a single number read as a list
 * of length 1.  *out is malloc'ed; caller frees. */
int gs_cfg_doubles_req(gs_cfg_node *map, const char *key, int allow_scalar, double **out,
                       size_t *n, gs_error *err);

/* A number or a list of one number per compartment (n compartments) into
 * out[0..n); def when absent and not required; every entry > lo (lo_strict)
 * or >= lo.  Shared by the solvers' per-compartment rate constants. */
int gs_cfg_per_comp(gs_cfg_node *map, const char *key, int required, double def, double lo,
                    int lo_strict, size_t n, double *out, gs_error *err);

/* Open the case fragment `gransim compartments` writes, named by the scalar
 * node fn (relative to dir, the case file's folder), and check that its
 * `compartments` equals ncomp.  NULL with err naming fn's file, line and the
 * fragment on failure; the caller frees the document. */
gs_cfg *gs_cfg_fragment_load(gs_cfg_node *fn, const char *dir, size_t ncomp, gs_error *err);

/* Parse a scalar node as a number (helper for sequences). */
int gs_cfg_node_double(const gs_cfg_node *n, double *out, gs_error *err);

/* Set key of map to a scalar (replacing its value, or adding the key): a
 * coupled case points its kernels at the tables it wrote before the case is
 * read (src/couple).  The new node takes map's file and line for messages. */
int gs_cfg_set_scalar(gs_cfg_node *map, const char *key, const char *text, gs_error *err);

/* "FILE:LINE: missing key 'key' HINT in PATH" (hint may be NULL),
 * e.g. "(linear, geometric or edges)"; but when map has a key nobody asked
 * for that looks like a misspelling of key, the message is at that key's own
 * line: "FILE:LINE: unknown key 'kernal' in PATH: did you mean 'kernel'?
 * (missing key 'kernel' ...)".  Returns GS_EINPUT. */
int gs_cfg_missing(const gs_cfg_node *map, const char *key, const char *hint, gs_error *err);

/* Report the first key of map that no accessor asked for:
 *   case.yaml:7: unknown key 'ratoi' in grid.axes[0]: did you mean 'ratio'? expected one of: name, type, cells, ratio
 * Also fails if map is not a map.  Call after reading all keys of a section. */
int gs_cfg_check_unused(const gs_cfg_node *map, gs_error *err);

/* Registries of named types: NULL-terminated arrays of pointers to type
 * structs whose first member is `const char *name`.  gs_registry_find: the
 * entry called name, or NULL; gs_registry_names: "a, b, c" into buf. */
const void *gs_registry_find(const void *const *types, const char *name);
void gs_registry_names(const void *const *types, char *buf, size_t size);
/* Read node's "type" and return the entry of the NULL-terminated
 * registry `types` with that name.  Every registered type struct starts with
 * its `const char *name`.  Unknown names give an error listing the known ones;
 * `what` names the registry in messages ("kernel", "selection function"...). */
const void *gs_registry_pick(gs_cfg_node *node, const void *const *types, const char *what,
                             gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
