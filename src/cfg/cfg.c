/* Configuration tree read from YAML with libyaml's event API: see
 * include/gransim/cfg.h.
 *
 * The whole document is turned into a tree up front so that every accessor
 * can name the file, line and path of the value it rejects, and so that
 * unused keys can be reported after a section has been read. */
#include "gransim/cfg.h"
#include "cfg/nearest.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <yaml.h>

/* Deeper nesting than this is certainly a mistake, and bounding it keeps the
 * recursive builder and gs_cfg_free safe from stack exhaustion. */
#define GS_CFG_MAX_DEPTH 200
/* Scalars longer than this are cut in messages so that one line stays readable. */
#define GS_CFG_MSG_VALUE_MAX 80

typedef struct {
  char *key;
  int line; /* line of the key itself, for unknown/duplicate key messages */
  int used;
  gs_cfg_node *value;
} gs_cfg_entry;

struct gs_cfg_node {
  gs_cfg_kind kind;
  int line;
  const char *file; /* borrowed from the owning gs_cfg */
  char *path;
  char *text;             /* scalars */
  gs_cfg_entry *entries;  /* maps */
  gs_cfg_node **items;    /* sequences */
  size_t n, cap;
  char **asked; /* every key name an accessor looked up, for "expected one of" */
  size_t nasked, capasked;
};

struct gs_cfg {
  char *name;
  char *dir;
  char *source;
  gs_cfg_node *root;
};

/* --- small helpers -------------------------------------------------------- */

static char *gs_strndup(const char *s, size_t len, gs_error *err) {
  char *d = gs_malloc(len + 1, err);
  if (!d) return NULL;
  memcpy(d, s, len);
  d[len] = '\0';
  return d;
}

static char *gs_strdup(const char *s, gs_error *err) { return gs_strndup(s, strlen(s), err); }

/* Ensure room for need elements of size elem in *arr. */
static int gs_grow(void **arr, size_t *cap, size_t need, size_t elem, gs_error *err) {
  if (need <= *cap) return GS_OK;
  size_t ncap = *cap ? *cap * 2 : 4;
  while (ncap < need) ncap *= 2;
  void *p = realloc(*arr, ncap * elem);
  if (!p) return gs_error_set(err, GS_ENOMEM, "out of memory reading configuration");
  *arr = p;
  *cap = ncap;
  return GS_OK;
}

/* "parent.key", or "key" at the root. */
static char *gs_path_key(const char *parent, const char *key, gs_error *err) {
  size_t lp = strlen(parent), lk = strlen(key);
  char *p = gs_malloc(lp + lk + 2, err);
  if (!p) return NULL;
  if (lp) snprintf(p, lp + lk + 2, "%s.%s", parent, key);
  else memcpy(p, key, lk + 1);
  return p;
}

/* "parent[i]". */
static char *gs_path_index(const char *parent, size_t i, gs_error *err) {
  size_t len = strlen(parent) + 24;
  char *p = gs_malloc(len, err);
  if (p) snprintf(p, len, "%s[%zu]", parent, i);
  return p;
}

/* Path as shown to the user: the root has no path of its own. */
static const char *gs_path_shown(const gs_cfg_node *n) {
  return n->path[0] ? n->path : "the top level";
}

static void gs_node_free(gs_cfg_node *n) {
  if (!n) return;
  for (size_t i = 0; i < n->n; i++) {
    if (n->kind == GS_CFG_MAP) {
      free(n->entries[i].key);
      gs_node_free(n->entries[i].value);
    } else if (n->kind == GS_CFG_SEQ) {
      gs_node_free(n->items[i]);
    }
  }
  for (size_t i = 0; i < n->nasked; i++) free(n->asked[i]);
  free(n->asked);
  free(n->entries);
  free(n->items);
  free(n->text);
  free(n->path);
  free(n);
}

static gs_cfg_node *gs_node_new(gs_cfg_kind kind, int line, const char *file, const char *path,
                                gs_error *err) {
  gs_cfg_node *n = gs_calloc(1, sizeof *n, err);
  if (!n) return NULL;
  n->kind = kind;
  n->line = line;
  n->file = file;
  n->path = gs_strdup(path, err);
  if (!n->path) {
    free(n);
    return NULL;
  }
  return n;
}

/* --- building the tree from libyaml events --------------------------------- */

typedef struct {
  yaml_parser_t parser;
  const char *name;
  const char *text;
  size_t len;
  gs_error *err;
} gs_loader;

/* 1-based line of a byte offset, for reader errors that carry no mark. */
static size_t gs_line_of_offset(const char *text, size_t len, size_t off) {
  size_t line = 1;
  for (size_t i = 0; i < off && i < len; i++)
    if (text[i] == '\n') line++;
  return line;
}

static int gs_syntax_error(gs_loader *L) {
  const yaml_parser_t *p = &L->parser;
  if (p->error == YAML_MEMORY_ERROR)
    return gs_error_set(L->err, GS_ENOMEM, "%s: out of memory parsing YAML", L->name);
  const char *problem = p->problem ? p->problem : "unknown error";
  if (p->error == YAML_READER_ERROR)
    return gs_error_set(L->err, GS_EINPUT, "%s:%zu: YAML syntax error: %s (byte offset %zu)",
                        L->name, gs_line_of_offset(L->text, L->len, p->problem_offset), problem,
                        p->problem_offset);
  return gs_error_set(L->err, GS_EINPUT, "%s:%zu:%zu: YAML syntax error: %s%s%s", L->name,
                      p->problem_mark.line + 1, p->problem_mark.column + 1, problem,
                      p->context ? " " : "", p->context ? p->context : "");
}

