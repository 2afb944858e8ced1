/* Fixed-pivot aggregation on uniform grids in O(n log n) per axis.
 *
 * On a grid whose pivots are p_i = p_0 + i h along every axis, the sum of
 * the pivots of cells i and j depends on i + j alone, so the births of the
 * fixed-pivot scheme (Kumar & Ramkrishna 1996) are a discrete convolution
 * followed by a redistribution that depends only on the index sum k = i + j.
 * For a kernel that is a sum of separable terms,
 *   beta(a, b) = coef sum_t c_t phi_m1(a) phi_m2(b),
 * the births at index sum k are
 *   B_k = coef/2 sum_t sum_{i+j=k} (phi_m1 N)_i (phi_m2 N)_j,
 * one convolution per term, computed with FFTs of the zero-padded arrays
 * (FFTW), and the deaths are N_a coef sum_t c_t phi_m1(a) M_m2 with the
 * moments M_m = sum_b phi_m(b) N_b (the approach of Hackbusch 2006 and
 * Le Borne & Shahmuradyan 2014 for the sectional form).  The constant, sum
 * and product kernels are exact in this form (rank 1, 2, 1).
 *
 * Each k is then placed like the pair scheme places a pair's product: by
 * the lever rule on the two pivots around p_i + p_j, clamped to the last
 * pivot (excess volume to the ledger) inside the last cell, lost beyond
 * the last edge (its volume to the ledger), so number and volume are
 * conserved up to the FFT's round-off (about 1e-16 of the largest birth
 * rate in every cell of the index sums of the occupied cells' box).
 *
 * Pivots not equally spaced on some axis take the same separable form into
 * the near/far split of aggregation_split.c instead of the convolution;
 * kernels with their own separable terms (kernel.h, `terms`) need no
 * low-rank decomposition. */
#include <fftw3.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "kernel/lowrank.h"
#include "kernel/size_measure.h"
#include "pbm/aggregation_fft.h"
#include "pbm/aggregation_split.h"

enum { PLACED = 0, CLAMPED = 1, OUTSIDE = 2 };

/* where the products of index sum k land along one (padded) axis */
typedef struct {
  size_t *lo;          /* lower node times the axis stride */
  double *w;           /* weight of the upper node */
  double *sum;         /* the pivot sum */
  double *excess;      /* clamped: sum minus the last pivot */
  unsigned char *state;
} axis_map;

typedef struct {
  double c;
  int m1, m2;
} term;

typedef struct {
  double *real;         /* nreal: padded input, then the births */
  fftw_complex **spec;  /* nspec, ncplx each: transforms of phi_m N */
  int nspec;
  fftw_complex *acc;    /* ncplx: sum of the terms' products */
  double *mom;          /* the moments sum_c phi_m(c) N_c, one per phi */
  double *x;            /* split: nphi x ncells, phi_m N */
  const double **xp;    /* split: nphi pointers into x */
} slot_t;

/* The separable form of the kernel in a set of compartments: terms
 * c_t phi_m1(a) phi_m2(b) */
typedef struct {
  int nphi, nterm;
  double *phi;             /* nphi x ncells */
  term *t;
  double rel_err;          /* low rank: achieved Frobenius error (kernel/lowrank.h) */
  int sampled_rows, cross_terms, dense; /* low rank: how it was built (kernel/lowrank.h) */
} form_set;

struct gs_agg_fft {
  int dim, off;            /* real axes at padded positions off..2 */
  size_t n[3], M[3], stride[3], ncells, nreal, ncplx;
  const double *coef;      /* per compartment, owned by the kernel or own_coef */
  double *own_coef;        /* low rank: ones (beta0 is inside the terms) */
  int lowrank;             /* terms of the truncated eigendecomposition */
  int nset;                /* one form, or one per compartment */
  form_set *set;
  axis_map map[3];         /* 2 n[q] - 1 entries each */
  fftw_plan fwd, inv;
  gs_agg_split *split;     /* pivots not equally spaced: the near/far split instead of the FFT */
  int nslots;
  slot_t *slot;
};

