/* Aggregation: the sectional form of
 *   dn/dt = 1/2 int beta n n  -  n int beta n
 * over unordered pairs of cells (a, b): w = beta_ab N_a N_b (1/2 if a = b)
 * events per unit time; each removes one particle from a and one from b and
 * creates one at x_a + x_b, which is redistributed onto the pivots by
 *  - cell average (Kumar et al. 2006; Chaudhury 2015 sec. 3.3 in 3-D): the
 *    births landing in each cell are pooled, their mean position computed,
 *    and the pool placed on the 2^dim surrounding pivots by the lever rule;
 *  - fixed pivot (Kumar & Ramkrishna 1996, Vale & McKenna 2005 in 2-D):
 *    each pair's product is placed individually by the lever rule.
 * Both conserve number (one per event) and the volume of every coordinate.
 * Products beyond the last edge of an axis are lost; products between the
 * last pivot and the last edge are clamped to the last pivot (lever.h).
 * Both go to the ledger's lost volume.
 *
 * Work per right-hand side is one pass over the ncells (ncells+1)/2 pairs.
 * Everything that does not depend on the state is precomputed: the kernel
 * table (packed upper triangle, per compartment, when it fits in
 * `table_limit_mb` and the kernel's rows are dear, else kernel rows are
 * evaluated per cell; a row of the table is filled when its cell first
 * takes part, so the memory touched follows the occupied cells), and per
 * axis the target cell of every pivot sum.  Internally the grid is padded to three
 * axes (padding axes of one cell at the front) so one loop nest serves 1-, 2-
 * and 3-D.  The pair loop is parallel over OpenMP threads with per-thread
 * accumulators.
 *
 * Carried quantities (liquid and gas lumped per solid bin, Sampat et al. 2018): each
 * particle of cell c carries Q_q[c] / N[c]; an event removes both partners'
 * loads from their cells and gives their sum to the product; the pooled
 * loads of a target cell are spread over the same nodes, with the same
 * weights, as its particles, so every carried volume is conserved exactly.
 * `wet` makes aggregation need liquid (Sampat et al. 2018, eq. 10): a particle is wet
 * when its liquid / solid volume ratio reaches min_content; pairs need both
 * partners wet, or either (then the dry-dry pairs are subtracted from a pass
 * over all pairs, which keeps every event whole). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "gransim/pbm.h"
#include "gransim/threads.h"
#include "pbm/aggregation_fft.h"
#include "pbm/lever.h"

enum { CELL_AVERAGE = 0, FIXED_PIVOT = 1 };
enum { WET_OFF = 0, WET_BOTH = 1, WET_EITHER = 2 };
enum { METHOD_PAIRS = 0, METHOD_FFT = 1, METHOD_AUTO = 2 };
/* method auto: the FFT from this many cells per compartment on (the
 * crossover measured by bench/bench_aggfft.c, docs/performance.md) */
#define FFT_MIN_CELLS 256
/* method auto with a low-rank kernel form: the FFT while rank <= cells /
 * LOWRANK_CELLS_PER_TERM.  Each term costs one transform more, and the
 * FFT's lead over the pairs grows with the grid (15x at 256 cells, 50x at
 * 1024, 700x at 4096 for one term); this keeps it about 6x or more. */
#define LOWRANK_CELLS_PER_TERM 64
/* method auto on non-uniform pivots (the near/far split, aggregation_split.c):
 * the split while its tuples times terms stay within cells^2 / this.  The
 * pairs skip empty cells and the split less so: on a dense state the split
 * was 1.4-5x faster in 1-D (256-512 cells, ratio 1.19) and 2-7x in 2-D
 * (256-1024 cells, ratio 1.6), but at the 3-D Madec case's own state (3 462
 * of 17 576 cells occupied) 2.3x slower, so auto keeps the pairs in 3-D
 * (bench/bench_aggfft.c geometric, docs/performance.md). */
#define SPLIT_PAIRS_PER_TUPLE 8

/* Per compartment, the choices made once per time value; a page each
 * (GS_APART), as threads evaluating neighbouring compartments at once write
 * them at every evaluation (per-compartment steps). */
typedef struct {
  _Alignas(GS_APART) double span_t; /* time of the state the spans were computed from */
  double wet_t;               /* time of the wetness choice (NAN: none yet) */
  size_t prange[2];           /* [lo, hi) of the cells in the spans */
  int span_valid;             /* spans computed at least once */
  unsigned long span_era, wet_era; /* gs_eval.era of those choices */
} comp_choice;

/* Per slot, the cells of its summed arrays its last use wrote (a page
 * each, for the same reason). */
typedef struct {
  _Alignas(GS_APART) size_t lo, hi;
} dirty_range;

typedef struct {
  gs_kernel kernel;
  int scheme;
  int dim, off;          /* real axes occupy padded positions off..2 */
  size_t ncells, ncomp, big;
  size_t n[3], stride[3];
  double *x[3];          /* per cell coordinate on padded axis q (NULL for padding) */
  size_t *target[3];     /* n[q]*n[q]: cell of the pivot sum along q, times stride; >= big if outside */
  size_t *fp_lo[3];      /* fixed pivot: lower node times stride, >= big if above the last pivot */
  double *fp_w[3];       /* fixed pivot: weight of the upper node */
  double *fp_excess[3];  /* fixed pivot: sum minus last pivot where clamped, else 0 */
  double *table;         /* packed kernel, table_comps * ncells*(ncells+1)/2, or NULL */
  size_t table_size, table_comps; /* table_comps: ncomp, or 1 when beta is the same in all */
  unsigned char *row_state; /* table_comps * ncells: ROW_* of each row of the table */
  double negligible;     /* cells holding less than this share of number and volume are skipped */
  size_t nrows;          /* rows along the last padded axis: n[0] * n[1] */
  /* per compartment, on whole pages (threads advancing neighbouring
   * compartments write them at every evaluation): entries of span (2 nrows)
   * and of wet_ok (ncells) */
  size_t span_len, wet_len;
  size_t *span;          /* per compartment and row: [lo, hi) of the cells taking part */
  comp_choice *cs;       /* per compartment: when its spans and wetness were chosen */
  int nc;                /* carried quantities */
  double *pcar;          /* per slot (pcar_len apart) nc * ncells: load per particle in the compartment being evaluated */
  size_t pcar_len, masked_len; /* per-slot strides, whole pages (GS_APART) */
  int wet, wet_liquid;   /* WET_*; carried index of the liquid (-1: a grid axis) */
  int wet_axis;          /* the liquid's grid axis when it is one (De et al. 2025's 3-D grid), else -1 */
  double wet_min;        /* liquid / solid volume ratio that makes a particle wet */
  double wet_ramp;       /* relative width of the switch (0: a step, as in Sampat et al. 2018) */
  double *wet_ok;        /* ncomp * ncells: wetness psi in [0, 1], chosen once per time value */
  double *masked;        /* ncells: numbers of the wet (or dry) cells for a pass */
  int nthreads;
  size_t work_len;
  double *work;          /* per thread: death, B, V[3], fp birth, row  */
  dirty_range *dirty;    /* per thread: [lo, hi) of the cells its summed arrays may hold non-zero */
  gs_agg_fft *fft;       /* method fft: births and deaths as convolutions (aggregation_fft.c), or NULL */
} agg_t;