static int gs_next_event(gs_loader *L, yaml_event_t *ev) {
  if (!yaml_parser_parse(&L->parser, ev)) return gs_syntax_error(L);
  return GS_OK;
}

static int gs_event_line(const yaml_event_t *ev) { return (int)ev->start_mark.line + 1; }

/* Anchors and aliases would make the tree a graph and hide where a value
 * came from in messages; case files must spell every value out. */
static int gs_reject_anchor(gs_loader *L, const yaml_event_t *ev) {
  const yaml_char_t *anchor = NULL;
  if (ev->type == YAML_SCALAR_EVENT) anchor = ev->data.scalar.anchor;
  else if (ev->type == YAML_MAPPING_START_EVENT) anchor = ev->data.mapping_start.anchor;
  else if (ev->type == YAML_SEQUENCE_START_EVENT) anchor = ev->data.sequence_start.anchor;
  if (ev->type == YAML_ALIAS_EVENT)
    return gs_error_set(L->err, GS_EINPUT,
                        "%s:%d: YAML aliases (*%s) are not supported in case files; "
                        "write the value out in full",
                        L->name, gs_event_line(ev), (const char *)ev->data.alias.anchor);
  if (anchor)
    return gs_error_set(L->err, GS_EINPUT,
                        "%s:%d: YAML anchors (&%s) are not supported in case files; "
                        "write the value out in full",
                        L->name, gs_event_line(ev), (const char *)anchor);
  return GS_OK;
}

static int gs_parse_node(gs_loader *L, const yaml_event_t *ev, const char *path, int depth,
                         gs_cfg_node **out);

/* Read the next event and build the node it starts. */
static int gs_parse_next(gs_loader *L, const char *path, int depth, gs_cfg_node **out) {
  yaml_event_t ev;
  int rc = gs_next_event(L, &ev);
  if (rc) return rc;
  rc = gs_parse_node(L, &ev, path, depth, out);
  yaml_event_delete(&ev);
  return rc;
}

static const gs_cfg_entry *gs_find_entry(const gs_cfg_node *map, const char *key) {
  for (size_t i = 0; i < map->n; i++)
    if (strcmp(map->entries[i].key, key) == 0) return &map->entries[i];
  return NULL;
}

/* Validate a key event of map and add an entry for it (value still NULL). */
static int gs_add_key(gs_loader *L, gs_cfg_node *map, const yaml_event_t *kev) {
  int line = gs_event_line(kev);
  if (kev->type != YAML_SCALAR_EVENT) {
    int rc = gs_reject_anchor(L, kev);
    if (rc) return rc;
    return gs_error_set(L->err, GS_EINPUT,
                        "%s:%d: in %s: a key must be a single word, not a map or a list",
                        L->name, line, gs_path_shown(map));
  }
  int rc = gs_reject_anchor(L, kev);
  if (rc) return rc;
  const char *key = (const char *)kev->data.scalar.value;
  const gs_cfg_entry *prev = gs_find_entry(map, key);
  if (prev)
    return gs_error_set(L->err, GS_EINPUT,
                        "%s:%d: duplicate key '%s' in %s (first given on line %d)", L->name, line,
                        key, gs_path_shown(map), prev->line);
  rc = gs_grow((void **)&map->entries, &map->cap, map->n + 1, sizeof *map->entries, L->err);
  if (rc) return rc;
  gs_cfg_entry *e = &map->entries[map->n];
  e->key = gs_strndup(key, kev->data.scalar.length, L->err);
  if (!e->key) return GS_ENOMEM;
  e->line = line;
  e->used = 0;
  e->value = NULL;
  map->n++;
  return GS_OK;
}

static int gs_parse_map(gs_loader *L, gs_cfg_node *map, int depth) {
  for (;;) {
    yaml_event_t kev;
    int rc = gs_next_event(L, &kev);
    if (rc) return rc;
    if (kev.type == YAML_MAPPING_END_EVENT) {
      yaml_event_delete(&kev);
      return GS_OK;
    }
    rc = gs_add_key(L, map, &kev);
    yaml_event_delete(&kev);
    if (rc) return rc;
    gs_cfg_entry *e = &map->entries[map->n - 1];
    char *cpath = gs_path_key(map->path, e->key, L->err);
    if (!cpath) return GS_ENOMEM;
    rc = gs_parse_next(L, cpath, depth + 1, &e->value);
    free(cpath);
    if (rc) return rc;
  }
}

static int gs_parse_seq(gs_loader *L, gs_cfg_node *seq, int depth) {
  for (;;) {
    yaml_event_t ev;
    int rc = gs_next_event(L, &ev);
    if (rc) return rc;
    if (ev.type == YAML_SEQUENCE_END_EVENT) {
      yaml_event_delete(&ev);
      return GS_OK;
    }
    rc = gs_grow((void **)&seq->items, &seq->cap, seq->n + 1, sizeof *seq->items, L->err);
    char *cpath = rc ? NULL : gs_path_index(seq->path, seq->n, L->err);
    if (cpath) {
      seq->items[seq->n] = NULL;
      rc = gs_parse_node(L, &ev, cpath, depth + 1, &seq->items[seq->n]);
      if (!rc) seq->n++;
    } else if (!rc) {
      rc = GS_ENOMEM;
    }
    free(cpath);
    yaml_event_delete(&ev);
    if (rc) return rc;
  }
}

/* Build the node started by ev (a scalar, mapping start or sequence start).
 * On failure nothing is left allocated and *out is untouched. */