/* Pivots equally spaced to within round-off: the pair scheme's lever
 * weights are then those of the index sums to about 1e-12. */
static int axis_uniform(const gs_axis *ax) {
  if (ax->n < 2) return 1;
  const double p0 = ax->pivots[0], h = (ax->pivots[ax->n - 1] - p0) / (double)(ax->n - 1);
  const double tol = 1e-13 * (fabs(p0) + fabs(ax->pivots[ax->n - 1]));
  for (size_t i = 0; i < ax->n; i++)
    if (fabs(ax->pivots[i] - (p0 + (double)i * h)) > tol) return 0;
  return 1;
}

/* The kernel's own exact separable form (constant, sum, product) */
static int exact_form(const gs_kernel *k) {
  gs_kernel_form f;
  if (!k->type->form) return 0;
  k->type->form(k->self, &f);
  return f.exact;
}

static int grid_uniform(const gs_grid *g) {
  for (int q = 0; q < g->dim; q++)
    if (!axis_uniform(&g->axis[q])) return 0;
  return 1;
}

/* The kernel's separable terms over ncells cells (kernel.h): their count,
 * 0 if it has none, -1 if out of memory. */
static int kernel_terms(const gs_kernel *k, size_t ncells, gs_kernel_terms *t) {
  return k->type->terms ? k->type->terms(k->self, ncells, t) : 0;
}

const char *gs_agg_fft_unusable(const gs_grid *g, const gs_kernel *k, double rank_tolerance) {
  if (exact_form(k)) return NULL;
  gs_kernel_terms kt;
  const int nt = kernel_terms(k, g->ncells, &kt);
  if (nt > 0) free(kt.phi);
  if (nt != 0) return NULL; /* out of memory (< 0) shows at create */
  if (!(rank_tolerance > 0))
    return "needs a kernel of separable form (constant, sum or product) or rank_tolerance for a low-rank form";
  /* any number of cells: the cross approximation holds cells x rank; a form
   * of more than GS_LOWRANK_MAX_TERMS terms is refused at create, naming
   * the cells and the memory */
  return NULL;
}

int gs_agg_fft_rank(const gs_agg_fft *F, double *rel_err) {
  int rank = 0;
  double e = 0;
  for (int s = 0; s < F->nset; s++) {
    if (F->set[s].nterm > rank) rank = F->set[s].nterm;
    e = fmax(e, F->set[s].rel_err);
  }
  if (rel_err) *rel_err = e;
  return F->lowrank ? rank : 0;
}

double gs_agg_fft_split_work(const gs_agg_fft *F) {
  if (!F->split) return 0;
  int terms = 0;
  for (int s = 0; s < F->nset; s++) terms = F->set[s].nterm > terms ? F->set[s].nterm : terms;
  return gs_agg_split_tuples(F->split) * terms;
}

void gs_agg_fft_rank_how(const gs_agg_fft *F, char *msg, size_t n) {
  int sampled = 0, terms = 0, dense = 0;
  for (int s = 0; F->lowrank && s < F->nset; s++) {
    sampled = sampled > F->set[s].sampled_rows ? sampled : F->set[s].sampled_rows;
    terms = terms > F->set[s].cross_terms ? terms : F->set[s].cross_terms;
    dense |= F->set[s].dense;
  }
  if (!F->lowrank || n == 0) {
    if (n) msg[0] = 0;
    return;
  }
  char where[96];
  if (sampled) snprintf(where, sizeof where, "error estimated from %d random rows", sampled);
  else snprintf(where, sizeof where, "error over all entries");
  if (dense)
    snprintf(msg, n, "dense eigendecomposition (the cross approximation did not converge in %d terms); %s", terms,
             where);
  else
    snprintf(msg, n, "adaptive cross approximation of %d terms; %s", terms, where);
}