static size_t packed_offset(size_t a, size_t n) { return a * n - a * (a - 1) / 2; }

static void agg_free(void *self) {
  agg_t *A = self;
  if (!A) return;
  gs_agg_fft_free(A->fft);
  gs_kernel_free(&A->kernel);
  for (int q = 0; q < 3; q++) {
    free(A->x[q]);
    free(A->target[q]);
    free(A->fp_lo[q]);
    free(A->fp_w[q]);
    free(A->fp_excess[q]);
  }
  free(A->table);
  free(A->row_state);
  free(A->span);
  free(A->cs);
  free(A->pcar);
  free(A->wet_ok);
  free(A->masked);
  free(A->work);
  free(A->dirty);
  free(A);
}

/* Per-axis tables of where the sum of two pivots lands: four values of 8
 * bytes per pair of an axis' cells.  The pairs' method alone builds them
 * (fft never; auto only where it falls back on the pairs, which is not
 * known before the kernel is built, so not counted here). */
static double agg_grid_bytes(gs_cfg_node *node, const gs_grid *g) {
  const char *method = gs_cfg_scalar(gs_cfg_get(node, "method"));
  if (method && strcmp(method, "pairs")) return 0;
  double bytes = 0;
  for (int k = 0; k < g->dim; k++) bytes += 32.0 * (double)g->axis[k].n * (double)g->axis[k].n;
  return bytes;
}

static int build_axis_maps(agg_t *A, const gs_grid *g, gs_error *err) {
  for (int q = 0; q < 3; q++) {
    size_t n = A->n[q];
    A->target[q] = gs_malloc(n * n * sizeof(size_t), err);
    A->fp_lo[q] = gs_malloc(n * n * sizeof(size_t), err);
    A->fp_w[q] = gs_calloc(n * n, sizeof(double), err);
    A->fp_excess[q] = gs_calloc(n * n, sizeof(double), err);
    if (!A->target[q] || !A->fp_lo[q] || !A->fp_w[q] || !A->fp_excess[q]) return GS_ENOMEM;
    if (q < A->off) { /* padding axis: a single cell mapping onto itself */
      A->target[q][0] = 0;
      A->fp_lo[q][0] = 0;
      continue;
    }
    const gs_axis *ax = &g->axis[q - A->off];
    for (size_t i = 0; i < n; i++)
      for (size_t j = 0; j < n; j++) {
        double s = ax->pivots[i] + ax->pivots[j];
        size_t t = gs_axis_locate_snapped(ax, s);
        A->target[q][i * n + j] = t == GS_NOWHERE ? A->big : t * A->stride[q];
        size_t lo;
        double w;
        int st = gs_axis_lever(ax, s, &lo, &w);
        if (st == 0) {
          A->fp_lo[q][i * n + j] = lo * A->stride[q];
          A->fp_w[q][i * n + j] = w;
        } else if (t != GS_NOWHERE) { /* inside the last cell, above its pivot: clamp */
          A->fp_lo[q][i * n + j] = (n - 1) * A->stride[q];
          A->fp_excess[q][i * n + j] = s - ax->pivots[n - 1];
        } else {
          A->fp_lo[q][i * n + j] = A->big;
        }
      }
  }
  return GS_OK;
}

static int build_kernel_table(agg_t *A, double limit_mb, gs_error *err) {
  size_t per = A->ncells * (A->ncells + 1) / 2;
  const gs_kernel_type *kt = A->kernel.type;
  /* a row as cheap as reading it: a table would only cost memory (and its
   * reads miss the cache on large grids) */
  if (kt->cheap_row && kt->cheap_row(A->kernel.self)) return GS_OK;
  A->table_comps = kt->per_compartment && kt->per_compartment(A->kernel.self) ? A->ncomp : 1;
  double mb = (double)(per * A->table_comps) * sizeof(double) / 1048576.0;
  if (mb > limit_mb) return GS_OK; /* evaluate rows on the fly */
  A->table_size = per;
  /* Not filled here (table_row fills a row at its first use): pages of a
   * large allocation are given memory only when written, so rows of cells
   * that never hold particles cost address space alone. */
  A->table = gs_malloc(per * A->table_comps * sizeof(double), err);
  A->row_state = gs_calloc(A->table_comps * A->ncells, 1, err);
  if (!A->table || !A->row_state) return GS_ENOMEM;
  return GS_OK;
}

enum { ROW_EMPTY = 0, ROW_FILLING = 1, ROW_READY = 2 };

/* Row a of the table (beta against b >= a) for compartment comp, filled
 * with the kernel's row() on first use; NULL while another thread fills it
 * (threads evaluating compartments that share one table), and the caller
 * then evaluates the row segments it needs itself: the same values. */
static const double *table_row(const agg_t *A, size_t comp, size_t a) {
  const size_t t = A->table_comps > 1 ? comp : 0;
  unsigned char *state = A->row_state + t * A->ncells + a;
  double *row = A->table + t * A->table_size + packed_offset(a, A->ncells);
  if (__atomic_load_n(state, __ATOMIC_ACQUIRE) == ROW_READY) return row;
  unsigned char empty = ROW_EMPTY;
  if (!__atomic_compare_exchange_n(state, &empty, ROW_FILLING, 0, __ATOMIC_ACQUIRE, __ATOMIC_RELAXED))
    return NULL;
  A->kernel.type->row(A->kernel.self, t, a, a, A->ncells, row);
  __atomic_store_n(state, ROW_READY, __ATOMIC_RELEASE);
  return row;
}