static int gs_parse_node(gs_loader *L, const yaml_event_t *ev, const char *path, int depth,
                         gs_cfg_node **out) {
  int rc = gs_reject_anchor(L, ev);
  if (rc) return rc;
  int line = gs_event_line(ev);
  if (depth > GS_CFG_MAX_DEPTH)
    return gs_error_set(L->err, GS_EINPUT, "%s:%d: nesting deeper than %d levels", L->name,
                        line, GS_CFG_MAX_DEPTH);
  gs_cfg_kind kind;
  if (ev->type == YAML_SCALAR_EVENT) kind = GS_CFG_SCALAR;
  else if (ev->type == YAML_MAPPING_START_EVENT) kind = GS_CFG_MAP;
  else if (ev->type == YAML_SEQUENCE_START_EVENT) kind = GS_CFG_SEQ;
  else
    return gs_error_set(L->err, GS_EINPUT, "%s:%d: unexpected YAML event", L->name, line);
  gs_cfg_node *n = gs_node_new(kind, line, L->name, path, L->err);
  if (!n) return GS_ENOMEM;
  if (kind == GS_CFG_SCALAR) {
    n->text = gs_strndup((const char *)ev->data.scalar.value, ev->data.scalar.length, L->err);
    rc = n->text ? GS_OK : GS_ENOMEM;
  } else if (kind == GS_CFG_MAP) {
    rc = gs_parse_map(L, n, depth);
  } else {
    rc = gs_parse_seq(L, n, depth);
  }
  if (rc) {
    gs_node_free(n);
    return rc;
  }
  *out = n;
  return GS_OK;
}

/* Read the next event, which libyaml's grammar guarantees to be of type. */
static int gs_expect(gs_loader *L, yaml_event_type_t type) {
  yaml_event_t ev;
  int rc = gs_next_event(L, &ev);
  if (rc) return rc;
  int line = gs_event_line(&ev), ok = ev.type == type;
  yaml_event_delete(&ev);
  if (ok) return GS_OK;
  return gs_error_set(L->err, GS_EINPUT, "%s:%d: unexpected YAML structure", L->name, line);
}

/* Parse the stream into cfg->root: zero or one document. */
static int gs_parse_stream(gs_loader *L, gs_cfg *cfg) {
  int rc = gs_expect(L, YAML_STREAM_START_EVENT);
  if (rc) return rc;
  yaml_event_t ev;
  rc = gs_next_event(L, &ev);
  if (rc) return rc;
  int empty = ev.type == YAML_STREAM_END_EVENT;
  yaml_event_delete(&ev);
  if (empty) return GS_OK; /* nothing but comments or whitespace */
  rc = gs_parse_next(L, "", 0, &cfg->root);
  if (!rc) rc = gs_expect(L, YAML_DOCUMENT_END_EVENT);
  if (!rc) rc = gs_next_event(L, &ev);
  if (rc) return rc;
  int line = gs_event_line(&ev), more = ev.type != YAML_STREAM_END_EVENT;
  yaml_event_delete(&ev);
  if (more)
    return gs_error_set(L->err, GS_EINPUT,
                        "%s:%d: a case file must hold a single YAML document "
                        "(found a second '---')",
                        L->name, line);
  return GS_OK;
}

/* Parse text (len bytes) into cfg, which already owns name/dir/source. */
static int gs_cfg_parse(gs_cfg *cfg, const char *text, size_t len, gs_error *err) {
  gs_loader L = {.name = cfg->name, .text = text, .len = len, .err = err};
  if (!yaml_parser_initialize(&L.parser))
    return gs_error_set(err, GS_ENOMEM, "%s: cannot initialise the YAML parser", cfg->name);
  yaml_parser_set_input_string(&L.parser, (const unsigned char *)text, len);
  int rc = gs_parse_stream(&L, cfg);
  yaml_parser_delete(&L.parser);
  if (rc) return rc;
  /* A bare "---" yields one empty scalar: treat it like an empty file. */
  if (cfg->root && cfg->root->kind == GS_CFG_SCALAR && cfg->root->text[0] == '\0') {
    gs_node_free(cfg->root);
    cfg->root = NULL;
  }
  return GS_OK;
}

/* --- loading ----------------------------------------------------------------- */

/* Directory part of path; "." when it has none. */
static char *gs_dirname(const char *path, gs_error *err) {
  const char *slash = strrchr(path, '/');
  if (!slash) return gs_strdup(".", err);
  if (slash == path) return gs_strdup("/", err);
  return gs_strndup(path, (size_t)(slash - path), err);
}

static gs_cfg *gs_cfg_build(char *source, size_t len, const char *name, const char *dir,
                            gs_error *err) {
  gs_cfg *cfg = gs_calloc(1, sizeof *cfg, err);
  if (!cfg) {
    free(source);
    return NULL;
  }
  cfg->source = source;
  cfg->name = gs_strdup(name, err);
  cfg->dir = dir ? gs_dirname(dir, err) : gs_strdup(".", err);
  if (!cfg->name || !cfg->dir || gs_cfg_parse(cfg, source, len, err)) {
    gs_cfg_free(cfg);
    return NULL;
  }
  return cfg;
}

/* Read a whole stream; *len gets its size.  NULL with errno set on failure. */
static char *gs_read_all(FILE *f, size_t *len) {
  size_t cap = 4096, n = 0;
  char *buf = malloc(cap);
  while (buf) {
    n += fread(buf + n, 1, cap - n - 1, f);
    if (ferror(f)) break;
    if (feof(f)) {
      buf[n] = '\0';
      *len = n;
      return buf;
    }
    if (n + 1 == cap) {
      char *nb = realloc(buf, cap * 2);
      if (!nb) break;
      buf = nb;
      cap *= 2;
    }
  }
  int saved = errno ? errno : ENOMEM;
  free(buf);
  errno = saved;
  return NULL;
}