void gs_agg_fft_free(gs_agg_fft *F) {
  if (!F) return;
  for (int s = 0; F->slot && s < F->nslots; s++) {
    fftw_free(F->slot[s].real);
    for (int m = 0; F->slot[s].spec && m < F->slot[s].nspec; m++) fftw_free(F->slot[s].spec[m]);
    free(F->slot[s].spec);
    fftw_free(F->slot[s].acc);
    free(F->slot[s].mom);
    free(F->slot[s].x);
    free(F->slot[s].xp);
  }
  gs_agg_split_free(F->split);
  free(F->slot);
  if (F->fwd) fftw_destroy_plan(F->fwd);
  if (F->inv) fftw_destroy_plan(F->inv);
  for (int q = 0; q < 3; q++) {
    free(F->map[q].lo);
    free(F->map[q].w);
    free(F->map[q].sum);
    free(F->map[q].excess);
    free(F->map[q].state);
  }
  for (int s = 0; F->set && s < F->nset; s++) {
    free(F->set[s].phi);
    free(F->set[s].t);
  }
  free(F->set);
  free(F->own_coef);
  free(F);
}

/* The same rules as the pair scheme's (aggregation.c, build_axis_maps),
 * applied to one pair of each index sum. */
static int build_map(gs_agg_fft *F, const gs_grid *g, int q, gs_error *err) {
  const size_t n = F->n[q], K = 2 * n - 1;
  axis_map *mp = &F->map[q];
  mp->lo = gs_calloc(K, sizeof(size_t), err);
  mp->w = gs_calloc(K, sizeof(double), err);
  mp->sum = gs_calloc(K, sizeof(double), err);
  mp->excess = gs_calloc(K, sizeof(double), err);
  mp->state = gs_calloc(K, 1, err);
  if (!mp->lo || !mp->w || !mp->sum || !mp->excess || !mp->state) return GS_ENOMEM;
  if (q < F->off) return GS_OK; /* padding axis: one cell onto itself */
  const gs_axis *ax = &g->axis[q - F->off];
  for (size_t k = 0; k < K; k++) {
    size_t i = k < n ? k : n - 1, j = k - i;
    double s = ax->pivots[i] + ax->pivots[j];
    mp->sum[k] = s;
    size_t lo;
    double w;
    if (gs_axis_lever(ax, s, &lo, &w) == 0) {
      mp->lo[k] = lo * F->stride[q];
      mp->w[k] = w;
    } else if (gs_axis_locate_snapped(ax, s) != GS_NOWHERE) {
      mp->lo[k] = (n - 1) * F->stride[q];
      mp->excess[k] = s - ax->pivots[n - 1];
      mp->state[k] = CLAMPED;
    } else {
      mp->state[k] = OUTSIDE;
    }
  }
  return GS_OK;
}

/* phi and the terms of the kernel's own separable form */
static int build_exact(gs_agg_fft *F, const gs_grid *g, const gs_kernel *k, gs_error *err) {
  gs_kernel_form f;
  k->type->form(k->self, &f);
  F->coef = f.coef;
  form_set *S = &F->set[0];
  S->nphi = f.kind == GS_KERNEL_FORM_SUM ? 2 : 1;
  S->nterm = f.kind == GS_KERNEL_FORM_SUM ? 2 : 1;
  S->phi = gs_malloc((size_t)S->nphi * F->ncells * sizeof(double), err);
  S->t = gs_malloc((size_t)S->nterm * sizeof(term), err);
  if (!S->phi || !S->t) return GS_ENOMEM;
  for (size_t c = 0; c < F->ncells; c++) {
    double u = gs_size_of(f.axes, g->dim, g->x + c * (size_t)g->dim);
    if (f.kind == GS_KERNEL_FORM_CONSTANT) {
      S->phi[c] = 1.0;
    } else if (f.kind == GS_KERNEL_FORM_PRODUCT) {
      S->phi[c] = u;
    } else {
      S->phi[c] = 1.0;
      S->phi[F->ncells + c] = u;
    }
  }
  if (f.kind == GS_KERNEL_FORM_SUM) { /* u(a) + u(b) */
    S->t[0] = (term){1.0, 1, 0};
    S->t[1] = (term){1.0, 0, 1};
  } else {
    S->t[0] = (term){1.0, 0, 0};
  }
  return GS_OK;
}