/* wet: {min_content, partners: both | either, liquid: <carried quantity or grid axis>} */
static int read_wet(gs_cfg_node *node, const gs_model *m, agg_t *A, gs_error *err) {
  static const char *const partners[] = {"both", "either", NULL};
  gs_cfg_node *wn = gs_cfg_get(node, "wet");
  if (!wn) return GS_OK;
  const char *liquid = NULL;
  int mode = 0;
  int rc = gs_cfg_require_kind(wn, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_double_range(wn, "min_content", 1, 0, 0, 0, HUGE_VAL, 0, &A->wet_min, err);
  if (!rc) rc = gs_cfg_enum_opt(wn, "partners", partners, 0, &mode, err);
  if (!rc) rc = gs_cfg_double_range(wn, "ramp", 0, 0.1, 0, 0, 2, 1, &A->wet_ramp, err);
  if (!rc) rc = gs_cfg_string_opt(wn, "liquid", "liquid", &liquid, err);
  A->wet_axis = -1;
  if (!rc && (A->wet_liquid = gs_model_carried_index(m, liquid)) < 0 &&
      (A->wet_axis = gs_grid_axis_by_name(&m->grid, liquid)) < 0) {
    gs_cfg_node *ln = gs_cfg_get(wn, "liquid");
    rc = gs_cfg_fail(ln ? ln : wn, err, "needs a carried quantity or a grid axis named '%s' (grid.carried, "
                     "grid.axes)", liquid);
  }
  if (!rc) rc = gs_cfg_check_unused(wn, err);
  A->wet = mode == 0 ? WET_BOTH : WET_EITHER;
  return rc;
}

/* method: pairs | fft | auto.  The FFT (the near/far split on non-uniform
 * pivots) serves fixed pivot with a kernel of separable form, without
 * wetness or carried quantities; auto takes it where it serves and the grid
 * is large enough for it to pay. */
static int choose_method(gs_cfg_node *node, const gs_model *m, agg_t *A, gs_error *err) {
  static const char *const methods[] = {"pairs", "fft", "auto", NULL};
  int method = METHOD_PAIRS;
  int rc = gs_cfg_enum_opt(node, "method", methods, METHOD_PAIRS, &method, err);
  double tol = 0;
  if (!rc) rc = gs_cfg_double_range(node, "rank_tolerance", 0, 0, 0, 1, 1, 1, &tol, err);
  if (!rc && tol > 0 && method == METHOD_PAIRS)
    rc = gs_cfg_fail(gs_cfg_get(node, "rank_tolerance"), err, "applies to method fft or auto, not pairs");
  if (rc || method == METHOD_PAIRS) return rc;
  const char *why = A->scheme != FIXED_PIVOT ? "needs redistribution: fixed_pivot"
                    : A->wet != WET_OFF      ? "does not take wet"
                    : m->ncarried            ? "does not move carried quantities (grid.carried)"
                                             : gs_agg_fft_unusable(&m->grid, &A->kernel, tol);
  if (why && method == METHOD_FFT) {
    gs_cfg_node *mn = gs_cfg_get(node, "method");
    return gs_cfg_fail(mn ? mn : node, err, "fft %s; use method: pairs or auto", why);
  }
  if (why || (method == METHOD_AUTO && m->grid.ncells < FFT_MIN_CELLS)) return GS_OK;
  rc = gs_agg_fft_create(&m->grid, &A->kernel, tol, m->nslots, &A->fft, err);
  if (rc == GS_EINPUT && method == METHOD_AUTO) return GS_OK; /* no low-rank form within the term cap: the pairs */
  if (rc == GS_EINPUT) { /* that refusal, at the key that asked for the form */
    char why_form[sizeof err->msg];
    snprintf(why_form, sizeof why_form, "%s", err->msg);
    return gs_cfg_fail(gs_cfg_get(node, "rank_tolerance"), err, "%s", why_form);
  }
  const double split = rc ? 0 : gs_agg_fft_split_work(A->fft), cells = (double)m->grid.ncells;
  if (!rc && method == METHOD_AUTO &&
      (gs_agg_fft_rank(A->fft, NULL) > (int)(m->grid.ncells / LOWRANK_CELLS_PER_TERM) ||
       (split > 0 && (m->grid.dim == 3 || split > cells * cells / SPLIT_PAIRS_PER_TUPLE)))) {
    gs_agg_fft_free(A->fft); /* too many terms or tuples to pay: the pairs */
    A->fft = NULL;
  }
  return rc;
}

static size_t summed_arrays(const agg_t *A);

static int agg_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  static const char *const schemes[] = {"cell_average", "fixed_pivot", NULL};
  const gs_grid *g = &m->grid;
  agg_t *A = gs_calloc(1, sizeof *A, err);
  if (!A) return GS_ENOMEM;
  double limit_mb = 0;
  gs_cfg_node *kn = NULL;
  int rc = gs_cfg_enum_opt(node, "redistribution", schemes, CELL_AVERAGE, &A->scheme, err);
  if (!rc) rc = gs_cfg_double_range(node, "table_limit_mb", 0, 1024, 0, 0, HUGE_VAL, 0, &limit_mb, err);
  if (!rc) rc = gs_cfg_double_range(node, "negligible", 0, 1e-14, 0, 0, 1e-3, 0, &A->negligible, err);
  if (!rc) rc = read_wet(node, m, A, err);
  if (!rc && m->ncarried && A->scheme == FIXED_PIVOT)
    rc = gs_cfg_fail(node, err, "fixed_pivot does not move carried quantities (grid.carried); use cell_average");
  if (!rc) rc = gs_cfg_map_req(node, "kernel", &kn, err);
  if (!rc) rc = gs_kernel_create(kn, g, m->dir, &A->kernel, err);
  if (!rc) rc = choose_method(node, m, A, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    agg_free(A);
    return rc;
  }
  A->dim = g->dim;
  A->off = 3 - g->dim;
  A->ncells = g->ncells;
  A->ncomp = g->ncomp;
  A->big = 3 * g->ncells + 3;
  for (int q = 0; q < 3; q++) {
    int k = q - A->off;
    A->n[q] = k >= 0 ? g->axis[k].n : 1;
    A->stride[q] = k >= 0 ? g->stride[k] : 0;
    if (k >= 0) {
      A->x[q] = gs_malloc(g->ncells * sizeof(double), err);
      if (!A->x[q]) rc = GS_ENOMEM;
      for (size_t c = 0; !rc && c < g->ncells; c++) A->x[q][c] = g->x[c * (size_t)g->dim + (size_t)k];
    }
  }
  /* the FFT needs neither (the maps hold n^2 entries per axis) */
  if (!rc && !A->fft) rc = build_axis_maps(A, g, err);
  if (!rc && !A->fft) rc = build_kernel_table(A, limit_mb, err);
  if (!rc) {
    A->nthreads = m->nslots > 0 ? m->nslots : 1;
    A->nc = m->ncarried;
    const size_t nslot = (size_t)A->nthreads;
    /* per slot, on pages of their own: threads write them at once */
    A->pcar_len = gs_doubles_apart((size_t)A->nc * A->ncells + 1);
    A->pcar = gs_calloc_apart(nslot * A->pcar_len * sizeof(double), err);
    A->wet_len = gs_doubles_apart(A->ncells);
    A->wet_ok = gs_calloc_apart(A->ncomp * A->wet_len * sizeof(double), err);
    A->masked_len = gs_doubles_apart(A->ncells);
    A->masked = gs_calloc_apart(nslot * A->masked_len * sizeof(double), err);
    A->cs = gs_calloc_apart(A->ncomp * sizeof(comp_choice), err);
    if (!A->pcar || !A->wet_ok || !A->cs || !A->masked) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t c = 0; !rc && c < A->ncomp; c++)
      A->cs[c] = (comp_choice){0.0, NAN, {0, 0}, 0, 0, 0}; /* nothing chosen yet */
    /* loads are computed only where pairs read them (carried_loads): a read
     * elsewhere would show as NaN, not as a load of another compartment */
    for (size_t i = 0; !rc && i < nslot * A->pcar_len; i++) A->pcar[i] = NAN;
    A->nrows = A->n[0] * A->n[1];
    A->span_len = gs_doubles_apart(2 * A->nrows); /* size_t: 8 bytes, as a double */
    A->span = gs_calloc_apart(A->span_len * A->ncomp * sizeof(size_t), err);
    if (!A->span) rc = GS_ENOMEM;
    A->work_len = gs_doubles_apart((summed_arrays(A) + 1) * A->ncells + A->n[2]);
    A->work = gs_calloc_apart((size_t)A->nthreads * A->work_len * sizeof(double), err);
    A->dirty = gs_calloc_apart((size_t)A->nthreads * sizeof(dirty_range), err);
    if (!A->work || !A->dirty) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
    for (int t = 0; !rc && t < A->nthreads; t++) { /* all of it, the first time */
      A->dirty[t].lo = 0;
      A->dirty[t].hi = A->ncells;
    }
  }
  if (rc) {
    agg_free(A);
    return rc;
  }
  *self = A;
  return GS_OK;
}

