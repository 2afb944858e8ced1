/* A pool of equal blocks for memory that a run fills and empties many times
 * (the per-compartment steps' records): blocks given back are handed out
 * again, last in first out (still in cache), and the pool takes its memory
 * from the system in 2 MiB-aligned chunks marked for transparent huge
 * pages: the first write to a fresh page takes a page fault (in a virtual
 * machine the hypervisor's as well), and a huge page costs far less per byte
 * than the 4 KiB pages it replaces (figures in docs/performance.md, "page
 * faults").  Where the kernel gives no huge pages the
 * chunks are plain pages and only the reuse helps.  Safe to use from
 * several threads at once. */
#ifndef GS_BLOCK_POOL_H
#define GS_BLOCK_POOL_H

#include <stddef.h>

#include "gransim/error.h"

typedef struct gs_block_pool gs_block_pool;

/* A pool of blocks of block_bytes each, rounded up to whole 4 KiB pages
 * (GS_APART: threads write neighbouring blocks); no memory yet. */
gs_block_pool *gs_block_pool_create(size_t block_bytes, gs_error *err);
/* A block (its contents undefined), or NULL when out of memory. */
void *gs_block_pool_get(gs_block_pool *p);
/* Give a block from gs_block_pool_get back. */
void gs_block_pool_put(gs_block_pool *p, void *block);
/* Take the memory for n blocks now and touch its pages (a first touch is
 * what costs here), so that the first n gets are cheap; returns GS_OK or
 * GS_ENOMEM. */
int gs_block_pool_reserve(gs_block_pool *p, size_t n, gs_error *err);
/* Bytes the pool took from the system. */
size_t gs_block_pool_bytes(const gs_block_pool *p);
/* Return all memory; the blocks handed out are gone with it. */
void gs_block_pool_free(gs_block_pool *p);

#endif