/* The kernel's own separable terms (taken over) */
static int build_terms(gs_agg_fft *F, gs_kernel_terms *kt, gs_error *err) {
  form_set *S = &F->set[0];
  F->coef = kt->coef;
  S->nphi = kt->nphi;
  S->nterm = kt->nterm;
  S->phi = kt->phi;
  if (!(S->t = gs_malloc((size_t)kt->nterm * sizeof(term), err))) return GS_ENOMEM;
  for (int t = 0; t < kt->nterm; t++) S->t[t] = (term){kt->c[t], kt->m1[t], kt->m2[t]};
  return GS_OK;
}

/* The low-rank form of the kernel matrix (kernel/lowrank.c: cross
 * approximation, recompressed and truncated) per set of compartments:
 * terms lambda_r v_r(a) v_r(b), beta0 inside. */
static int build_lowrank(gs_agg_fft *F, const gs_grid *g, const gs_kernel *k, double tol,
                         gs_error *err) {
  if (!(F->own_coef = gs_malloc(g->ncomp * sizeof(double), err))) return GS_ENOMEM;
  for (size_t z = 0; z < g->ncomp; z++) F->own_coef[z] = 1.0;
  F->coef = F->own_coef;
  for (int s = 0; s < F->nset; s++) {
    gs_kernel_lowrank lr;
    int rc = gs_kernel_lowrank_build(k, F->ncells, (size_t)s, tol, &lr, err);
    if (rc) return rc;
    form_set *S = &F->set[s];
    S->nphi = S->nterm = lr.rank;
    S->rel_err = lr.rel_err;
    S->sampled_rows = lr.sampled_rows;
    S->cross_terms = lr.cross_terms;
    S->dense = lr.dense;
    S->phi = lr.vec; /* taken over */
    S->t = gs_malloc((size_t)(lr.rank ? lr.rank : 1) * sizeof(term), err);
    for (int r = 0; S->t && r < lr.rank; r++) S->t[r] = (term){lr.lambda[r], r, r};
    free(lr.lambda);
    if (!S->t) return GS_ENOMEM;
  }
  return GS_OK;
}