gs_cfg *gs_cfg_load_file(const char *path, gs_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    gs_error_set(err, GS_EIO, "cannot open case file '%s': %s", path, strerror(errno));
    return NULL;
  }
  size_t len = 0;
  errno = 0;
  char *text = gs_read_all(f, &len);
  int saved = errno;
  fclose(f);
  if (!text) {
    gs_error_set(err, GS_EIO, "cannot read case file '%s': %s", path, strerror(saved));
    return NULL;
  }
  return gs_cfg_build(text, len, path, path, err);
}

gs_cfg *gs_cfg_load_string(const char *text, const char *name, gs_error *err) {
  char *copy = gs_strdup(text, err);
  if (!copy) return NULL;
  return gs_cfg_build(copy, strlen(copy), name ? name : "<string>", NULL, err);
}

void gs_cfg_free(gs_cfg *cfg) {
  if (!cfg) return;
  gs_node_free(cfg->root);
  free(cfg->name);
  free(cfg->dir);
  free(cfg->source);
  free(cfg);
}

/* Carries the values set since parsing (gs_cfg_set, gs_cfg_set_scalar) from
 * src onto dst, the same source parsed afresh: a copy of a varied case must
 * be that case, not its file (optimise starts from a copy's values). */
static int gs_node_sync(gs_cfg_node *dst, const gs_cfg_node *src, gs_error *err) {
  if (dst->kind != src->kind)
    return gs_error_set(err, GS_EINPUT, "copying the case: %s changed its kind", gs_path_shown(src));
  if (src->kind == GS_CFG_SCALAR) {
    if (!strcmp(dst->text ? dst->text : "", src->text ? src->text : "")) return GS_OK;
    char *t = gs_strdup(src->text ? src->text : "", err);
    if (!t) return GS_ENOMEM;
    free(dst->text);
    dst->text = t;
    return GS_OK;
  }
  for (size_t i = 0; i < src->n; i++) {
    if (src->kind == GS_CFG_SEQ) {
      if (i >= dst->n)
        return gs_error_set(err, GS_EINPUT, "copying the case: %s grew", gs_path_shown(src));
      if (gs_node_sync(dst->items[i], src->items[i], err)) return err->code;
      continue;
    }
    const gs_cfg_entry *e = &src->entries[i];
    size_t j = 0;
    while (j < dst->n && strcmp(dst->entries[j].key, e->key)) j++;
    int rc = j < dst->n ? gs_node_sync(dst->entries[j].value, e->value, err)
             : e->value->kind == GS_CFG_SCALAR
                 ? gs_cfg_set_scalar(dst, e->key, e->value->text ? e->value->text : "", err)
                 : gs_error_set(err, GS_EINPUT, "copying the case: %s gained a map or list",
                                gs_path_shown(src));
    if (rc) return rc;
  }
  return GS_OK;
}

gs_cfg *gs_cfg_copy(const gs_cfg *cfg, gs_error *err) {
  if (!cfg) {
    gs_error_set(err, GS_EINPUT, "no configuration to copy");
    return NULL;
  }
  gs_cfg *c = gs_calloc(1, sizeof *c, err);
  if (!c) return NULL;
  c->source = gs_strdup(cfg->source, err);
  c->name = gs_strdup(cfg->name, err);
  c->dir = gs_strdup(cfg->dir, err);
  if (!c->source || !c->name || !c->dir || gs_cfg_parse(c, c->source, strlen(c->source), err) ||
      (cfg->root && c->root && gs_node_sync(c->root, cfg->root, err))) { /* an empty file has no root */
    gs_cfg_free(c);
    return NULL;
  }
  return c;
}

gs_cfg_node *gs_cfg_root(gs_cfg *cfg) { return cfg ? cfg->root : NULL; }
const char *gs_cfg_source(const gs_cfg *cfg) { return cfg ? cfg->source : ""; }
const char *gs_cfg_name(const gs_cfg *cfg) { return cfg ? cfg->name : ""; }
const char *gs_cfg_dir(const gs_cfg *cfg) { return cfg ? cfg->dir : "."; }

/* --- generic node access --------------------------------------------------- */

gs_cfg_kind gs_cfg_kind_of(const gs_cfg_node *n) { return n ? n->kind : GS_CFG_SCALAR; }
int gs_cfg_line(const gs_cfg_node *n) { return n ? n->line : 0; }
const char *gs_cfg_path(const gs_cfg_node *n) { return n ? n->path : ""; }
const char *gs_cfg_file(const gs_cfg_node *n) { return n ? n->file : ""; }

const char *gs_cfg_scalar(const gs_cfg_node *n) {
  return n && n->kind == GS_CFG_SCALAR ? n->text : NULL;
}

size_t gs_cfg_size(const gs_cfg_node *n) {
  return n && n->kind != GS_CFG_SCALAR ? n->n : 0;
}

gs_cfg_node *gs_cfg_item(gs_cfg_node *seq, size_t i) {
  return seq && seq->kind == GS_CFG_SEQ && i < seq->n ? seq->items[i] : NULL;
}

const char *gs_cfg_key_at(const gs_cfg_node *map, size_t i) {
  return map && map->kind == GS_CFG_MAP && i < map->n ? map->entries[i].key : NULL;
}

gs_cfg_node *gs_cfg_value_at(gs_cfg_node *map, size_t i) {
  if (!map || map->kind != GS_CFG_MAP || i >= map->n) return NULL;
  map->entries[i].used = 1;
  return map->entries[i].value;
}

/* Remember that key was asked for, so unknown-key messages can list it.
 * Failure to remember only degrades that list, so it is not an error. */
