/* JSON sidecars of the DEM tables (csv_meta.h). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "demdata/csv_meta.h"

/* A JSON string: quotes, backslashes and control characters escaped (RFC 8259). */
static void json_string(FILE *fp, const char *s) {
  fputc('"', fp);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(fp, "\\%c", *p);
    else if (*p == '\n') fputs("\\n", fp);
    else if (*p < 0x20) fprintf(fp, "\\u%04x", *p);
    else fputc(*p, fp);
  }
  fputc('"', fp);
}

int gs_csv_meta_write(const char *csv_path, const char *written_by, const char *description,
                      const char *const *units, gs_error *err) {
  size_t n = strlen(csv_path);
  if (n < 4 || strcmp(csv_path + n - 4, ".csv"))
    return gs_error_set(err, GS_EINPUT, "%s: a table's name must end in .csv", csv_path);
  char *path = malloc(n + sizeof ".json.partial"), *partial = malloc(n + sizeof ".json.partial");
  if (!path || !partial) {
    free(path), free(partial);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  snprintf(path, n + sizeof ".json.partial", "%.*s.json", (int)(n - 4), csv_path);
  snprintf(partial, n + sizeof ".json.partial", "%s.partial", path);
  int rc = GS_OK;
  FILE *fp = fopen(partial, "w");
  if (!fp) {
    rc = gs_error_set(err, GS_EIO, "%s: cannot write: %s", partial, strerror(errno));
  } else {
    const char *base = strrchr(csv_path, '/');
    fputs("{\n  \"file\": ", fp);
    json_string(fp, base ? base + 1 : csv_path);
    fputs(",\n  \"written_by\": ", fp);
    json_string(fp, written_by);
    fputs(",\n  \"description\": ", fp);
    json_string(fp, description);
    fputs(",\n  \"units\": {", fp);
    for (size_t i = 0; units && units[i] && units[i + 1]; i += 2) {
      fputs(i ? ",\n    " : "\n    ", fp);
      json_string(fp, units[i]);
      fputs(": ", fp);
      json_string(fp, units[i + 1]);
    }
    fputs(units && units[0] ? "\n  }\n}\n" : "}\n}\n", fp);
    int bad = ferror(fp);
    if (fclose(fp) || bad || rename(partial, path))
      rc = gs_error_set(err, GS_EIO, "%s: write failed: %s", path, strerror(errno));
  }
  free(path), free(partial);
  return rc;
}

FILE *gs_csv_open(gs_csv_out *t, const char *path, gs_error *err) {
  t->buf = NULL;
  t->len = 0;
  if ((size_t)snprintf(t->path, sizeof t->path, "%s", path) >= sizeof t->path) {
    gs_error_set(err, GS_EIO, "%s: path too long", path);
    return t->fp = NULL;
  }
  t->fp = open_memstream(&t->buf, &t->len);
  if (!t->fp) gs_error_set(err, GS_ENOMEM, "out of memory");
  return t->fp;
}

FILE *gs_csv_open_in(gs_csv_out *t, const char *dir, const char *name, gs_error *err) {
  char path[sizeof t->path];
  if ((size_t)snprintf(path, sizeof path, "%s/%s", dir, name) >= sizeof path) {
    gs_error_set(err, GS_EIO, "%s/%s: path too long", dir, name);
    return t->fp = NULL;
  }
  return gs_csv_open(t, path, err);
}

int gs_csv_close(gs_csv_out *t, const char *written_by, const char *const *units, gs_error *err) {
  int rc = GS_OK;
  if (fclose(t->fp) || !t->buf) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  /* "# text" lines, wherever they are, make the description, one line each;
   * the others, in order, the table */
  char *desc = rc ? NULL : malloc(t->len + 1), *body = rc ? NULL : malloc(t->len + 1);
  size_t nd = 0, nb = 0;
  if (!rc && (!desc || !body)) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (char *p = t->buf; !rc && *p;) {
    char *nl = strchr(p, '\n');
    size_t n = nl ? (size_t)(nl - p) : strlen(p);
    if (*p == '#') {
      size_t skip = n > 1 && p[1] == ' ' ? 2 : 1;
      if (nd) desc[nd++] = '\n';
      memcpy(desc + nd, p + skip, n - skip);
      nd += n - skip;
    } else {
      memcpy(body + nb, p, n + (nl != NULL));
      nb += n + (nl != NULL);
    }
    p += n + (nl != NULL);
  }
  if (desc) desc[nd] = '\0';
  char partial[sizeof t->path + 16];
  snprintf(partial, sizeof partial, "%s.partial", t->path);
  FILE *fp = rc ? NULL : fopen(partial, "w");
  if (!rc && !fp) rc = gs_error_set(err, GS_EIO, "%s: cannot write: %s", partial, strerror(errno));
  if (fp) {
    fwrite(body, 1, nb, fp);
    int bad = ferror(fp);
    if (fclose(fp) || bad || rename(partial, t->path))
      rc = gs_error_set(err, GS_EIO, "%s: write failed: %s", t->path, strerror(errno));
  }
  if (!rc) rc = gs_csv_meta_write(t->path, written_by, desc, units, err);
  free(desc);
  free(body);
  free(t->buf);
  t->buf = NULL;
  t->fp = NULL;
  return rc;
}