int gs_agg_fft_create(const gs_grid *g, const gs_kernel *k, double rank_tolerance, int nslots,
                      gs_agg_fft **out, gs_error *err) {
  const char *why = gs_agg_fft_unusable(g, k, rank_tolerance);
  if (why) return gs_error_set(err, GS_EINPUT, "aggregation method fft %s", why);
  gs_agg_fft *F = gs_calloc(1, sizeof *F, err);
  if (!F) return GS_ENOMEM;
  F->dim = g->dim;
  F->off = 3 - g->dim;
  F->ncells = g->ncells;
  F->nreal = 1;
  F->ncplx = 1;
  int dims[3];
  for (int q = 0; q < 3; q++) {
    int a = q - F->off;
    F->n[q] = a >= 0 ? g->axis[a].n : 1;
    F->stride[q] = a >= 0 ? g->stride[a] : 0;
    /* 2n: the linear convolution (2n - 1 entries) without wrap-around */
    F->M[q] = a >= 0 ? 2 * F->n[q] : 1;
    F->nreal *= F->M[q];
    if (a >= 0) {
      dims[a] = (int)F->M[q];
      F->ncplx *= q == 2 ? F->M[q] / 2 + 1 : F->M[q];
    }
  }
  gs_kernel_terms kt;
  const int nt = kernel_terms(k, g->ncells, &kt);
  F->lowrank = !exact_form(k) && nt == 0;
  F->nset = F->lowrank && k->type->per_compartment && k->type->per_compartment(k->self) ? (int)g->ncomp : 1;
  int rc = (F->set = gs_calloc((size_t)F->nset, sizeof(form_set), err)) ? GS_OK : GS_ENOMEM;
  if (nt < 0) rc = gs_error_set(err, GS_ENOMEM, "out of memory for the kernel's separable terms");
  else if (!rc) rc = F->lowrank ? build_lowrank(F, g, k, rank_tolerance, err)
                     : exact_form(k) ? build_exact(F, g, k, err)
                                     : build_terms(F, &kt, err);
  else if (nt > 0) free(kt.phi);
  const int split = !grid_uniform(g);
  int maxphi = 0;
  for (int s = 0; !rc && s < F->nset; s++) maxphi = F->set[s].nphi > maxphi ? F->set[s].nphi : maxphi;
  if (!rc && split) rc = gs_agg_split_create(g, nslots, maxphi, &F->split, err);
  for (int q = 0; !rc && !split && q < 3; q++) rc = build_map(F, g, q, err);
  F->nslots = nslots > 0 ? nslots : 1;
  if (!rc && !(F->slot = gs_calloc((size_t)F->nslots, sizeof(slot_t), err))) rc = GS_ENOMEM;
  for (int s = 0; !rc && s < F->nslots; s++) {
    slot_t *S = &F->slot[s];
    S->mom = malloc((size_t)(maxphi > 0 ? maxphi : 1) * sizeof(double));
    if (split) {
      S->x = malloc((size_t)maxphi * F->ncells * sizeof(double));
      S->xp = malloc((size_t)maxphi * sizeof(double *));
      if (!S->mom || !S->x || !S->xp) rc = gs_error_set(err, GS_ENOMEM, "out of memory for aggregation's scratch");
      continue;
    }
    S->real = fftw_malloc(F->nreal * sizeof(double));
    /* the lowrank terms take one transform at a time, the others one per phi */
    S->nspec = F->lowrank || maxphi < 2 ? 2 : maxphi;
    S->spec = calloc((size_t)S->nspec, sizeof(fftw_complex *));
    for (int m = 0; S->spec && m < S->nspec; m++)
      if (!(S->spec[m] = fftw_malloc(F->ncplx * sizeof(fftw_complex)))) rc = GS_ENOMEM;
    S->acc = fftw_malloc(F->ncplx * sizeof(fftw_complex));
    if (rc || !S->mom || !S->real || !S->spec || !S->acc)
      rc = gs_error_set(err, GS_ENOMEM, "out of memory for the FFT arrays of aggregation");
  }
  if (!rc && !split) {
    /* FFTW_ESTIMATE leaves the arrays alone; every slot's arrays come from
     * fftw_malloc (same alignment), so the plans serve them all through the
     * new-array execute functions, which are thread safe */
    F->fwd = fftw_plan_dft_r2c(F->dim, dims, F->slot[0].real, F->slot[0].spec[0], FFTW_ESTIMATE);
    F->inv = fftw_plan_dft_c2r(F->dim, dims, F->slot[0].acc, F->slot[0].real, FFTW_ESTIMATE);
    if (!F->fwd || !F->inv) rc = gs_error_set(err, GS_ENOMEM, "FFTW could not plan the aggregation transforms");
  }
  if (rc) {
    gs_agg_fft_free(F);
    return rc;
  }
  *out = F;
  return GS_OK;
}

/* Place the births of the convolution (real, padded layout) on the grid:
 * the index sums in [klo, khi] per axis, twice the box of the occupied cells
 * (outside it the convolution is exactly zero and the FFT's values are
 * round-off, which would give cells no pair reaches births of either sign). */