static void gs_note_asked(gs_cfg_node *map, const char *key) {
  for (size_t i = 0; i < map->nasked; i++)
    if (strcmp(map->asked[i], key) == 0) return;
  if (gs_grow((void **)&map->asked, &map->capasked, map->nasked + 1, sizeof *map->asked, NULL))
    return;
  char *copy = gs_strdup(key, NULL);
  if (copy) map->asked[map->nasked++] = copy;
}

gs_cfg_node *gs_cfg_get(gs_cfg_node *map, const char *key) {
  if (!map || map->kind != GS_CFG_MAP || !key) return NULL;
  gs_note_asked(map, key);
  for (size_t i = 0; i < map->n; i++) {
    if (strcmp(map->entries[i].key, key) == 0) {
      map->entries[i].used = 1;
      return map->entries[i].value;
    }
  }
  return NULL;
}

/* --- dotted paths (studies vary one value of a case) ---------------------- */

/* "a, b, c": the keys of map, for "it has: ..." hints. */
static void gs_keys_of(const gs_cfg_node *map, char *buf, size_t size) {
  size_t at = 0;
  buf[0] = '\0';
  for (size_t i = 0; i < map->n && at + 1 < size; i++) {
    int w = snprintf(buf + at, size - at, "%s%s", i ? ", " : "", map->entries[i].key);
    if (w < 0) break;
    at += (size_t)w;
  }
}

gs_cfg_node *gs_cfg_find(gs_cfg *cfg, const char *dotted, gs_error *err) {
  gs_cfg_node *n = cfg ? cfg->root : NULL;
  const char *p = dotted ? dotted : "";
  if (!*p) {
    gs_error_set(err, GS_EINPUT, "empty key");
    return NULL;
  }
  if (!n) {
    gs_error_set(err, GS_EINPUT, "key '%s': the case file is empty", dotted);
    return NULL;
  }
  while (*p) {
    size_t len = strcspn(p, ".");
    char part[256];
    if (len == 0 || len >= sizeof part) {
      gs_error_set(err, GS_EINPUT, "key '%s': %s", dotted,
                   len ? "a part is too long" : "empty part (two dots, or a dot at an end)");
      return NULL;
    }
    memcpy(part, p, len);
    part[len] = '\0';
    const char *where = gs_path_shown(n);
    if (n->kind == GS_CFG_MAP) {
      gs_cfg_node *next = NULL;
      for (size_t i = 0; i < n->n && !next; i++)
        if (strcmp(n->entries[i].key, part) == 0) next = n->entries[i].value;
      if (!next) {
        char keys[512], hint[128] = "";
        gs_keys_of(n, keys, sizeof keys);
        const gs_cfg_entry *near = NULL;
        for (size_t i = 0; i < n->n; i++) {
          const char *const one[] = {n->entries[i].key};
          if (gs_nearest_word(part, one, 1) &&
              (!near || gs_edit_distance(part, one[0]) < gs_edit_distance(part, near->key)))
            near = &n->entries[i];
        }
        if (near) snprintf(hint, sizeof hint, "; did you mean '%s'?", near->key);
        gs_error_set(err, GS_EINPUT, "key '%s': the case has no '%s' in %s (it has: %s)%s", dotted,
                     part, where, keys, hint);
        return NULL;
      }
      n = next;
    } else if (n->kind == GS_CFG_SEQ) {
      char *end = NULL;
      unsigned long i = strtoul(part, &end, 10);
      if (!isdigit((unsigned char)part[0]) || *end) {
        gs_error_set(err, GS_EINPUT, "key '%s': %s is a list; expected an index (0, 1, ...), got '%s'",
                     dotted, where, part);
        return NULL;
      }
      if (i >= n->n) {
        gs_error_set(err, GS_EINPUT, "key '%s': %s has %zu entr%s (indices from 0), no %lu", dotted,
                     where, n->n, n->n == 1 ? "y" : "ies", i);
        return NULL;
      }
      n = n->items[i];
    } else {
      gs_error_set(err, GS_EINPUT, "key '%s': %s is a value ('%s'), not a map or list", dotted,
                   where, n->text);
      return NULL;
    }
    p += len;
    if (*p == '.') {
      p++;
      if (!*p) {
        gs_error_set(err, GS_EINPUT, "key '%s': empty part (two dots, or a dot at an end)", dotted);
        return NULL;
      }
    }
  }
  return n;
}

int gs_cfg_set(gs_cfg *cfg, const char *dotted, const char *value, gs_error *err) {
  gs_cfg_node *n = gs_cfg_find(cfg, dotted, err);
  if (!n) return GS_EINPUT;
  if (n->kind != GS_CFG_SCALAR)
    return gs_error_set(err, GS_EINPUT, "key '%s': %s is a %s, not a single value", dotted,
                        gs_path_shown(n), n->kind == GS_CFG_MAP ? "map" : "list");
  char *copy = gs_strdup(value ? value : "", err);
  if (!copy) return GS_ENOMEM;
  free(n->text);
  n->text = copy;
  return GS_OK;
}

int gs_cfg_set_scalar(gs_cfg_node *map, const char *key, const char *text, gs_error *err) {
  if (!map || map->kind != GS_CFG_MAP) return gs_error_set(err, GS_EINPUT, "gs_cfg_set_scalar: not a map");
  char *path = gs_path_key(map->path, key, err);
  if (!path) return GS_ENOMEM;
  gs_cfg_node *n = gs_node_new(GS_CFG_SCALAR, map->line, map->file, path, err);
  free(path);
  if (!n) return GS_ENOMEM;
  if (!(n->text = gs_strdup(text, err))) {
    gs_node_free(n);
    return GS_ENOMEM;
  }
  for (size_t i = 0; i < map->n; i++)
    if (strcmp(map->entries[i].key, key) == 0) {
      gs_node_free(map->entries[i].value);
      map->entries[i].value = n;
      return GS_OK;
    }
  char *k = gs_strdup(key, err);
  if (!k || gs_grow((void **)&map->entries, &map->cap, map->n + 1, sizeof *map->entries, err)) {
    free(k);
    gs_node_free(n);
    return GS_ENOMEM;
  }
  map->entries[map->n++] = (gs_cfg_entry){.key = k, .line = map->line, .used = 0, .value = n};
  return GS_OK;
}