/* Accumulators of one thread. */
typedef struct {
  double *death, *births, *vol[3], *fp, *row, *wrow;
  double *cvol[GS_MAX_CARRIED]; /* pooled carried loads per target cell */
  /* cell average: the pool of the pairs with a negative rate (a partner's
   * count below zero: integration noise), kept apart from births, vol and
   * cvol so that each pool's mean lies in its target cell (see pairs_generic) */
  double *nbirths, *nvol[3], *ncvol[GS_MAX_CARRIED];
  const double *pcar;           /* loads per particle of the compartment (read only) */
  double lost_n, lost_v[3], lost_c[GS_MAX_CARRIED];
  /* [lo, hi): the cells written in the summed arrays (deaths of the cells
   * taking part, births at their targets).  Large grids hold their
   * population in a band, and the passes over the cells, with the zeroing
   * before the next use, had cost more than the pairs (32 x 32 bins). */
  size_t lo, hi;
} acc_t;

/* Per-thread work: death, births, vol[3], cvol[nc], fp, and with cell
 * average the negative pool nbirths, nvol[3], ncvol[nc] (zeroed and summed
 * over threads), then row and wrow (scratch). */
static size_t summed_arrays(const agg_t *A) {
  return (size_t)(6 + A->nc) + (A->scheme == FIXED_PIVOT ? 0 : (size_t)(4 + A->nc));
}
static size_t summed_len(const agg_t *A) { return summed_arrays(A) * A->ncells; }

/* Zero the cells of thread tid's summed arrays that its last use wrote. */
static void clear_dirty(const agg_t *A, int tid) {
  double *w = A->work + (size_t)tid * A->work_len;
  const size_t lo = A->dirty[tid].lo, hi = A->dirty[tid].hi;
  if (lo < hi)
    for (size_t k = 0; k < summed_arrays(A); k++) memset(w + k * A->ncells + lo, 0, (hi - lo) * sizeof(double));
  A->dirty[tid].lo = A->ncells;
  A->dirty[tid].hi = 0;
}

/* Thread tid's summed arrays are written in [lo, hi) now. */
static void mark_dirty(const agg_t *A, int tid, size_t lo, size_t hi) {
  if (lo < A->dirty[tid].lo) A->dirty[tid].lo = lo;
  if (hi > A->dirty[tid].hi) A->dirty[tid].hi = hi;
}

static acc_t thread_acc(const agg_t *A, int tid) {
  double *w = A->work + (size_t)tid * A->work_len;
  size_t n = A->ncells, nc = (size_t)A->nc;
  acc_t acc;
  memset(&acc, 0, sizeof acc);
  acc.death = w;
  acc.births = w + n;
  for (int q = 0; q < 3; q++) acc.vol[q] = w + (2 + (size_t)q) * n;
  for (size_t q = 0; q < nc; q++) acc.cvol[q] = w + (5 + q) * n;
  acc.fp = w + (5 + nc) * n;
  if (A->scheme != FIXED_PIVOT) {
    acc.nbirths = w + (6 + nc) * n;
    for (int q = 0; q < 3; q++) acc.nvol[q] = w + (7 + nc + (size_t)q) * n;
    for (size_t q = 0; q < nc; q++) acc.ncvol[q] = w + (10 + nc + q) * n;
  }
  acc.row = w + summed_arrays(A) * n;
  acc.wrow = w + (summed_arrays(A) + 1) * n;
  clear_dirty(A, tid);
  acc.lo = n;
  acc.hi = 0;
  return acc;
}

/* All pairs (a, b >= a) of one compartment for a fixed a.  Written once and
 * specialised by the compiler for each (DIM, FP) through always_inline with
 * constant arguments; all pointers are local and restrict so the hot loop
 * keeps them in registers. */