static void place(const gs_agg_fft *F, const double *B, const size_t *klo, const size_t *khi,
                  double *dN, double *lost, double *born) {
  const axis_map *m0 = &F->map[0], *m1 = &F->map[1], *m2 = &F->map[2];
  const size_t s0 = F->stride[0], s1 = F->stride[1], s2 = F->stride[2];
  double placed = 0, lv[3] = {0, 0, 0};
  for (size_t k0 = klo[0]; k0 <= khi[0]; k0++)
    for (size_t k1 = klo[1]; k1 <= khi[1]; k1++) {
      const double *row = B + (k0 * F->M[1] + k1) * F->M[2];
      const int out01 = m0->state[k0] == OUTSIDE || m1->state[k1] == OUTSIDE;
      const double w0 = m0->w[k0], w1 = m1->w[k1];
      const double f0[2] = {1 - w0, w0}, f1[2] = {1 - w1, w1};
      for (size_t k2 = klo[2]; k2 <= khi[2]; k2++) {
        const double b = row[k2];
        if (out01 || m2->state[k2] == OUTSIDE) { /* the product lies beyond the grid */
          lv[0] += b * m0->sum[k0];
          lv[1] += b * m1->sum[k1];
          lv[2] += b * m2->sum[k2];
          continue;
        }
        placed += b;
        lv[0] += b * m0->excess[k0];
        lv[1] += b * m1->excess[k1];
        lv[2] += b * m2->excess[k2];
        if (!dN) continue;
        const double w2 = m2->w[k2], f2[2] = {1 - w2, w2};
        const size_t lo = m0->lo[k0] + m1->lo[k1] + m2->lo[k2];
        for (int u0 = 0; u0 < 2; u0++)
          for (int u1 = 0; u1 < 2; u1++)
            for (int u2 = 0; u2 < 2; u2++) {
              const double f = b * f0[u0] * f1[u1] * f2[u2];
              if (f != 0.0) dN[lo + (size_t)u0 * s0 + (size_t)u1 * s1 + (size_t)u2 * s2] += f;
            }
      }
    }
  *born += placed;
  for (int k = 0; lost && k < F->dim; k++) lost[k] += lv[F->off + k];
}

/* phi N into the low corner of the padded array, transformed into spec;
 * returns the moment sum_c phi(c) N_c */
static double transform(const gs_agg_fft *F, slot_t *S, const double *phi, const double *N,
                        fftw_complex *spec) {
  double mom = 0;
  for (size_t c = 0; c < F->ncells; c++) mom += phi[c] * N[c];
  memset(S->real, 0, F->nreal * sizeof(double));
  for (size_t i0 = 0; i0 < F->n[0]; i0++)
    for (size_t i1 = 0; i1 < F->n[1]; i1++) {
      const size_t c = i0 * F->n[1] * F->n[2] + i1 * F->n[2];
      double *dst = S->real + (i0 * F->M[1] + i1) * F->M[2];
      for (size_t i2 = 0; i2 < F->n[2]; i2++) dst[i2] = phi[c + i2] * N[c + i2];
    }
  fftw_execute_dft_r2c(F->fwd, S->real, spec);
  return mom;
}

/* Deaths of compartment comp's numbers N from the moments of the form set
 * fs (mom, filled by the caller); the box of the occupied cells per padded
 * axis into klo, khi (klo[0] = SIZE_MAX: no particles). */
static double deaths(const gs_agg_fft *F, const form_set *fs, double coef, const double *mom,
                     const double *N, double *dN, size_t *klo, size_t *khi) {
  double removed = 0;
  for (int q = 0; q < 3; q++) {
    klo[q] = SIZE_MAX;
    khi[q] = 0;
  }
  for (size_t c = 0; c < F->ncells; c++) {
    if (N[c] == 0.0) continue;
    const size_t idx[3] = {c / (F->n[1] * F->n[2]), c / F->n[2] % F->n[1], c % F->n[2]};
    for (int q = 0; q < 3; q++) {
      if (2 * idx[q] < klo[q]) klo[q] = 2 * idx[q];
      if (2 * idx[q] > khi[q]) khi[q] = 2 * idx[q];
    }
    double r = 0;
    for (int t = 0; t < fs->nterm; t++) r += fs->t[t].c * fs->phi[(size_t)fs->t[t].m1 * F->ncells + c] * mom[fs->t[t].m2];
    r *= coef * N[c];
    removed += r;
    if (dN) dN[c] -= r;
  }
  return removed;
}

/* Non-uniform pivots: the births by the near/far split
 * (aggregation_split.c), terms (m1, m2) and (m2, m1) merged (the placement
 * of a pair does not depend on its order), the deaths from the moments. */