/* --- messages ------------------------------------------------------------------ */

/* The scalar's text as quoted in messages: first line only, length-capped. */
static void gs_value_excerpt(const char *text, char *buf, size_t size) {
  size_t len = strcspn(text, "\r\n");
  int cut = len < strlen(text);
  if (len > GS_CFG_MSG_VALUE_MAX) {
    len = GS_CFG_MSG_VALUE_MAX;
    cut = 1;
  }
  snprintf(buf, size, "%.*s%s", (int)len, text, cut ? "..." : "");
}

int gs_cfg_fail(const gs_cfg_node *n, gs_error *err, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (!n) return gs_error_set(err, GS_EINPUT, "%s", msg);
  if (n->kind != GS_CFG_SCALAR)
    return gs_error_set(err, GS_EINPUT, "%s:%d: %s: %s", n->file, n->line, gs_path_shown(n), msg);
  char value[GS_CFG_MSG_VALUE_MAX + 8];
  gs_value_excerpt(n->text, value, sizeof value);
  return gs_error_set(err, GS_EINPUT, "%s:%d: %s = '%s': %s", n->file, n->line, gs_path_shown(n),
                      value, msg);
}

static const char *gs_kind_expectation(gs_cfg_kind kind) {
  switch (kind) {
  case GS_CFG_MAP: return "expected a map (key: value entries)";
  case GS_CFG_SEQ: return "expected a list";
  default: return "expected a single value, not a map or a list";
  }
}

int gs_cfg_require_kind(const gs_cfg_node *n, gs_cfg_kind kind, gs_error *err) {
  if (!n) return gs_error_set(err, GS_EINPUT, "empty configuration: %s", gs_kind_expectation(kind));
  if (n->kind == kind) return GS_OK;
  return gs_cfg_fail(n, err, "%s", gs_kind_expectation(kind));
}

/* --- typed accessors --------------------------------------------------------------- */

/* A key of map that nothing asked for and that looks like a misspelling of
 * key, or NULL. */
static const gs_cfg_entry *gs_misspelt(const gs_cfg_node *map, const char *key) {
  for (size_t i = 0; map->kind == GS_CFG_MAP && i < map->n; i++) {
    const gs_cfg_entry *e = &map->entries[i];
    const char *const one[] = {key};
    if (!e->used && gs_nearest_word(e->key, one, 1)) return e;
  }
  return NULL;
}

int gs_cfg_missing(const gs_cfg_node *map, const char *key, const char *hint, gs_error *err) {
  if (!map)
    return gs_error_set(err, GS_EINPUT, "missing key '%s' (the configuration is empty)", key);
  const gs_cfg_entry *typo = gs_misspelt(map, key);
  if (typo) /* at the misspelt key's own line, where the fix is */
    return gs_error_set(err, GS_EINPUT, "%s:%d: unknown key '%s' in %s: did you mean '%s'? (missing key '%s'%s%s)",
                        map->file, typo->line, typo->key, gs_path_shown(map), key, key, hint ? " " : "",
                        hint ? hint : "");
  return gs_error_set(err, GS_EINPUT, "%s:%d: missing key '%s'%s%s in %s", map->file, map->line, key,
                      hint ? " " : "", hint ? hint : "", gs_path_shown(map));
}

static int gs_missing(const gs_cfg_node *map, const char *key, gs_error *err) {
  return gs_cfg_missing(map, key, NULL, err);
}

/* Look key up for an accessor.  *out is NULL when absent; fails if map is
 * not a map, or if the key is absent and required. */
static int gs_lookup(gs_cfg_node *map, const char *key, int required, gs_cfg_node **out,
                     gs_error *err) {
  *out = NULL;
  if (map) {
    int rc = gs_cfg_require_kind(map, GS_CFG_MAP, err);
    if (rc) return rc;
    *out = gs_cfg_get(map, key);
  }
  if (!*out && required) return gs_missing(map, key, err);
  return GS_OK;
}

static int gs_kind_req(gs_cfg_node *map, const char *key, gs_cfg_kind kind, gs_cfg_node **out,
                       gs_error *err) {
  gs_cfg_node *v;
  int rc = gs_lookup(map, key, 1, &v, err);
  if (!rc) rc = gs_cfg_require_kind(v, kind, err);
  if (!rc) *out = v;
  return rc;
}

int gs_cfg_map_req(gs_cfg_node *map, const char *key, gs_cfg_node **out, gs_error *err) {
  return gs_kind_req(map, key, GS_CFG_MAP, out, err);
}

int gs_cfg_seq_req(gs_cfg_node *map, const char *key, gs_cfg_node **out, gs_error *err) {
  return gs_kind_req(map, key, GS_CFG_SEQ, out, err);
}

/* YAML spells infinities and NaN ".inf"/".nan"; strtod does not know them,
 * but the user deserves the same "finite" message as for "inf". */
static int gs_is_yaml_nonfinite(const char *s) {
  if (*s == '+' || *s == '-') s++;
  return strcasecmp(s, ".inf") == 0 || strcasecmp(s, ".nan") == 0;
}

