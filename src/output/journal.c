/* The commit journal (see journal.h). */
#include "output/journal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/uio.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#define MAGIC "GSJRNL01"
#define TAG_ROW 0x574f52u    /* "ROW" */
#define TAG_COMMIT 0x544d43u /* "CMT" */
#define IOV_MAX_PIECES 8

struct gs_journal {
  int fd;
  char *path;
  size_t row_values;
  uint64_t appended, committed; /* rows */
  off_t *offsets;               /* after a reopen: where each committed row starts */
};

typedef struct {
  uint32_t tag, crc;
  uint64_t n; /* a row's index, a commit's count */
} record_head;

static int io_error(gs_error *err, const char *what, const char *path) {
  return gs_error_set(err, GS_EIO, "cannot %s %s: %s", what, path, strerror(errno));
}

/* write(2) until all is written (a signal may cut a write short). */
static int write_all(int fd, struct iovec *iov, int n) {
  while (n > 0) {
    ssize_t w = writev(fd, iov, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return -1;
    }
    while (n > 0 && (size_t)w >= iov->iov_len) {
      w -= (ssize_t)iov->iov_len;
      iov++;
      n--;
    }
    if (n > 0) {
      iov->iov_base = (char *)iov->iov_base + w;
      iov->iov_len -= (size_t)w;
    }
  }
  return 0;
}

static int read_at(int fd, void *buf, size_t len, off_t at) {
  while (len > 0) {
    ssize_t r = pread(fd, buf, len, at);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return -1;
    buf = (char *)buf + r;
    len -= (size_t)r;
    at += r;
  }
  return 0;
}

static void journal_free(gs_journal *j) {
  if (!j) return;
  if (j->fd >= 0) close(j->fd);
  free(j->path);
  free(j->offsets);
  free(j);
}

static gs_journal *journal_alloc(const char *path, gs_error *err) {
  gs_journal *j = gs_calloc(1, sizeof *j, err);
  if (!j) return NULL;
  j->fd = -1;
  j->path = gs_malloc(strlen(path) + 1, err);
  if (!j->path) {
    journal_free(j);
    return NULL;
  }
  strcpy(j->path, path);
  return j;
}

