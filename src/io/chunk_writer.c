/* See chunk_writer.h. */
#include "io/chunk_writer.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

struct gs_chunk_writer {
  z_stream z;
  int level; /* of the open stream; -2: none open */
  unsigned char *buf;
  size_t cap;
};

gs_chunk_writer *gs_chunk_writer_new(void) {
  gs_chunk_writer *w = calloc(1, sizeof *w);
  if (w) w->level = -2;
  return w;
}

void gs_chunk_writer_free(gs_chunk_writer *w) {
  if (!w) return;
  if (w->level != -2) deflateEnd(&w->z);
  free(w->buf);
  free(w);
}

int gs_chunk_direct_ok(void) {
  return H5Tequal(H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE) > 0;
}

/* Deflates n bytes into w->buf; returns the compressed size, or 0 when zlib
 * fails or the result would not be smaller (the chunk is then stored raw). */
static size_t squeeze(gs_chunk_writer *w, const void *src, size_t n, int level) {
  if (w->level != level) {
    if (w->level != -2) deflateEnd(&w->z);
    memset(&w->z, 0, sizeof w->z);
    w->level = deflateInit(&w->z, level) == Z_OK ? level : -2;
    if (w->level == -2) return 0;
  } else if (deflateReset(&w->z) != Z_OK) {
    return 0;
  }
  size_t bound = deflateBound(&w->z, (uLong)n);
  if (bound > w->cap) {
    unsigned char *b = realloc(w->buf, bound);
    if (!b) return 0;
    w->buf = b;
    w->cap = bound;
  }
  w->z.next_in = (Bytef *)(uintptr_t)src; /* zlib's API is not const */
  w->z.avail_in = (uInt)n;
  w->z.next_out = w->buf;
  w->z.avail_out = (uInt)w->cap;
  if (deflate(&w->z, Z_FINISH) != Z_STREAM_END) return 0;
  return w->z.total_out < n ? (size_t)w->z.total_out : 0;
}

herr_t gs_chunk_write_rows(gs_chunk_writer *w, hid_t ds, hsize_t start, hsize_t count,
                           size_t values, const double *rows, int deflate, int level) {
  hsize_t offset[H5S_MAX_RANK] = {0}; /* a chunk spans every dimension after time */
  const size_t bytes = values * sizeof(double);
  for (hsize_t r = 0; r < count; r++) {
    const double *row = rows + r * values;
    offset[0] = start + r;
    size_t packed = deflate ? squeeze(w, row, bytes, level) : 0;
    /* filter mask bit 0 set: the (only, optional) deflate filter was skipped */
    herr_t st = packed ? H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset, packed, w->buf)
                       : H5Dwrite_chunk(ds, H5P_DEFAULT, deflate ? 1u : 0u, offset, bytes, row);
    if (st < 0) return st;
  }
  return 0;
}