static void split_rates(gs_agg_fft *F, const form_set *fs, double coef, const double *N, int slot,
                        double *dN, double *lost, double *born, double *dead) {
  slot_t *S = &F->slot[slot > 0 ? slot : 0];
  for (int m = 0; m < fs->nphi; m++) {
    const double *phi = fs->phi + (size_t)m * F->ncells;
    double *x = S->x + (size_t)m * F->ncells, mom = 0;
    for (size_t c = 0; c < F->ncells; c++) {
      x[c] = phi[c] * N[c];
      mom += x[c];
    }
    S->mom[m] = mom;
    S->xp[m] = x;
  }
  size_t klo[3], khi[3];
  *dead += deaths(F, fs, coef, S->mom, N, dN, klo, khi);
  int m1[GS_SPLIT_MAX_TERMS], m2[GS_SPLIT_MAX_TERMS], n = 0;
  double sc[GS_SPLIT_MAX_TERMS];
  for (int t = 0; t < fs->nterm; t++) {
    const term *T = &fs->t[t];
    int k = 0;
    while (k < n && !((m1[k] == T->m1 && m2[k] == T->m2) || (m1[k] == T->m2 && m2[k] == T->m1))) k++;
    if (k == n) {
      m1[n] = T->m1;
      m2[n] = T->m2;
      sc[n++] = 0;
    }
    sc[k] += 0.5 * coef * T->c;
    if (n == GS_SPLIT_MAX_TERMS || t == fs->nterm - 1) { /* a batch */
      gs_agg_split_births(F->split, slot, fs->nphi, S->xp, n, m1, m2, sc, dN, lost, born);
      n = 0;
    }
  }
}

void gs_agg_fft_rates(gs_agg_fft *F, size_t comp, const double *N, int slot, double *dN,
                      double *lost, double *born, double *dead) {
  slot_t *S = &F->slot[slot > 0 ? slot : 0];
  const form_set *fs = &F->set[F->nset > 1 ? comp : 0];
  const double coef = F->coef[comp];
  /* coef/2 sum_t c_t conv(phi_m1 N, phi_m2 N); FFTW's inverse is unscaled */
  const double scale = 0.5 * coef / (double)F->nreal;
  double *mom = S->mom;
  if (F->split) {
    split_rates(F, fs, coef, N, slot, dN, lost, born, dead);
    return;
  }
  if (!F->lowrank) {
    for (int m = 0; m < fs->nphi; m++) mom[m] = transform(F, S, fs->phi + (size_t)m * F->ncells, N, S->spec[m]);
    for (size_t i = 0; i < F->ncplx; i++) {
      double re = 0, im = 0;
      for (int t = 0; t < fs->nterm; t++) {
        const double *a = S->spec[fs->t[t].m1][i], *b = S->spec[fs->t[t].m2][i];
        re += fs->t[t].c * (a[0] * b[0] - a[1] * b[1]);
        im += fs->t[t].c * (a[0] * b[1] + a[1] * b[0]);
      }
      S->acc[i][0] = scale * re;
      S->acc[i][1] = scale * im;
    }
  } else { /* terms lambda_r v_r(a) v_r(b): one transform each, squared */
    memset(S->acc, 0, F->ncplx * sizeof(fftw_complex));
    for (int r = 0; r < fs->nterm; r++) {
      mom[r] = transform(F, S, fs->phi + (size_t)r * F->ncells, N, S->spec[0]);
      const double c = scale * fs->t[r].c;
      for (size_t i = 0; i < F->ncplx; i++) {
        const double *a = S->spec[0][i];
        S->acc[i][0] += c * (a[0] * a[0] - a[1] * a[1]);
        S->acc[i][1] += c * (2 * a[0] * a[1]);
      }
    }
  }
  fftw_execute_dft_c2r(F->inv, S->acc, S->real);
  size_t klo[3], khi[3];
  *dead += deaths(F, fs, coef, mom, N, dN, klo, khi);
  if (klo[0] != SIZE_MAX) place(F, S->real, klo, khi, dN, lost, born); /* else no particles */
}