static inline __attribute__((always_inline)) void
pairs_generic(const agg_t *A, size_t comp, const double *restrict N, size_t a, acc_t *acc,
              const int DIM, const int FP) {
  const double Na = N[a];
  const size_t n0 = A->n[0], n1 = A->n[1], n2 = A->n[2], ncells = A->ncells;
  const size_t a0 = a / (n1 * n2), a1 = (a / n2) % n1, a2 = a % n2;
  /* kernel values against b >= a: from the table, or evaluated below per row segment */
  const double *tab = A->table ? table_row(A, comp, a) : NULL;
  const double *restrict beta = tab ? tab - a : acc->row - a;
  const size_t *restrict span = A->span + comp * A->span_len;
  const int off = 3 - DIM;
  double *restrict death = acc->death, *restrict births = acc->births, *restrict fp = acc->fp;
  double *restrict v0 = acc->vol[off], *restrict v1 = DIM > 1 ? acc->vol[off + 1] : NULL;
  double *restrict v2 = DIM > 2 ? acc->vol[2] : NULL;
  const double *restrict x0 = A->x[off], *restrict x1 = DIM > 1 ? A->x[off + 1] : NULL;
  const double *restrict x2 = DIM > 2 ? A->x[2] : NULL;
  const double xa0 = x0[a], xa1 = DIM > 1 ? x1[a] : 0, xa2 = DIM > 2 ? x2[a] : 0;
  /* carried loads per particle (cell average only) */
  const int NC = FP ? 0 : A->nc;
  const double *restrict p0 = acc->pcar, *restrict p1 = acc->pcar + ncells;
  const double pa0 = NC > 0 ? p0[a] : 0, pa1 = NC > 1 ? p1[a] : 0;
  double *restrict c0 = acc->cvol[0], *restrict c1 = acc->cvol[1];
  double lostq0 = 0, lostq1 = 0;
  const size_t *T0 = A->target[0] + a0 * n0, *T1 = A->target[1] + a1 * n1;
  const size_t *restrict T2 = A->target[2] + a2 * n2;
  const size_t *L0 = A->fp_lo[0] + a0 * n0, *L1 = A->fp_lo[1] + a1 * n1;
  const size_t *restrict L2 = A->fp_lo[2] + a2 * n2;
  const double *W0 = A->fp_w[0] + a0 * n0, *W1 = A->fp_w[1] + a1 * n1;
  const double *restrict W2 = A->fp_w[2] + a2 * n2;
  const double *E0 = A->fp_excess[off] + (off == 0 ? a0 * n0 : off == 1 ? a1 * n1 : a2 * n2);
  const double *E1 = DIM > 1 ? A->fp_excess[off + 1] + (off == 0 ? a1 * n1 : a2 * n2) : NULL;
  const double *E2 = DIM > 2 ? A->fp_excess[2] + a2 * n2 : NULL;
  const size_t s0 = A->stride[0], s1 = A->stride[1], s2 = A->stride[2], big = A->big;
  double death_a = 0, lost_n = 0, lost0 = 0, lost1 = 0, lost2 = 0;
  /* cells written: deaths of a and of the partners after it; births at the
   * pivot sums, which lie at or after a on every axis, hence at or after a
   * (fixed pivot: up to the last cell; cell average: up to the last target
   * of each row, where the targets never decrease) */
  const size_t touched_lo = a;
  size_t touched_hi = FP ? ncells : a + 1;
  for (size_t i0 = a0; i0 < n0; i0++) {
    for (size_t i1 = (i0 == a0 ? a1 : 0); i1 < n1; i1++) {
      const size_t r = i0 * n1 + i1, row_end = span[2 * r + 1];
      const size_t row_start = (i0 == a0 && i1 == a1) ? a2 : span[2 * r];
      if (row_start >= row_end) continue; /* nothing in this row takes part */
      const size_t bbase = r * n2, tbase = T0[i0] + T1[i1];
      if (!tab)
        A->kernel.type->row(A->kernel.self, comp, a, bbase + row_start, bbase + row_end,
                            acc->row + (bbase + row_start - a));
      const size_t lbase = L0[i0] + L1[i1];
      const double w0 = W0[i0], w1 = W1[i1];
      /* clamping excess of the axes that are fixed along this row */
      const double e_fix0 = FP ? (off == 0 ? E0[i0] : off == 1 ? E0[i1] : 0.0) : 0.0;
      const double e_fix1 = FP && DIM > 1 ? (off == 0 ? E1[i1] : 0.0) : 0.0;
      /* pass 1 (vectorised): event rates of the row and the deaths they cause */
      const size_t len = row_end - row_start;
      const double *restrict Nb = N + bbase + row_start, *restrict bb = beta + bbase + row_start;
      double *restrict wr = acc->wrow;
      for (size_t j = 0; j < len; j++) wr[j] = Na * bb[j] * Nb[j];
      if (bbase + row_start == a) wr[0] *= 0.5; /* a self-pair counts once */
      double *restrict db = death + bbase + row_start;
      if (bbase + row_end > touched_hi) touched_hi = bbase + row_end; /* rows only grow */
      for (size_t j = 0; j < len; j++) {
        db[j] += wr[j];
        death_a += wr[j];
      }
      /* pass 2: births.  Along a row the target cell never decreases, so runs
       * with the same target are summed in registers before one store; this
       * avoids store-to-load chains on the same accumulator. */
      size_t t_run = (size_t)-1;
      double rb = 0, r0 = 0, r1 = 0, r2 = 0, q0 = 0, q1 = 0;
      for (size_t i2 = row_start; i2 < row_end; i2++) {
        const size_t b = bbase + i2;
        const double w = wr[i2 - row_start];
        if (w == 0.0) continue;
        if (!FP) {
          const size_t t = tbase + T2[i2];
          if (t < ncells && w < 0.0) {
            /* A partner's count below zero (integration noise): pooled
             * with the positive births of t, the mean of a mixed-sign pool
             * can lie far outside t, and the lever would carry the packet
             * to the grid's far corners (where consolidation, say, is very
             * stiff); pooled apart, each pool's mean lies in t. */
            acc->nbirths[t] += w;
            acc->nvol[off][t] += w * (xa0 + x0[b]);
            if (DIM > 1) acc->nvol[off + 1][t] += w * (xa1 + x1[b]);
            if (DIM > 2) acc->nvol[2][t] += w * (xa2 + x2[b]);
            if (NC > 0) acc->ncvol[0][t] += w * (pa0 + p0[b]);
            if (NC > 1) acc->ncvol[1][t] += w * (pa1 + p1[b]);
            if (t + 1 > touched_hi) touched_hi = t + 1;
            continue;
          }
          if (t < ncells) {
            if (t != t_run) {
              if (t_run != (size_t)-1) {
                births[t_run] += rb;
                v0[t_run] += r0;
                if (DIM > 1) v1[t_run] += r1;
                if (DIM > 2) v2[t_run] += r2;
                if (NC > 0) c0[t_run] += q0;
                if (NC > 1) c1[t_run] += q1;
              }
              t_run = t;
              rb = r0 = r1 = r2 = q0 = q1 = 0;
            }
            rb += w;
            r0 += w * (xa0 + x0[b]);
            if (DIM > 1) r1 += w * (xa1 + x1[b]);
            if (DIM > 2) r2 += w * (xa2 + x2[b]);
            if (NC > 0) q0 += w * (pa0 + p0[b]);
            if (NC > 1) q1 += w * (pa1 + p1[b]);
            continue;
          }
        } else {
          const size_t lo = lbase + L2[i2];
          if (lo < big) {
            /* DIM-linear lever; padded axes have weight 0 towards "up" */
            const double w2 = W2[i2];
            const double f2[2] = {1 - w2, w2};
            const double f1[2] = {1 - w1, w1};
            const double f0[2] = {1 - w0, w0};
            for (int u0 = 0; u0 < (DIM > 2 ? 2 : 1); u0++)
              for (int u1 = 0; u1 < (DIM > 1 ? 2 : 1); u1++)
                for (int u2 = 0; u2 < 2; u2++) {
                  double f = w * f2[u2] * (DIM > 1 ? f1[u1] : 1.0) * (DIM > 2 ? f0[u0] : 1.0);
                  if (f != 0.0) fp[lo + (size_t)u2 * s2 + (size_t)u1 * s1 + (size_t)u0 * s0] += f;
                }
            /* excess along each real axis: axis off+k is padded index off+k */
            lost0 += w * (off == 2 ? E0[i2] : e_fix0);
            if (DIM > 1) lost1 += w * (off == 1 ? E1[i2] : e_fix1);
            if (DIM > 2) lost2 += w * E2[i2];
            continue;
          }
        }
        lost_n += w; /* the product lies beyond the grid */
        if (NC > 0) lostq0 += w * (pa0 + p0[b]);
        if (NC > 1) lostq1 += w * (pa1 + p1[b]);
        lost0 += w * (xa0 + x0[b]);
        if (DIM > 1) lost1 += w * (xa1 + x1[b]);
        if (DIM > 2) lost2 += w * (xa2 + x2[b]);
      }
      if (!FP && t_run != (size_t)-1) {
        if (t_run + 1 > touched_hi) touched_hi = t_run + 1;
        births[t_run] += rb;
        v0[t_run] += r0;
        if (DIM > 1) v1[t_run] += r1;
        if (DIM > 2) v2[t_run] += r2;
        if (NC > 0) c0[t_run] += q0;
        if (NC > 1) c1[t_run] += q1;
      }
    }
  }
  death[a] += death_a;
  if (touched_lo < acc->lo) acc->lo = touched_lo;
  if (touched_hi > acc->hi) acc->hi = touched_hi;
  acc->lost_n += lost_n;
  acc->lost_v[off] += lost0;
  if (DIM > 1) acc->lost_v[off + 1] += lost1;
  if (DIM > 2) acc->lost_v[2] += lost2;
  acc->lost_c[0] += lostq0;
  acc->lost_c[1] += lostq1;
}

