/* Direct chunk writes (src/output/chunk_writer.c): what HDF5's own reader gets
 * back through its filter pipeline is exactly what was written, for a
 * deflated dataset (compressible rows deflated, incompressible ones stored
 * raw with the filter marked skipped) and for a plain one; the deflated
 * chunks are really smaller; a row deflated in pieces (gs_chunk_row_*) is
 * stored byte for byte as the row deflated at once. */
#include <hdf5.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "output/chunk_writer.h"

enum { NROWS = 4, NA = 3, NB = 1000, ROW = NA * NB };

/* Row 0 zeros, row 1 a smooth ramp (both compress), rows 2-3 random bits
 * (do not: every bit random), all finite. */
static void make_rows(double *rows) {
  uint64_t s = 0x9e3779b97f4a7c15ull;
  for (size_t i = 0; i < ROW; i++) {
    rows[i] = 0.0;
    rows[ROW + i] = 1e-3 * (double)i;
  }
  for (size_t i = 2 * ROW; i < NROWS * (size_t)ROW; i++) {
    s ^= s << 13, s ^= s >> 7, s ^= s << 17; /* xorshift64 */
    uint64_t bits = s;
    if ((bits & 0x7ff0000000000000ull) == 0x7ff0000000000000ull) bits ^= 0x0010000000000000ull; /* no NaN */
    memcpy(&rows[i], &bits, sizeof bits);
  }
}

static hid_t make_dataset(hid_t f, const char *name, int deflate) {
  hsize_t dims[3] = {0, NA, NB}, maxdims[3] = {H5S_UNLIMITED, NA, NB}, chunk[3] = {1, NA, NB};
  hid_t space = H5Screate_simple(3, dims, maxdims), dcpl = H5Pcreate(H5P_DATASET_CREATE);
  CHECK(H5Pset_chunk(dcpl, 3, chunk) >= 0);
  if (deflate) CHECK(H5Pset_deflate(dcpl, 1) >= 0);
  hid_t d = H5Dcreate2(f, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  CHECK(d >= 0);
  H5Pclose(dcpl);
  H5Sclose(space);
  hsize_t ext[3] = {NROWS, NA, NB};
  CHECK(H5Dset_extent(d, ext) >= 0);
  return d;
}

/* Stored size and filter mask of row r's chunk. */
static void chunk_info(hid_t d, hsize_t r, hsize_t *size, unsigned *mask) {
  hsize_t off[3] = {r, 0, 0};
  haddr_t addr;
  CHECK(H5Dget_chunk_info_by_coord(d, off, mask, &addr, size) >= 0);
}

/* Row r of dataset a and of b are stored alike: same mask, same bytes. */
static void check_same_chunk(hid_t a, hid_t b, hsize_t r) {
  hsize_t sa, sb;
  unsigned ma, mb;
  chunk_info(a, r, &sa, &ma);
  chunk_info(b, r, &sb, &mb);
  CHECK(sa == sb && ma == mb);
  if (sa != sb) return;
  unsigned char *ba = malloc(sa), *bb = malloc(sb);
  hsize_t off[3] = {r, 0, 0};
  uint32_t fa, fb;
  CHECK(H5Dread_chunk(a, H5P_DEFAULT, off, &fa, ba) >= 0);
  CHECK(H5Dread_chunk(b, H5P_DEFAULT, off, &fb, bb) >= 0);
  CHECK(memcmp(ba, bb, sa) == 0);
  free(ba);
  free(bb);
}

static void check_read_back(hid_t d, const double *want) {
  double *got = malloc(NROWS * (size_t)ROW * sizeof *got);
  CHECK(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, got) >= 0);
  CHECK(memcmp(got, want, NROWS * (size_t)ROW * sizeof *got) == 0);
  free(got);
}

int main(void) {
  CHECK(gs_chunk_direct_ok()); /* every platform gransim is built on is little-endian */
  char path[] = "/tmp/gs_test_chunks.XXXXXX";
  int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  double *rows = malloc(NROWS * (size_t)ROW * sizeof *rows);
  make_rows(rows);
  gs_chunk_writer *w = gs_chunk_writer_new();
  CHECK(w != NULL);

  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  hid_t zipped = make_dataset(f, "zipped", 1), plain = make_dataset(f, "plain", 0);
  /* two calls, so the stream is reused across calls as well as rows */
  CHECK(gs_chunk_write_rows(w, zipped, 0, 2, ROW, rows, 1, 1) >= 0);
  CHECK(gs_chunk_write_rows(w, zipped, 2, 2, ROW, rows + 2 * ROW, 1, 1) >= 0);
  CHECK(gs_chunk_write_rows(w, plain, 0, NROWS, ROW, rows, 0, 1) >= 0);
  /* rows deflated in uneven pieces, the last one short */
  hid_t pieces = make_dataset(f, "pieces", 1);
  const size_t bytes = ROW * sizeof(double), piece = 7000;
  for (hsize_t r = 0; r < NROWS; r++) {
    const double *row = rows + r * ROW;
    gs_chunk_row_begin(w, bytes, 1);
    for (size_t from = 0; from < bytes; from += piece)
      gs_chunk_row_feed(w, (const char *)row + from, from + piece < bytes ? piece : bytes - from,
                        from + piece >= bytes);
    CHECK(gs_chunk_row_write(w, pieces, r, ROW, row) >= 0);
  }
  /* a different level restarts the stream; the data still read back */
  CHECK(gs_chunk_write_rows(w, zipped, 1, 1, ROW, rows + ROW, 1, 6) >= 0);
  H5Dclose(zipped);
  H5Dclose(plain);
  H5Dclose(pieces);
  CHECK(H5Fclose(f) >= 0);

  f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  zipped = H5Dopen2(f, "zipped", H5P_DEFAULT);
  plain = H5Dopen2(f, "plain", H5P_DEFAULT);
  pieces = H5Dopen2(f, "pieces", H5P_DEFAULT);
  check_read_back(zipped, rows);
  check_read_back(plain, rows);
  check_read_back(pieces, rows);
  for (hsize_t r = 0; r < NROWS; r++)
    if (r != 1) check_same_chunk(pieces, zipped, r); /* row 1 of zipped went at level 6 last */
  const hsize_t raw = ROW * sizeof(double);
  hsize_t size;
  unsigned mask;
  for (hsize_t r = 0; r < 2; r++) { /* compressible rows: deflated */
    chunk_info(zipped, r, &size, &mask);
    CHECK(mask == 0 && size < raw / 2);
  }
  for (hsize_t r = 2; r < NROWS; r++) { /* random rows: raw, filter skipped */
    chunk_info(zipped, r, &size, &mask);
    CHECK(mask == 1 && size == raw);
  }
  for (hsize_t r = 0; r < NROWS; r++) {
    chunk_info(plain, r, &size, &mask);
    CHECK(mask == 0 && size == raw);
  }
  H5Dclose(zipped);
  H5Dclose(plain);
  H5Dclose(pieces);
  H5Fclose(f);
  unlink(path);
  gs_chunk_writer_free(w);
  free(rows);
  TEST_EXIT();
}