gs_journal *gs_journal_create(const char *path_new, const char *path, const void *head,
                              size_t nhead, size_t row_values, gs_error *err) {
  gs_journal *j = journal_alloc(path, err);
  if (!j) return NULL;
  j->row_values = row_values;
  j->fd = open(path_new, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (j->fd < 0) {
    io_error(err, "create", path_new);
    journal_free(j);
    return NULL;
  }
  uint64_t sizes[2] = {row_values, nhead};
  uint32_t crc = (uint32_t)crc32_z(0, (const Bytef *)MAGIC, 8);
  crc = (uint32_t)crc32_z(crc, (const Bytef *)sizes, sizeof sizes);
  crc = (uint32_t)crc32_z(crc, head, nhead);
  struct iovec iov[4] = {{MAGIC, 8}, {sizes, sizeof sizes}, {(void *)head, nhead}, {&crc, sizeof crc}};
  if (write_all(j->fd, iov, 4)) {
    io_error(err, "write", path_new);
    journal_free(j);
    unlink(path_new);
    return NULL;
  }
  if (rename(path_new, path)) {
    gs_error_set(err, GS_EIO, "cannot rename %s to %s: %s", path_new, path, strerror(errno));
    journal_free(j);
    unlink(path_new);
    return NULL;
  }
  return j;
}

int gs_journal_append(gs_journal *j, const double *const *pieces, const size_t *lens, int npieces,
                      gs_error *err) {
  struct iovec iov[IOV_MAX_PIECES + 1];
  record_head h = {TAG_ROW, 0, j->appended};
  uint32_t crc = (uint32_t)crc32_z(0, (const Bytef *)&h.n, sizeof h.n);
  size_t total = 0;
  if (npieces > IOV_MAX_PIECES)
    return gs_error_set(err, GS_EINPUT, "journal %s: %d pieces in a row (at most %d)", j->path,
                        npieces, IOV_MAX_PIECES);
  for (int p = 0; p < npieces; p++) {
    iov[p + 1] = (struct iovec){(void *)pieces[p], lens[p] * sizeof(double)};
    crc = (uint32_t)crc32_z(crc, (const Bytef *)pieces[p], lens[p] * sizeof(double));
    total += lens[p];
  }
  if (total != j->row_values)
    return gs_error_set(err, GS_EINPUT, "journal %s: a row of %zu values where %zu are due",
                        j->path, total, j->row_values);
  h.crc = crc;
  iov[0] = (struct iovec){&h, sizeof h};
  if (write_all(j->fd, iov, npieces + 1)) return io_error(err, "write", j->path);
  j->appended++;
  return GS_OK;
}

int gs_journal_commit(gs_journal *j, gs_error *err) {
  if (j->committed == j->appended) return GS_OK;
  record_head h = {TAG_COMMIT, 0, j->appended};
  h.crc = (uint32_t)crc32_z(0, (const Bytef *)&h.n, sizeof h.n);
  struct iovec iov = {&h, sizeof h};
  if (write_all(j->fd, &iov, 1)) return io_error(err, "write", j->path);
  j->committed = j->appended;
  return GS_OK;
}

uint64_t gs_journal_committed(const gs_journal *j) { return j->committed; }

/* The header: returns its end, or -1 (err set) when it is not intact. */
static off_t read_header(gs_journal *j, void **head, size_t *nhead, gs_error *err) {
  char magic[8];
  uint64_t sizes[2];
  uint32_t crc_file;
  struct stat st;
  /* sizes a damaged file cannot hold are refused before anything is
   * allocated for them (fuzz_journal: a length of 2 GB in a file of 1 KB) */
  if (fstat(j->fd, &st) || read_at(j->fd, magic, 8, 0) || memcmp(magic, MAGIC, 8) ||
      read_at(j->fd, sizes, sizeof sizes, 8) || sizes[1] > (uint64_t)st.st_size || sizes[0] == 0 ||
      sizes[0] > ((uint64_t)1 << 40)) {
    gs_error_set(err, GS_EIO, "cannot resume from %s: not a gransim journal, or its header is damaged", j->path);
    return -1;
  }
  void *h = gs_malloc(sizes[1] ? sizes[1] : 1, err);
  if (!h) return -1;
  off_t at = 8 + (off_t)sizeof sizes;
  uint32_t crc = (uint32_t)crc32_z(0, (const Bytef *)MAGIC, 8);
  crc = (uint32_t)crc32_z(crc, (const Bytef *)sizes, sizeof sizes);
  if (read_at(j->fd, h, sizes[1], at) || read_at(j->fd, &crc_file, sizeof crc_file, at + (off_t)sizes[1]) ||
      (uint32_t)crc32_z(crc, h, sizes[1]) != crc_file) {
    free(h);
    gs_error_set(err, GS_EIO, "cannot resume from %s: its header is damaged", j->path);
    return -1;
  }
  *head = h;
  *nhead = sizes[1];
  j->row_values = sizes[0];
  return at + (off_t)sizes[1] + (off_t)sizeof crc_file;
}

/* Walks the records from `at`: the rows up to the last intact commit
 * record go to j->offsets; returns where that commit record ends. */
static off_t scan_records(gs_journal *j, off_t at, gs_error *err) {
  const size_t row_bytes = j->row_values * sizeof(double);
  struct stat st;
  if (fstat(j->fd, &st)) return io_error(err, "read", j->path), -1;
  /* no row fits in what the file holds: nothing to read, nothing to allocate */
  if ((uint64_t)row_bytes > (uint64_t)st.st_size) {
    j->appended = j->committed = 0;
    return at;
  }
  double *buf = gs_malloc(row_bytes, err);
  size_t cap = 0;
  uint64_t rows = 0;
  off_t end = at;
  record_head h;
  while (buf && !read_at(j->fd, &h, sizeof h, at)) {
    if (h.tag == TAG_ROW) {
      if (h.n != rows || read_at(j->fd, buf, row_bytes, at + (off_t)sizeof h)) break;
      uint32_t crc = (uint32_t)crc32_z(0, (const Bytef *)&h.n, sizeof h.n);
      if ((uint32_t)crc32_z(crc, (const Bytef *)buf, row_bytes) != h.crc) break;
      if (rows == cap) {
        cap = cap ? 2 * cap : 64;
        off_t *o2 = realloc(j->offsets, cap * sizeof *o2);
        if (!o2) {
          free(buf);
          gs_error_set(err, GS_ENOMEM, "out of memory reading %s", j->path);
          return -1;
        }
        j->offsets = o2;
      }
      j->offsets[rows++] = at + (off_t)sizeof h;
      at += (off_t)(sizeof h + row_bytes);
    } else if (h.tag == TAG_COMMIT) {
      if (h.n != rows || (uint32_t)crc32_z(0, (const Bytef *)&h.n, sizeof h.n) != h.crc) break;
      j->committed = rows;
      at += (off_t)sizeof h;
      end = at;
    } else {
      break;
    }
  }
  if (!buf) return -1;
  free(buf);
  j->appended = j->committed;
  return end;
}

gs_journal *gs_journal_reopen(const char *path, void **head, size_t *nhead, size_t *row_values,
                              gs_error *err) {
  *head = NULL;
  gs_journal *j = journal_alloc(path, err);
  if (!j) return NULL;
  j->fd = open(path, O_RDWR | O_CLOEXEC);
  off_t at = j->fd < 0 ? (io_error(err, "open", path), -1) : read_header(j, head, nhead, err);
  if (at >= 0) at = scan_records(j, at, err);
  /* the torn or uncommitted tail goes: the appends continue after the
   * last commit */
  if (at >= 0 && (ftruncate(j->fd, at) || lseek(j->fd, at, SEEK_SET) != at)) {
    io_error(err, "truncate", path);
    at = -1;
  }
  if (at < 0) {
    free(*head);
    *head = NULL;
    journal_free(j);
    return NULL;
  }
  *row_values = j->row_values;
  return j;
}

int gs_journal_read(gs_journal *j, uint64_t index, double *row, gs_error *err) {
  if (index >= j->committed || !j->offsets)
    return gs_error_set(err, GS_EINPUT, "journal %s: row %llu is not committed", j->path,
                        (unsigned long long)index);
  if (read_at(j->fd, row, j->row_values * sizeof(double), j->offsets[index]))
    return io_error(err, "read", j->path);
  return GS_OK;
}

int gs_journal_close(gs_journal *j, gs_error *err) {
  if (!j) return GS_OK;
  int rc = GS_OK;
  if (j->fd >= 0 && close(j->fd)) rc = io_error(err, "close", j->path);
  j->fd = -1;
  journal_free(j);
  return rc;
}