static void pairs_of(const agg_t *A, size_t comp, const double *N, size_t a, acc_t *acc) {
  switch (A->dim * 2 + A->scheme) {
  case 2: pairs_generic(A, comp, N, a, acc, 1, 0); break;
  case 3: pairs_generic(A, comp, N, a, acc, 1, 1); break;
  case 4: pairs_generic(A, comp, N, a, acc, 2, 0); break;
  case 5: pairs_generic(A, comp, N, a, acc, 2, 1); break;
  case 6: pairs_generic(A, comp, N, a, acc, 3, 0); break;
  default: pairs_generic(A, comp, N, a, acc, 3, 1); break;
  }
}

/* Sum the per-thread accumulators into thread 0's. */
static void reduce_threads(const agg_t *A, int nth, acc_t *acc) {
  for (int t = 1; t < nth; t++) {
    const double *src = A->work + (size_t)t * A->work_len;
    double *dst = A->work;
    for (size_t i = 0; i < summed_len(A); i++) dst[i] += src[i];
    if (acc[t].lo < acc[0].lo) acc[0].lo = acc[t].lo;
    if (acc[t].hi > acc[0].hi) acc[0].hi = acc[t].hi;
    acc[0].lost_n += acc[t].lost_n;
    for (int q = 0; q < 3; q++) acc[0].lost_v[q] += acc[t].lost_v[q];
    for (int q = 0; q < GS_MAX_CARRIED; q++) acc[0].lost_c[q] += acc[t].lost_c[q];
  }
}

/* Which cells take part in this evaluation.  A cell holding less than
 * `negligible` of the compartment's number AND of its volume is left out
 * (together with every pair it belongs to, so number and volume stay exactly
 * conserved); along each row of the last axis the cells that take part are
 * the span between the first and the last cell that matters.  Populations on
 * large grids occupy a thin band (aggregates tend to the mean composition),
 * so whole rows and most pairs drop out. */
static void find_spans(agg_t *A, size_t comp, const double *N, double noise) {
  const size_t n2 = A->n[2];
  size_t *span = A->span + comp * A->span_len;
  double ntot = 0, vtot = 0;
  for (size_t c = 0; c < A->ncells; c++) {
    double v = 0;
    for (int q = A->off; q < 3; q++) v += A->x[q][c];
    if (N[c] > 0) {
      ntot += N[c];
      vtot += N[c] * v;
    }
  }
  const double nmin = A->negligible * ntot, vmin = A->negligible * vtot;
  size_t first = A->ncells, last = 0;
  for (size_t r = 0; r < A->nrows; r++) {
    size_t lo = n2, hi = 0;
    for (size_t i = 0; i < n2; i++) {
      size_t c = r * n2 + i;
      if (N[c] == 0.0) continue;
      double v = 0;
      for (int q = A->off; q < 3; q++) v += A->x[q][c];
      if (fabs(N[c]) > noise && (fabs(N[c]) > nmin || fabs(N[c]) * v > vmin)) {
        if (lo == n2) lo = i;
        hi = i + 1;
      }
    }
    span[2 * r] = lo;
    span[2 * r + 1] = hi;
    if (lo < hi) {
      if (first == A->ncells) first = r * n2 + lo;
      last = r * n2 + hi;
    }
  }
  A->cs[comp].prange[0] = first;
  A->cs[comp].prange[1] = last;
  A->cs[comp].span_valid = 1;
}

/* Choose the cells taking part in compartment comp's pair loop for the
 * numbers N (find_spans), or keep the last choice: it is made once per
 * time value under an integrator, and kept while held (Jacobian-vector
 * difference quotients, whose perturbed state has tolerance-sized noise in
 * every cell), so that Newton iterations see one smooth right-hand side. */
static void choose_cells(agg_t *A, size_t comp, double t, const double *N, const gs_eval *ev) {
  /* held or not, a choice never outlives its output interval (era): a run
   * resumed there makes it afresh, so the uninterrupted run must too */
  int keep = A->cs[comp].span_valid && ev->era == A->cs[comp].span_era &&
             (ev->hold || (ev->in_integrator && t == A->cs[comp].span_t));
  if (!keep) {
    find_spans(A, comp, N, A->negligible > 0 ? ev->noise_floor : 0.0);
    A->cs[comp].span_t = t;
    A->cs[comp].span_era = ev->era;
  }
}

