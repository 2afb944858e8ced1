/* Equal blocks from huge-page chunks: see block_pool.h. */
#include "core/block_pool.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

#define CHUNK_ALIGN ((size_t)2 << 20) /* a huge page on x86-64 and arm64 */

struct gs_block_pool {
  size_t block;       /* bytes per block */
  size_t chunk;       /* bytes per chunk: a multiple of CHUNK_ALIGN */
  atomic_flag busy;   /* the lock: gets and puts are a few instructions */
  void *free_list;    /* blocks given back, each holding the next one's address */
  char *carve, *end;  /* the newest chunk's blocks never handed out yet */
  void **chunks;      /* for gs_block_pool_free */
  size_t nchunks, cap;
};

static void lock(gs_block_pool *p) {
  while (atomic_flag_test_and_set_explicit(&p->busy, memory_order_acquire)) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
}

static void unlock(gs_block_pool *p) { atomic_flag_clear_explicit(&p->busy, memory_order_release); }

gs_block_pool *gs_block_pool_create(size_t block_bytes, gs_error *err) {
  /* its lock and free list on a page of their own: every thread writes them */
  gs_block_pool *p = gs_calloc_apart(sizeof *p, err);
  if (!p) return NULL;
  /* whole pages (GS_APART): different threads write neighbouring blocks */
  p->block = (block_bytes ? block_bytes + GS_APART - 1 : GS_APART) / GS_APART * GS_APART;
  p->chunk = (p->block + CHUNK_ALIGN - 1) / CHUNK_ALIGN * CHUNK_ALIGN;
  atomic_flag_clear(&p->busy);
  return p;
}

/* A chunk of p->chunk bytes on a CHUNK_ALIGN boundary (a huge page can only
 * back an aligned 2 MiB range), or NULL. */
static void *new_chunk(const gs_block_pool *p) {
  const size_t len = p->chunk + CHUNK_ALIGN;
  char *raw = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) return NULL;
  char *at = (char *)(((uintptr_t)raw + CHUNK_ALIGN - 1) & ~(uintptr_t)(CHUNK_ALIGN - 1));
  if (at > raw) munmap(raw, (size_t)(at - raw));
  const size_t tail = (size_t)(raw + len - (at + p->chunk));
  if (tail) munmap(at + p->chunk, tail);
#ifdef MADV_HUGEPAGE
  madvise(at, p->chunk, MADV_HUGEPAGE); /* a hint: without huge pages, plain pages */
#endif
  return at;
}

void *gs_block_pool_get(gs_block_pool *p) {
  lock(p);
  void *b = p->free_list;
  if (b) {
    p->free_list = *(void **)b;
  } else {
    if (!p->carve || (size_t)(p->end - p->carve) < p->block) {
      if (p->nchunks == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 8;
        void **grown = realloc(p->chunks, cap * sizeof *grown);
        if (!grown) {
          unlock(p);
          return NULL;
        }
        p->chunks = grown;
        p->cap = cap;
      }
      char *c = new_chunk(p);
      if (!c) {
        unlock(p);
        return NULL;
      }
      p->chunks[p->nchunks++] = c;
      p->carve = c;
      p->end = c + p->chunk;
    }
    b = p->carve;
    p->carve += p->block;
  }
  unlock(p);
  return b;
}

void gs_block_pool_put(gs_block_pool *p, void *block) {
  if (!block) return;
  lock(p);
  *(void **)block = p->free_list;
  p->free_list = block;
  unlock(p);
}

int gs_block_pool_reserve(gs_block_pool *p, size_t n, gs_error *err) {
  void **taken = n ? malloc(n * sizeof *taken) : NULL;
  if (n && !taken) return gs_error_set(err, GS_ENOMEM, "out of memory reserving %zu blocks", n);
  size_t got = 0;
  for (; got < n; got++) {
    char *b = taken[got] = gs_block_pool_get(p);
    if (!b) break;
    for (size_t at = 0; at < p->block; at += GS_APART) b[at] = 0;
  }
  /* back in reverse, so that they come out again in the order taken */
  for (size_t i = got; i-- > 0;) gs_block_pool_put(p, taken[i]);
  free(taken);
  return got == n ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory reserving %zu blocks", n);
}

size_t gs_block_pool_bytes(const gs_block_pool *p) { return p->nchunks * p->chunk; }

void gs_block_pool_free(gs_block_pool *p) {
  if (!p) return;
  for (size_t i = 0; i < p->nchunks; i++) munmap(p->chunks[i], p->chunk);
  free(p->chunks);
  free(p);
}