int gs_cfg_node_double(const gs_cfg_node *n, double *out, gs_error *err) {
  if (!n) return gs_error_set(err, GS_EINPUT, "expected a number");
  if (n->kind != GS_CFG_SCALAR) return gs_cfg_fail(n, err, "expected a number");
  const char *s = n->text;
  char *end = NULL;
  errno = 0;
  double v = (*s && !isspace((unsigned char)*s)) ? strtod(s, &end) : 0.0;
  if (!end || end == s || *end != '\0')
    return gs_cfg_fail(n, err, gs_is_yaml_nonfinite(s) ? "expected a finite number"
                                                         : "expected a number");
  if (!isfinite(v)) return gs_cfg_fail(n, err, "expected a finite number");
  *out = v;
  return GS_OK;
}

static int gs_node_long(const gs_cfg_node *n, long *out, gs_error *err) {
  if (n->kind != GS_CFG_SCALAR) return gs_cfg_fail(n, err, "expected an integer");
  const char *s = n->text;
  char *end = NULL;
  errno = 0;
  long v = (*s && !isspace((unsigned char)*s)) ? strtol(s, &end, 10) : 0;
  if (!end || end == s || *end != '\0') return gs_cfg_fail(n, err, "expected an integer");
  if (errno == ERANGE)
    return gs_cfg_fail(n, err, "expected an integer between %ld and %ld", LONG_MIN, LONG_MAX);
  *out = v;
  return GS_OK;
}

int gs_cfg_double_req(gs_cfg_node *map, const char *key, double *out, gs_error *err) {
  gs_cfg_node *v;
  int rc = gs_lookup(map, key, 1, &v, err);
  return rc ? rc : gs_cfg_node_double(v, out, err);
}

int gs_cfg_double_opt(gs_cfg_node *map, const char *key, double def, double *out, gs_error *err) {
  gs_cfg_node *v;
  int rc = gs_lookup(map, key, 0, &v, err);
  if (rc) return rc;
  if (!v) {
    *out = def;
    return GS_OK;
  }
  return gs_cfg_node_double(v, out, err);
}

/* "> 0", "between 0 and 1", "> 0 and <= 1"; "" when unbounded. */
static void gs_range_text(char *buf, size_t size, const char *lo, const char *lo_op,
                          const char *hi, const char *hi_op) {
  if (lo && hi && strcmp(lo_op, ">=") == 0 && strcmp(hi_op, "<=") == 0)
    snprintf(buf, size, " between %s and %s", lo, hi);
  else if (lo && hi)
    snprintf(buf, size, " %s %s and %s %s", lo_op, lo, hi_op, hi);
  else if (lo)
    snprintf(buf, size, " %s %s", lo_op, lo);
  else if (hi)
    snprintf(buf, size, " %s %s", hi_op, hi);
  else
    buf[0] = '\0';
}

int gs_cfg_double_range(gs_cfg_node *map, const char *key, int required, double def, double lo,
                        int lo_strict, double hi, int hi_strict, double *out, gs_error *err) {
  gs_cfg_node *n;
  int rc = gs_lookup(map, key, required, &n, err);
  if (rc) return rc;
  if (!n) {
    *out = def;
    return GS_OK;
  }
  double v = 0;
  rc = gs_cfg_node_double(n, &v, err);
  if (rc) return rc;
  int has_lo = lo > -HUGE_VAL, has_hi = hi < HUGE_VAL;
  int bad = (has_lo && (lo_strict ? !(v > lo) : !(v >= lo))) ||
            (has_hi && (hi_strict ? !(v < hi) : !(v <= hi)));
  if (bad) {
    char los[32], his[32], range[96];
    snprintf(los, sizeof los, "%g", lo);
    snprintf(his, sizeof his, "%g", hi);
    gs_range_text(range, sizeof range, has_lo ? los : NULL, lo_strict ? ">" : ">=",
                  has_hi ? his : NULL, hi_strict ? "<" : "<=");
    return gs_cfg_fail(n, err, "expected a number%s", range);
  }
  *out = v;
  return GS_OK;
}

int gs_cfg_long_range(gs_cfg_node *map, const char *key, int required, long def, long lo, long hi,
                      long *out, gs_error *err) {
  gs_cfg_node *n;
  int rc = gs_lookup(map, key, required, &n, err);
  if (rc) return rc;
  if (!n) {
    *out = def;
    return GS_OK;
  }
  long v = 0;
  rc = gs_node_long(n, &v, err);
  if (rc) return rc;
  if (v < lo || v > hi) {
    char los[32], his[32], range[96];
    snprintf(los, sizeof los, "%ld", lo);
    snprintf(his, sizeof his, "%ld", hi);
    gs_range_text(range, sizeof range, lo > LONG_MIN ? los : NULL, ">=",
                  hi < LONG_MAX ? his : NULL, "<=");
    return gs_cfg_fail(n, err, "expected an integer%s", range);
  }
  *out = v;
  return GS_OK;
}

int gs_cfg_bool_opt(gs_cfg_node *map, const char *key, int def, int *out, gs_error *err) {
  static const char *const yes[] = {"true", "yes", "on"};
  static const char *const no[] = {"false", "no", "off"};
  gs_cfg_node *n;
  int rc = gs_lookup(map, key, 0, &n, err);
  if (rc) return rc;
  if (!n) {
    *out = def;
    return GS_OK;
  }
  for (size_t i = 0; n->kind == GS_CFG_SCALAR && i < 3; i++) {
    if (strcasecmp(n->text, yes[i]) == 0 || strcasecmp(n->text, no[i]) == 0) {
      *out = strcasecmp(n->text, yes[i]) == 0;
      return GS_OK;
    }
  }
  return gs_cfg_fail(n, err, "expected true or false");
}