/* Pair loop of one compartment over the cells choose_cells chose.  slot <
 * 0: this compartment alone, split over the OpenMP team (result in acc[0]);
 * slot >= 0: called by thread `slot` of a team that splits the
 * compartments, so the loop is serial (result in acc[slot]). */
static void compartment_pairs(agg_t *A, size_t comp, const double *N, acc_t *acc, int slot,
                              const double *pcar) {
  const size_t *span = A->span + comp * A->span_len;
  /* small grids (or one thread): a parallel region costs more than the pairs */
  if (slot < 0 && (A->nthreads < 2 || gs_threads_for(A->ncells, 401) < 2)) slot = 0;
  if (slot >= 0) {
    acc[slot] = thread_acc(A, slot);
    acc[slot].pcar = pcar;
    for (size_t a = 0; a < A->ncells; a++) {
      const size_t r = a / A->n[2], i = a % A->n[2];
      if (N[a] != 0.0 && i >= span[2 * r] && i < span[2 * r + 1]) pairs_of(A, comp, N, a, &acc[slot]);
    }
    mark_dirty(A, slot, acc[slot].lo, acc[slot].hi);
    return;
  }
  int nth = 1;
  /* at most the team the per-thread scratch was made for (a program may
   * ask OpenMP for more threads after the case is built) */
#pragma omp parallel num_threads(A->nthreads)
  {
#pragma omp single
    nth = omp_get_num_threads();
    int tid = omp_get_thread_num();
    acc[tid] = thread_acc(A, tid);
    acc[tid].pcar = pcar;
#pragma omp for schedule(static, 8)
    for (size_t a = 0; a < A->ncells; a++) {
      const size_t r = a / A->n[2], i = a % A->n[2];
      if (N[a] != 0.0 && i >= span[2 * r] && i < span[2 * r + 1])
        pairs_of(A, comp, N, a, &acc[tid]);
    }
    mark_dirty(A, tid, acc[tid].lo, acc[tid].hi);
  }
  reduce_threads(A, nth, acc);
  mark_dirty(A, 0, acc[0].lo, acc[0].hi); /* the others' sums added into thread 0's */
}

/* Place the pool of B births in cell t (cell average), whose volumes and
 * carried loads are vol[.][t] and cvol[.][t]; returns the number placed. */
static double place_pool(const agg_t *A, const gs_grid *g, size_t t, double B, double *const *vol,
                         double *const *cvol, double sign, double *dydt, double *const *qdst, acc_t *acc) {
  if (B == 0.0) return 0.0;
  double vbar[GS_MAX_DIM], excess[GS_MAX_DIM] = {0}, qtot[GS_MAX_CARRIED];
  for (int k = 0; k < A->dim; k++) vbar[k] = vol[A->off + k][t] / B;
  for (int q = 0; q < A->nc; q++) qtot[q] = sign * cvol[q][t];
  gs_lever_place_carried(g, t, vbar, sign * B, dydt, excess, qdst ? A->nc : 0, qtot, qdst);
  /* excess carries the packet's sign already, and pass() books lost_v
   * times sign: unsigned here, like the pairs' losses (with the sign
   * twice, the dry pass of wet "either" had booked its clamped volume
   * with the wrong sign) */
  for (int k = 0; k < A->dim; k++) acc->lost_v[A->off + k] += sign * excess[k];
  return sign * B;
}

/* Redistribute pooled births (cell average) or copy fixed-pivot births into
 * dydt; returns the number placed.  Lost packets go to lost_n / lost_v. */
static double place_births(const agg_t *A, const gs_grid *g, acc_t *acc, double sign,
                           double *dydt, double *const *qdst) {
  double placed = 0;
  if (A->scheme == FIXED_PIVOT) {
    for (size_t c = acc->lo; c < acc->hi; c++) {
      dydt[c] += sign * acc->fp[c];
      placed += sign * acc->fp[c];
    }
    return placed;
  }
  for (size_t t = acc->lo; t < acc->hi; t++) {
    placed += place_pool(A, g, t, acc->births[t], acc->vol, acc->cvol, sign, dydt, qdst, acc);
    placed += place_pool(A, g, t, acc->nbirths[t], acc->nvol, acc->ncvol, sign, dydt, qdst, acc);
  }
  return placed;
}

/* Work of one evaluator: thread `slot` of a team that splits the
 * compartments, or -1 for the whole team on one compartment (slot 0). */
typedef struct {
  int slot, res;  /* res: the acc entry and work slot holding the results */
  double *pcar;   /* nc * ncells loads per particle */
  double *masked; /* ncells */
} evaluator;

static evaluator evaluator_for(const agg_t *A, int slot) {
  int res = slot < 0 ? 0 : slot;
  evaluator e = {slot, res, A->pcar + (size_t)res * A->pcar_len,
                 A->masked + (size_t)res * A->masked_len};
  return e;
}

/* Loads per particle of compartment comp's cells that take part (the only
 * ones the pairs read, and the losses where there are deaths): a large
 * grid's population sits in a band. */
static void carried_loads(const agg_t *A, const gs_model *m, const gs_eval *ev, size_t comp,
                          const double *y, double *pcar) {
  const size_t lo = A->cs[comp].prange[0], hi = A->cs[comp].prange[1];
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  for (int q = 0; q < A->nc; q++) {
    const double *Q = gs_eval_carried_c(m, ev, y, comp, q);
    double *p = pcar + (size_t)q * A->ncells;
    for (size_t c = lo; c < hi; c++) p[c] = N[c] > 0 ? Q[c] / N[c] : 0.0;
  }
}


/* Wetness psi of the cells of compartment comp: 0 below min_content, 1
 * above, linear across the relative width `ramp` around it (a step makes the
 * right-hand side jump whenever a cell crosses, which adaptive integrators
 * cannot step over).  Chosen once per time value under an integrator (like
 * the participating cells), so Newton iterations see one function. */
static const double *wet_cells(agg_t *A, const gs_model *m, const gs_eval *ev, size_t comp,
                               double t, const double *y) {
  double *psi = A->wet_ok + comp * A->wet_len;
  if (!isnan(A->cs[comp].wet_t) && ev->era == A->cs[comp].wet_era &&
      (ev->hold || (ev->in_integrator && t == A->cs[comp].wet_t)))
    return psi;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  const double lo = A->wet_min * (1 - 0.5 * A->wet_ramp), hi = A->wet_min * (1 + 0.5 * A->wet_ramp);
  const gs_grid *g = &m->grid;
  if (A->wet_axis >= 0) {
    /* liquid as a coordinate: the content of a cell's pivot, liquid over
     * the rest of the granule (its solid, and gas if an axis holds it) */
    for (size_t c = 0; c < A->ncells; c++) {
      const double l = g->x[c * (size_t)g->dim + (size_t)A->wet_axis], s = g->volume[c] - l;
      const double content = s > 0 ? l / s : 0.0;
      psi[c] = content >= hi ? 1.0 : content < lo ? 0.0 : (content - lo) / (hi - lo);
    }
  } else {
    const double *L = gs_eval_carried_c(m, ev, y, comp, A->wet_liquid);
    for (size_t c = 0; c < A->ncells; c++) {
      double content = N[c] > 0 ? L[c] / (N[c] * g->volume[c]) : 0.0;
      psi[c] = content >= hi ? 1.0 : content < lo ? 0.0 : (content - lo) / (hi - lo);
    }
  }
  A->cs[comp].wet_t = t;
  A->cs[comp].wet_era = ev->era;
  return psi;
}

