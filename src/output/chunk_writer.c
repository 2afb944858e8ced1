/* See chunk_writer.h. */
#include "output/chunk_writer.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

struct gs_chunk_writer {
  z_stream z;
  int level; /* of the open stream; -2: none open */
  unsigned char *buf;
  size_t cap;
  int failed; /* the row in progress cannot be deflated: it goes raw */
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

void gs_chunk_row_begin(gs_chunk_writer *w, size_t bytes, int level) {
  w->failed = 1;
  if (w->level != level) {
    if (w->level != -2) deflateEnd(&w->z);
    memset(&w->z, 0, sizeof w->z);
    w->level = deflateInit(&w->z, level) == Z_OK ? level : -2;
    if (w->level == -2) return;
  } else if (deflateReset(&w->z) != Z_OK) {
    return;
  }
  size_t bound = deflateBound(&w->z, (uLong)bytes);
  if (bound > w->cap) {
    unsigned char *b = realloc(w->buf, bound);
    if (!b) return;
    w->buf = b;
    w->cap = bound;
  }
  w->z.next_out = w->buf;
  w->z.avail_out = (uInt)w->cap;
  w->failed = 0;
}

void gs_chunk_row_feed(gs_chunk_writer *w, const void *span, size_t n, int last) {
  if (w->failed) return;
  w->z.next_in = (Bytef *)(uintptr_t)span; /* zlib's API is not const */
  w->z.avail_in = (uInt)n;
  /* the output buffer holds deflateBound of the whole row: every piece fits */
  int st = deflate(&w->z, last ? Z_FINISH : Z_NO_FLUSH);
  if (last ? st != Z_STREAM_END : (st != Z_OK || w->z.avail_in)) w->failed = 1;
}

herr_t gs_chunk_row_write(gs_chunk_writer *w, hid_t ds, hsize_t index, size_t values,
                          const double *row) {
  hsize_t offset[H5S_MAX_RANK] = {0}; /* a chunk spans every dimension after time */
  const size_t bytes = values * sizeof(double);
  offset[0] = index;
  /* stored raw when zlib failed or the result would not be smaller, with
   * filter mask bit 0 set: the (only, optional) deflate filter was skipped */
  if (!w->failed && w->z.total_out < bytes)
    return H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset, (size_t)w->z.total_out, w->buf);
  return H5Dwrite_chunk(ds, H5P_DEFAULT, 1u, offset, bytes, row);
}

herr_t gs_chunk_write_rows(gs_chunk_writer *w, hid_t ds, hsize_t start, hsize_t count,
                           size_t values, const double *rows, int deflate, int level) {
  hsize_t offset[H5S_MAX_RANK] = {0};
  const size_t bytes = values * sizeof(double);
  for (hsize_t r = 0; r < count; r++) {
    const double *row = rows + r * values;
    herr_t st;
    if (deflate) {
      gs_chunk_row_begin(w, bytes, level);
      gs_chunk_row_feed(w, row, bytes, 1);
      st = gs_chunk_row_write(w, ds, start + r, values, row);
    } else {
      offset[0] = start + r;
      st = H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset, bytes, row);
    }
    if (st < 0) return st;
  }
  return 0;
}

herr_t gs_chunk_write_blocks(gs_chunk_writer *w, hid_t ds, hsize_t start, hsize_t count,
                             size_t chunk_rows, size_t values, const double *rows) {
  hsize_t offset[H5S_MAX_RANK] = {0};
  const size_t chunk_bytes = chunk_rows * values * sizeof(double);
  for (hsize_t done = 0; done < count; done += chunk_rows) {
    const double *block = rows + done * values;
    offset[0] = start + done;
    if (count - done < chunk_rows) { /* the last, partly filled: padded in the buffer */
      if (chunk_bytes > w->cap) {
        unsigned char *b = realloc(w->buf, chunk_bytes);
        if (!b) return -1;
        w->buf = b;
        w->cap = chunk_bytes;
      }
      const size_t have = (size_t)(count - done) * values * sizeof(double);
      memcpy(w->buf, block, have);
      memset(w->buf + have, 0, chunk_bytes - have);
      block = (const double *)(const void *)w->buf;
    }
    if (H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset, chunk_bytes, block) < 0) return -1;
  }
  return 0;
}