static int gs_string_get(gs_cfg_node *map, const char *key, int required, const char *def,
                         const char **out, gs_error *err) {
  gs_cfg_node *n;
  int rc = gs_lookup(map, key, required, &n, err);
  if (rc) return rc;
  if (!n) {
    *out = def;
    return GS_OK;
  }
  if (n->kind != GS_CFG_SCALAR) return gs_cfg_fail(n, err, "expected a string");
  *out = n->text;
  return GS_OK;
}

int gs_cfg_string_req(gs_cfg_node *map, const char *key, const char **out, gs_error *err) {
  return gs_string_get(map, key, 1, NULL, out, err);
}

int gs_cfg_string_opt(gs_cfg_node *map, const char *key, const char *def, const char **out,
                      gs_error *err) {
  return gs_string_get(map, key, 0, def, out, err);
}

/* "a, b, c" from a NULL-terminated list (or from a key list). */
static void gs_join(char *buf, size_t size, const char *const *words, size_t count) {
  size_t used = 0;
  buf[0] = '\0';
  for (size_t i = 0; i < count && words[i] && used < size; i++) {
    int w = snprintf(buf + used, size - used, "%s%s", i ? ", " : "", words[i]);
    if (w < 0) break;
    used += (size_t)w;
  }
}

int gs_cfg_enum_opt(gs_cfg_node *map, const char *key, const char *const *choices, int def,
                    int *out, gs_error *err) {
  gs_cfg_node *n;
  int rc = gs_lookup(map, key, 0, &n, err);
  if (rc) return rc;
  if (!n) {
    *out = def;
    return GS_OK;
  }
  for (int i = 0; n->kind == GS_CFG_SCALAR && choices[i]; i++) {
    if (strcmp(n->text, choices[i]) == 0) {
      *out = i;
      return GS_OK;
    }
  }
  char list[768];
  gs_join(list, sizeof list, choices, (size_t)-1);
  return gs_cfg_fail(n, err, "expected one of: %s", list);
}

/* Fill a fresh array from the scalars of seq. */
static int gs_seq_doubles(const gs_cfg_node *seq, double **out, size_t *count, gs_error *err) {
  if (seq->n == 0) return gs_cfg_fail(seq, err, "expected a non-empty list of numbers");
  double *v = gs_malloc(seq->n * sizeof *v, err);
  if (!v) return GS_ENOMEM;
  for (size_t i = 0; i < seq->n; i++) {
    int rc = gs_cfg_node_double(seq->items[i], &v[i], err);
    if (rc) {
      free(v);
      return rc;
    }
  }
  *out = v;
  *count = seq->n;
  return GS_OK;
}

int gs_cfg_doubles_req(gs_cfg_node *map, const char *key, int allow_scalar, double **out,
                       size_t *n, gs_error *err) {
  gs_cfg_node *v;
  int rc = gs_lookup(map, key, 1, &v, err);
  if (rc) return rc;
  if (v->kind == GS_CFG_SEQ) return gs_seq_doubles(v, out, n, err);
  if (v->kind != GS_CFG_SCALAR || !allow_scalar)
    return gs_cfg_fail(v, err, allow_scalar ? "expected a number or a list of numbers"
                                            : "expected a list of numbers");
  double x = 0;
  rc = gs_cfg_node_double(v, &x, err);
  if (rc) return rc;
  double *one = gs_malloc(sizeof *one, err);
  if (!one) return GS_ENOMEM;
  *one = x;
  *out = one;
  *n = 1;
  return GS_OK;
}

int gs_cfg_per_comp(gs_cfg_node *map, const char *key, int required, double def, double lo,
                    int lo_strict, size_t n, double *out, gs_error *err) {
  gs_cfg_node *node = gs_cfg_get(map, key);
  if (!node) {
    if (required) return gs_missing(map, key, err);
    for (size_t z = 0; z < n; z++) out[z] = def;
    return GS_OK;
  }
  double *v = NULL;
  size_t cnt = 0;
  int rc = gs_cfg_doubles_req(map, key, 1, &v, &cnt, err);
  if (!rc && cnt != 1 && cnt != n)
    rc = gs_cfg_fail(node, err, "expected one number or one per compartment (%zu), got %zu", n, cnt);
  for (size_t z = 0; !rc && z < n; z++) {
    out[z] = v[cnt == 1 ? 0 : z];
    if (lo_strict ? !(out[z] > lo) : !(out[z] >= lo))
      rc = gs_cfg_fail(node, err, "expected numbers %s %g (entry %zu is %g)", lo_strict ? ">" : ">=", lo, z, out[z]);
  }
  free(v);
  return rc;
}

int gs_cfg_check_unused(const gs_cfg_node *map, gs_error *err) {
  if (!map) return GS_OK; /* an absent optional section has no unknown keys */
  int rc = gs_cfg_require_kind(map, GS_CFG_MAP, err);
  if (rc) return rc;
  for (size_t i = 0; i < map->n; i++) {
    const gs_cfg_entry *e = &map->entries[i];
    if (e->used) continue;
    if (map->nasked == 0)
      return gs_error_set(err, GS_EINPUT, "%s:%d: unknown key '%s' in %s; this section takes no keys",
                          map->file, e->line, e->key, gs_path_shown(map));
    char list[1024], hint[128] = "";
    gs_join(list, sizeof list, (const char *const *)map->asked, map->nasked);
    const char *near = gs_nearest_word(e->key, (const char *const *)map->asked, map->nasked);
    if (near) snprintf(hint, sizeof hint, "did you mean '%s'? ", near);
    return gs_error_set(err, GS_EINPUT, "%s:%d: unknown key '%s' in %s; %sexpected one of: %s",
                        map->file, e->line, e->key, gs_path_shown(map), hint, list);
  }
  return GS_OK;
}