/* One pass of pairs over the numbers Nv, its rates added with sign; choose:
 * choose the cells taking part from Nv and find their loads, else keep the
 * last pass's. */
static void pass(agg_t *A, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                 const double *y,
                 const double *Nv, double sign, int choose, double *dydt, double *dledger,
                 double *born, double *dead, acc_t *acc, const evaluator *wk) {
  if (choose) {
    choose_cells(A, comp, t, Nv, ev);
    carried_loads(A, m, ev, comp, y, wk->pcar);
  }
  compartment_pairs(A, comp, Nv, acc, wk->slot, wk->pcar);
  acc_t *r = &acc[wk->res];
  double *d = dydt ? gs_eval_numbers(m, ev, dydt, comp) : NULL;
  /* the cells outside [lo, hi) hold no deaths or births */
  const size_t lo = r->lo, hi = r->hi;
  if (d) {
    for (size_t c = lo; c < hi; c++) d[c] -= sign * r->death[c];
  } else { /* number_rates: the total only (in a register: through the pointer,
            * which may alias, every cell waited for the previous store) */
    double dead_sum = *dead;
    for (size_t c = lo; c < hi; c++) dead_sum += sign * r->death[c];
    *dead = dead_sum;
  }
  double *qdst[GS_MAX_CARRIED] = {NULL, NULL};
  for (int q = 0; d && q < A->nc; q++) {
    qdst[q] = gs_eval_carried(m, ev, dydt, comp, q);
    const double *p = wk->pcar + (size_t)q * A->ncells;
    /* cells without events lose no load; skipping them also keeps a load
     * that overflows (a stray denormal number) from making 0 x inf = NaN */
    for (size_t c = lo; c < hi; c++) /* a select, not a branch: it vectorises */
      qdst[q][c] -= r->death[c] != 0.0 ? sign * r->death[c] * p[c] : 0.0;
  }
  double *scratch = d ? d : r->row; /* number_rates: place into a scratch row */
  if (!d) memset(scratch, 0, A->ncells * sizeof(double));
  *born += place_births(A, &m->grid, r, sign, scratch, d ? qdst : NULL);
  if (dledger) {
    double *lost = gs_eval_ledger(m, ev, dledger, comp) + m->nvol;
    for (int k = 0; k < A->dim; k++) lost[k] += sign * r->lost_v[A->off + k];
    for (int q = 0; q < A->nc; q++) lost[A->dim + q] += sign * r->lost_c[q];
  }
}

/* Compartment comp's rates (dydt, dledger), or with dydt NULL its number
 * formation and depletion rates alone (birth, death).  slot < 0: this
 * compartment alone, its pair loop split over the OpenMP team; slot >= 0:
 * serial, in that slot's scratch. */
static void compartment_rates(agg_t *A, const gs_model *m, const gs_eval *ev, size_t comp,
                              double t, const double *y, double *dydt, double *dledger,
                              double *birth, double *death) {
  acc_t acc[A->nthreads > 0 ? A->nthreads : 1];
  const evaluator wk = evaluator_for(A, ev->slot);
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  double born = 0, dead = 0;
  if (A->fft) {
    double *lost = dledger ? gs_eval_ledger(m, ev, dledger, comp) + m->nvol : NULL;
    gs_agg_fft_rates(A->fft, comp, N, ev->slot, dydt ? gs_eval_numbers(m, ev, dydt, comp) : NULL, lost,
                     &born, &dead);
  } else if (A->wet == WET_OFF) {
    pass(A, m, ev, comp, t, y, N, 1.0, 1, dydt, dledger, &born, &dead, acc, &wk);
  } else {
    const double *psi = wet_cells(A, m, ev, comp, t, y);
    /* both: pair weight psi_a psi_b, so the numbers psi N; either:
     * 1 - (1 - psi_a)(1 - psi_b), all pairs minus those of (1 - psi) N */
    const int both = A->wet == WET_BOTH;
    for (size_t c = 0; c < A->ncells; c++) wk.masked[c] = (both ? psi[c] : 1.0 - psi[c]) * N[c];
    /* either: the dry pairs subtracted are among the cells of all pairs (a
     * dry cell negligible in the whole compartment takes part in neither) */
    if (!both) pass(A, m, ev, comp, t, y, N, 1.0, 1, dydt, dledger, &born, &dead, acc, &wk);
    pass(A, m, ev, comp, t, y, wk.masked, both ? 1.0 : -1.0, both, dydt, dledger, &born, &dead, acc, &wk);
  }
  if (birth) *birth = born;
  if (death) *death = dead;
}

static void agg_rhs(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                    const double *y, double *dydt, double *dledger) {
  compartment_rates(self, m, ev, comp, t, y, dydt, dledger, NULL, NULL);
}

/* The low-rank form's rank and error, which the tolerance chose */
static int agg_describe(void *self, char *msg, size_t n) {
  const agg_t *A = self;
  double e = 0;
  const int rank = A->fft ? gs_agg_fft_rank(A->fft, &e) : 0;
  if (!rank) return 0;
  char how[160];
  gs_agg_fft_rank_how(A->fft, how, sizeof how);
  snprintf(msg, n, "method fft with a low-rank kernel form of rank %d (achieved error %.2g of the kernel matrix, "
           "Frobenius; %s)", rank, e, how);
  return 1;
}

static void agg_number_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                             double t, const double *y, double *birth, double *death) {
  compartment_rates(self, m, ev, comp, t, y, NULL, NULL, birth, death);
}

const gs_mech_type gs_mech_aggregation = {
    .name = "aggregation",
    .summary = "binary aggregation with a kernel; cell-average or fixed-pivot redistribution",
    .create = agg_create,
    .rates = agg_rhs,
    .number_rates = agg_number_rates,
    .describe = agg_describe,
    .free = agg_free,
    .pages_per_compartment = 3, /* wet_ok, cs, span */
    .grid_bytes = agg_grid_bytes,
};
