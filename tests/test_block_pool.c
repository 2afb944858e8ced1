/* The block pool (core/block_pool.h): blocks are whole pages, never
 * overlap, keep what is written into them, come back last in first out,
 * can be reserved ahead, and stay whole when several threads get and put
 * at once; and the helpers that keep threads' data pages apart. */
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "core/block_pool.h"

#define BLOCK 55320 /* a record block of the CoriMix example: 3 nodes of 2305 doubles */

static int cmp_ptr(const void *a, const void *b) {
  const uintptr_t x = (uintptr_t) * (void *const *)a, y = (uintptr_t) * (void *const *)b;
  return x < y ? -1 : x > y;
}

/* n blocks: aligned, apart by at least a block, each holding its own
 * pattern after all were written; the pool's memory is whole 2 MiB chunks,
 * no more of them than the blocks need. */
static void distinct_blocks(size_t n) {
  gs_error err;
  gs_block_pool *p = gs_block_pool_create(BLOCK, &err);
  CHECK(p != NULL);
  if (!p) return;
  void **b = calloc(n, sizeof *b);
  for (size_t i = 0; i < n; i++) {
    b[i] = gs_block_pool_get(p);
    CHECK(b[i] != NULL);
    CHECK((uintptr_t)b[i] % GS_APART == 0);
    memset(b[i], (int)(i % 251), BLOCK);
  }
  int intact = 1;
  for (size_t i = 0; i < n; i++)
    for (size_t j = 0; j < BLOCK; j += 997)
      if (((unsigned char *)b[i])[j] != (unsigned char)(i % 251)) intact = 0;
  CHECK(intact);
  qsort(b, n, sizeof *b, cmp_ptr);
  for (size_t i = 1; i < n; i++) CHECK((uintptr_t)b[i] - (uintptr_t)b[i - 1] >= BLOCK);
  const size_t chunk = (size_t)2 << 20, block = (BLOCK + GS_APART - 1) / GS_APART * GS_APART;
  const size_t per_chunk = chunk / block, chunks = (n + per_chunk - 1) / per_chunk;
  CHECK(gs_block_pool_bytes(p) == chunks * chunk);
  free(b);
  gs_block_pool_free(p);
}

/* Blocks given back come out again, the last first, and take no new
 * memory. */
static void reuse(void) {
  gs_error err;
  gs_block_pool *p = gs_block_pool_create(100, &err); /* rounded up to a page */
  void *a = gs_block_pool_get(p), *b = gs_block_pool_get(p), *c = gs_block_pool_get(p);
  CHECK((uintptr_t)b - (uintptr_t)a == GS_APART && (uintptr_t)c - (uintptr_t)b == GS_APART);
  const size_t bytes = gs_block_pool_bytes(p);
  gs_block_pool_put(p, a);
  gs_block_pool_put(p, c);
  CHECK(gs_block_pool_get(p) == c);
  CHECK(gs_block_pool_get(p) == a);
  void *d = gs_block_pool_get(p);
  CHECK(d != a && d != b && d != c);
  CHECK(gs_block_pool_bytes(p) == bytes);
  gs_block_pool_put(p, NULL); /* nothing */
  CHECK(gs_block_pool_get(p) != NULL);
  gs_block_pool_free(p);
  gs_block_pool_free(NULL);
}

/* Blocks larger than a chunk get chunks of whole multiples of 2 MiB. */
static void large_blocks(void) {
  gs_error err;
  const size_t big = ((size_t)2 << 20) + 1;
  gs_block_pool *p = gs_block_pool_create(big, &err);
  char *a = gs_block_pool_get(p), *b = gs_block_pool_get(p);
  CHECK(a && b && a != b);
  if (a && b) {
    memset(a, 1, big);
    memset(b, 2, big);
    CHECK(a[big - 1] == 1 && b[0] == 2);
  }
  CHECK(gs_block_pool_bytes(p) == 2 * ((size_t)4 << 20));
  gs_block_pool_free(p);
}

/* Threads get blocks, stamp them, check the stamp and give them back, many
 * times over: a block handed to two threads at once, or lost from the free
 * list, shows as a wrong stamp or as more memory than the blocks ever held. */
static void threads(void) {
  gs_error err;
  gs_block_pool *p = gs_block_pool_create(256, &err);
  const int nt = 4, held = 16, rounds = 20000;
  int bad = 0;
#pragma omp parallel num_threads(nt) reduction(+ : bad)
  {
    const int me = omp_get_thread_num();
    void *mine[16];
    for (int r = 0; r < rounds; r++) {
      for (int i = 0; i < held; i++) {
        long *blk = mine[i] = gs_block_pool_get(p);
        if (!blk) {
          bad++;
          continue;
        }
        for (int j = 0; j < 32; j++) blk[j] = (long)me * 1000000 + r * 100 + i;
      }
      for (int i = 0; i < held; i++) {
        long *blk = mine[i];
        if (!blk) continue;
        for (int j = 0; j < 32; j++)
          if (blk[j] != (long)me * 1000000 + r * 100 + i) bad++;
        gs_block_pool_put(p, blk);
      }
    }
  }
  CHECK(bad == 0);
  /* at most nt * held blocks were out at once: one chunk holds them all */
  CHECK(gs_block_pool_bytes(p) == ((size_t)2 << 20));
  gs_block_pool_free(p);
}

/* A reservation takes the memory for its blocks at once, and the gets
 * after it take no more, the blocks coming in the order they were cut. */
static void reserve(void) {
  gs_error err;
  gs_block_pool *p = gs_block_pool_create(BLOCK, &err);
  const size_t block = (BLOCK + GS_APART - 1) / GS_APART * GS_APART, per_chunk = ((size_t)2 << 20) / block;
  const size_t n = per_chunk + 3; /* two chunks */
  CHECK(gs_block_pool_reserve(p, n, &err) == GS_OK);
  CHECK(gs_block_pool_bytes(p) == 2 * ((size_t)2 << 20));
  char *first = gs_block_pool_get(p), *second = gs_block_pool_get(p);
  CHECK(first != NULL && second == first + block);
  for (size_t i = 2; i < n; i++) CHECK(gs_block_pool_get(p) != NULL);
  CHECK(gs_block_pool_bytes(p) == 2 * ((size_t)2 << 20));
  CHECK(gs_block_pool_reserve(p, 0, &err) == GS_OK);
  gs_block_pool_free(p);
}

/* The helpers that keep data different threads write whole pages apart
 * (gransim/error.h): strides in whole pages, at least what was asked for;
 * memory on a page boundary, zeroed. */
static void apart_helpers(void) {
  const size_t per = GS_APART / sizeof(double);
  CHECK(GS_APART == 4096);
  CHECK(gs_doubles_apart(0) == 0);
  CHECK(gs_doubles_apart(1) == per && gs_doubles_apart(per) == per && gs_doubles_apart(per + 1) == 2 * per);
  gs_error err;
  for (size_t bytes = 1; bytes <= 3 * GS_APART; bytes += GS_APART / 2 + 3) {
    unsigned char *p = gs_calloc_apart(bytes, &err);
    CHECK(p != NULL);
    if (!p) continue;
    CHECK((uintptr_t)p % GS_APART == 0);
    int zero = 1;
    for (size_t i = 0; i < bytes; i++) zero &= p[i] == 0;
    CHECK(zero);
    free(p);
  }
}

int main(void) {
  distinct_blocks(1);
  distinct_blocks(100); /* three chunks */
  reuse();
  reserve();
  apart_helpers();
  large_blocks();
  threads();
  TEST_EXIT();
}
