/* Low-rank kernel form without the dense matrix: adaptive cross
 * approximation, recompression into symmetric terms, truncation on the
 * achieved error.
 *
 * Cross approximation (Bebendorf 2000; Bebendorf & Rjasanow 2003), partially
 * pivoted, on the symmetrised kernel matrix S = (B + B^T)/2: step k takes
 * the residual of row i_k, its largest entry j_k as pivot delta, the
 * residual of column j_k (= row j_k, S being symmetric), and adds
 * u_k v_k^T with u_k the column residual and v_k the row residual / delta;
 * the next row is the unused one where |u_k| is largest.  Only 2 k rows of
 * S are evaluated and the memory is U, V: 2 k n doubles.  S_k = U V^T lies
 * in the span of the columns S[:, I u J] of the pivots, so the
 * recompression -- thin QR [U V] = Q R (LAPACK dgeqrf/dorgqr) and the
 * eigenpairs of the small symmetric core (R_U R_V^T + R_V R_U^T)/2 (dsyevr)
 * -- gives S ~ C W C^T with C = S[:, I u J] as terms mu_t q_t q_t^T with
 * orthonormal q_t, in O(n k^2).  Symmetrising cannot add error:
 * ||S - sym(S_k)||_F <= ||S - S_k||_F.
 *
 * Stopping: the usual estimate ||u_k|| ||v_k|| <= eps ||S_k||_F (the new
 * term against the approximation so far, ||S_k||_F updated in O(n k)), with
 * eps = tol / GS_ACA_MARGIN and met on two steps in a row, since one small
 * term can be a lucky pivot.  The estimate is a heuristic, so the check
 * decides: the achieved error of every truncation q_1..q_r is measured
 * against the kernel's rows (all n^2 entries up to GS_LOWRANK_EXACT_MAX_CELLS
 * cells, O(n^2 k) flops and no O(n^3); above, GS_LOWRANK_SAMPLE_ROWS random
 * rows), and the fewest terms within tol are kept.  Where all terms together
 * miss tol / GS_ACA_MARGIN, the cross approximation goes on with eps / 10
 * (and twice the steps in a row) and is checked again; where it reaches
 * aca_terms_cap first, the dense eigendecomposition (lowrank_dense.c) takes
 * over on grids it can hold, else the form is refused. */
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "kernel/lowrank.h"

void dgeqrf_(const int *m, const int *n, double *a, const int *lda, double *tau, double *work, const int *lwork,
             int *info);
void dorgqr_(const int *m, const int *n, const int *k, double *a, const int *lda, const double *tau, double *work,
             const int *lwork, int *info);

/* the cross approximation is run to tol / GS_ACA_MARGIN, so that what it
 * misses takes ~1e-4 of the error budget (squared) and the truncation, not
 * the approximation, decides the rank as the dense decomposition's does */
#define GS_ACA_MARGIN 100.0

enum { BLOCK = 32 }; /* rows of S evaluated together by the error check */

/* rows of S through the kernel's rows; col: n x BLOCK scratch */
typedef struct {
  const gs_kernel *k;
  size_t comp, n;
  double *col;
} sym_t;

/* rows a0 .. a0 + m - 1 of S, columns c0 .. n - 1, into out (m x n; the
 * columns below c0 left alone), m <= BLOCK */
static int sym_rows(const sym_t *s, size_t a0, size_t m, size_t c0, double *out, gs_error *err) {
  const size_t n = s->n;
  for (size_t i = 0; i < m; i++) s->k->type->row(s->k->self, s->comp, a0 + i, c0, n, out + i * n + c0);
  for (size_t b = c0; b < n; b++) s->k->type->row(s->k->self, s->comp, b, a0, a0 + m, s->col + b * m);
  for (size_t i = 0; i < m; i++)
    for (size_t b = c0; b < n; b++) {
      const double v = 0.5 * (out[i * n + b] + s->col[b * m + i]);
      if (!isfinite(v))
        return gs_error_set(err, GS_ENUMERIC, "the kernel is not finite between cells %zu and %zu", a0 + i, b);
      out[i * n + b] = v;
    }
  return GS_OK;
}

typedef struct {
  size_t n;
  int k, cap;          /* terms, allocated */
  int max_terms;       /* the cap: aca_terms_cap */
  double *U, *V;       /* k x n each */
  double norm2;        /* ||S_k||_F^2 */
  double scale;        /* largest |S_ab| evaluated */
  unsigned char *used; /* rows taken as pivots */
  size_t nused, next;
  double *r, *c;       /* n each: residual row and column */
  gsl_rng *rng;
} aca_t;

static void aca_free(aca_t *A) {
  free(A->U);
  free(A->V);
  free(A->used);
  free(A->r);
  free(A->c);
  if (A->rng) gsl_rng_free(A->rng);
}

static double mib(size_t n, int terms) { return 6.0 * (double)n * terms * sizeof(double) / 1048576.0; }

static int aca_grow(aca_t *A, gs_error *err) {
  if (A->k < A->cap) return GS_OK;
  const int cap = A->cap ? 2 * A->cap : 16;
  double *U = realloc(A->U, (size_t)cap * A->n * sizeof(double));
  if (U) A->U = U;
  double *V = U ? realloc(A->V, (size_t)cap * A->n * sizeof(double)) : NULL;
  if (V) A->V = V;
  if (!U || !V)
    return gs_error_set(err, GS_ENOMEM, "out of memory for a low-rank kernel form: %zu cells x %d terms take ~%.0f MiB",
                        A->n, cap, mib(A->n, cap));
  A->cap = cap;
  return GS_OK;
}

/* The most cross terms on n cells.  Beyond n / GS_ACA_CELLS_PER_TERM the
 * recompression (QR and core of 2k columns, (2k)^2 n flops with reference
 * BLAS) costs more than the dense decomposition would (measured on 512
 * cells: 0.6-1.4 s for 250-310 terms against 0.25 s), and such a form has
 * no use in an FFT anyway (method auto wants rank <= cells / 64). */
#define GS_ACA_CELLS_PER_TERM 8
static int aca_terms_cap(size_t n) {
  size_t cap = n / GS_ACA_CELLS_PER_TERM;
  if (cap < 32) cap = 32;
  if (cap > n) cap = n;
  return cap > GS_LOWRANK_MAX_TERMS ? GS_LOWRANK_MAX_TERMS : (int)cap;
}

/* an unused row from a random start (fixed seed): where the last term
 * gives no guidance */
static size_t random_unused(aca_t *A) {
  size_t i = gsl_rng_uniform_int(A->rng, A->n);
  while (A->used[i]) i = (i + 1) % A->n;
  return i;
}

static double dot(const double *x, const double *y, size_t n) {
  double s = 0;
  for (size_t i = 0; i < n; i++) s += x[i] * y[i];
  return s;
}

/* Steps until the estimate holds on `hits` steps in a row, every row is a
 * pivot, or GS_LOWRANK_MAX_TERMS terms; *converged says which. */
static int aca_run(aca_t *A, const sym_t *s, double eps, int hits, int *converged, gs_error *err) {
  const size_t n = A->n;
  int met = 0, rc = GS_OK;
  *converged = 0;
  while (!rc && A->nused < n && A->k < A->max_terms) {
    const size_t i = A->next;
    if ((rc = sym_rows(s, i, 1, 0, A->r, err))) break;
    for (size_t b = 0; b < n; b++) A->scale = fmax(A->scale, fabs(A->r[b]));
    for (int l = 0; l < A->k; l++) {
      const double f = A->U[(size_t)l * n + i], *v = A->V + (size_t)l * n;
      for (size_t b = 0; b < n; b++) A->r[b] -= f * v[b];
    }
    A->used[i] = 1;
    A->nused++;
    size_t j = 0;
    for (size_t b = 1; b < n; b++)
      if (fabs(A->r[b]) > fabs(A->r[j])) j = b;
    const double delta = A->r[j];
    if (!(fabs(delta) > 1e-14 * A->scale)) { /* the row is represented to round-off: no term */
      if (++met >= hits) break;
      if (A->nused < n) A->next = random_unused(A);
      continue;
    }
    if ((rc = sym_rows(s, j, 1, 0, A->c, err)) || (rc = aca_grow(A, err))) break;
    for (int l = 0; l < A->k; l++) {
      const double f = A->V[(size_t)l * n + j], *u = A->U + (size_t)l * n;
      for (size_t b = 0; b < n; b++) A->c[b] -= f * u[b];
    }
    double *u = A->U + (size_t)A->k * n, *v = A->V + (size_t)A->k * n;
    for (size_t b = 0; b < n; b++) {
      u[b] = A->c[b];
      v[b] = A->r[b] / delta;
    }
    /* ||S_k||^2 = ||S_{k-1}||^2 + 2 sum_l (u.u_l)(v.v_l) + |u|^2 |v|^2 */
    const double uu = dot(u, u, n), vv = dot(v, v, n);
    double cross = 0;
    for (int l = 0; l < A->k; l++) cross += dot(u, A->U + (size_t)l * n, n) * dot(v, A->V + (size_t)l * n, n);
    A->norm2 = fmax(A->norm2 + 2 * cross + uu * vv, 0);
    A->k++;
    met = sqrt(uu * vv) <= eps * sqrt(A->norm2) ? met + 1 : 0;
    if (met >= hits) break;
    size_t next = SIZE_MAX;
    for (size_t b = 0; b < n; b++)
      if (!A->used[b] && u[b] != 0 && (next == SIZE_MAX || fabs(u[b]) > fabs(u[next]))) next = b;
    if (A->nused < n) A->next = next != SIZE_MAX ? next : random_unused(A);
  }
  *converged = met >= hits || A->nused == n;
  return rc;
}

/* S_k symmetrised as terms mu_t q_t q_t^T, |mu| decreasing, q orthonormal
 * (p x n): thin QR of [U V], eigenpairs of the p x p core. */
static int recompress(const aca_t *A, double **mu_out, double **q_out, int *p_out, gs_error *err) {
  const size_t n = A->n;
  const int k = A->k, m = 2 * k, nn = (int)n, p = nn < m ? nn : m;
  *mu_out = *q_out = NULL;
  *p_out = 0;
  if (k == 0) return GS_OK;
  double *C = gs_malloc((size_t)m * n * sizeof(double), err), *tau = gs_malloc((size_t)p * sizeof(double), err);
  double *R = gs_calloc((size_t)p * (size_t)m, sizeof(double), err);
  double *M = gs_malloc((size_t)p * (size_t)p * sizeof(double), err), *Z = gs_malloc((size_t)p * (size_t)p * sizeof(double), err);
  double *w = gs_malloc((size_t)p * sizeof(double), err), *q = gs_malloc((size_t)p * n * sizeof(double), err);
  int *order = gs_malloc((size_t)p * sizeof(int), err);
  double *work = NULL;
  int rc = C && tau && R && M && Z && w && q && order ? GS_OK : GS_ENOMEM, info = 0, lwork = -1;
  if (!rc) {
    memcpy(C, A->U, (size_t)k * n * sizeof(double)); /* column-major n x m: U's terms, then V's */
    memcpy(C + (size_t)k * n, A->V, (size_t)k * n * sizeof(double));
    double wq = 0;
    dgeqrf_(&nn, &m, C, &nn, tau, &wq, &lwork, &info);
    lwork = (int)wq;
    dorgqr_(&nn, &p, &p, C, &nn, tau, &wq, &(int){-1}, &info);
    lwork = (int)wq > lwork ? (int)wq : lwork;
    if (!(work = gs_malloc((size_t)lwork * sizeof(double), err))) rc = GS_ENOMEM;
  }
  if (!rc) {
    dgeqrf_(&nn, &m, C, &nn, tau, work, &lwork, &info);
    if (info) rc = gs_error_set(err, GS_ENUMERIC, "LAPACK dgeqrf failed (info %d) on %d cross terms", info, k);
  }
  if (!rc) {
    for (int j = 0; j < m; j++)
      for (int i = 0; i <= j && i < p; i++) R[i + (size_t)j * p] = C[i + (size_t)j * n];
    dorgqr_(&nn, &p, &p, C, &nn, tau, work, &lwork, &info);
    if (info) rc = gs_error_set(err, GS_ENUMERIC, "LAPACK dorgqr failed (info %d) on %d cross terms", info, k);
  }
  if (!rc) {
    /* core (R_U R_V^T + R_V R_U^T) / 2 */
    for (int a = 0; a < p; a++)
      for (int b = 0; b <= a; b++) {
        double s = 0;
        for (int l = 0; l < k; l++)
          s += R[a + (size_t)l * p] * R[b + (size_t)(k + l) * p] + R[a + (size_t)(k + l) * p] * R[b + (size_t)l * p];
        M[a + (size_t)b * p] = M[b + (size_t)a * p] = 0.5 * s;
      }
    rc = gs_lowrank_eigen(M, p, w, Z, err);
  }
  if (!rc) {
    gs_lowrank_order(w, (size_t)p, order);
    for (int t = 0; t < p; t++) {
      const double *z = Z + (size_t)order[t] * p;
      double *qt = q + (size_t)t * n;
      memset(qt, 0, n * sizeof(double));
      for (int i = 0; i < p; i++) {
        const double f = z[i], *Qi = C + (size_t)i * n;
        for (size_t c = 0; c < n; c++) qt[c] += f * Qi[c];
      }
      M[t] = w[order[t]]; /* M's first p entries: mu by |mu| */
    }
    memcpy(w, M, (size_t)p * sizeof(double));
    *mu_out = w;
    *q_out = q;
    *p_out = p;
    w = q = NULL;
  }
  free(C);
  free(tau);
  free(R);
  free(M);
  free(Z);
  free(w);
  free(q);
  free(order);
  free(work);
  return rc;
}

/* err2[r], r = 0..p: the squared Frobenius norm of S - sum_{t<r} mu_t q_t
 * q_t^T over the rows `rows` (NULL: all n rows, each residual symmetric, so
 * its upper triangle counted twice: half the kernel evaluations); blk:
 * BLOCK x n scratch.  With rows, var (2 (p + 1) + 1 doubles, or NULL) gets
 * the sums over the rows of e_r^2 and e_r s (e_r: the row's err2[r], s: its
 * err2[0]) and of s^2, for the standard error of the ratio (see below). */
static int residual_norms(const sym_t *s, const double *mu, const double *q, int p, const size_t *rows, size_t nrows,
                          double *blk, double *err2, double *var, gs_error *err) {
  const size_t n = s->n;
  memset(err2, 0, (size_t)(p + 1) * sizeof(double));
  if (var) memset(var, 0, (2 * (size_t)(p + 1) + 1) * sizeof(double));
  const size_t total = rows ? nrows : n;
  for (size_t i0 = 0; i0 < total;) {
    const size_t a0 = rows ? rows[i0] : i0, m = rows ? 1 : (total - i0 < BLOCK ? total - i0 : BLOCK);
    int rc = sym_rows(s, a0, m, rows ? 0 : a0, blk, err);
    if (rc) return rc;
    for (size_t i = 0; i < m; i++) {
      /* whole row: entries from 0, weight 1; upper triangle: the diagonal
       * apart (weight 1), the rest from a + 1 (weight 2) */
      const size_t a = a0 + i, b0 = rows ? 0 : a + 1;
      const double w = rows ? 1 : 2;
      double *res = blk + i * n, diag = rows ? 0 : res[a];
      const double s0 = w * dot(res + b0, res + b0, n - b0) + diag * diag;
      err2[0] += s0;
      if (var) {
        var[0] += s0 * s0;
        var[1] += s0 * s0;
        var[2 * (size_t)(p + 1)] += s0 * s0;
      }
      for (int t = 0; t < p; t++) {
        const double f = mu[t] * q[(size_t)t * n + a], *qt = q + (size_t)t * n;
        double e = 0;
        for (size_t b = b0; b < n; b++) {
          res[b] -= f * qt[b];
          e += res[b] * res[b];
        }
        diag -= f * qt[a];
        e = w * e + (rows ? 0 : diag * diag);
        err2[t + 1] += e;
        if (var) {
          var[2 * (size_t)(t + 1)] += e * e;
          var[2 * (size_t)(t + 1) + 1] += e * s0;
        }
      }
    }
    i0 += m;
  }
  return GS_OK;
}

/* The squared relative error of truncation r from sampled rows, raised by
 * three standard errors: the ratio R = sum e_r / sum s of m rows has
 * var(R) ~ sum (e_r - R s)^2 / (m (m - 1) mean(s)^2) (delta method), and
 * the spread measured between samples of 256 rows was 9-14 % of the
 * estimate, so the point estimate alone let a true error of 1.16 tol pass. */
static double sampled_bound(const double *err2, const double *var, int p, int r, size_t m) {
  if (!(err2[0] > 0)) return 0;
  const double R = err2[r] / err2[0], mean_s = err2[0] / (double)m;
  const double ss = fmax(0, var[2 * (size_t)r] - 2 * R * var[2 * (size_t)r + 1] + R * R * var[2 * (size_t)(p + 1)]);
  return R + 3 * sqrt(ss / ((double)m * (double)(m - 1))) / mean_s;
}

/* m distinct rows of n, uniformly at random, in increasing order */
static int sample_rows(gsl_rng *rng, size_t n, size_t m, size_t *rows, gs_error *err) {
  size_t *all = gs_malloc(n * sizeof(size_t), err);
  if (!all) return GS_ENOMEM;
  for (size_t i = 0; i < n; i++) all[i] = i;
  gsl_ran_choose(rng, rows, m, all, n, sizeof(size_t));
  free(all);
  return GS_OK;
}

int gs_kernel_lowrank_error(const gs_kernel *k, size_t ncells, size_t comp, const gs_kernel_lowrank *lr, int nrows,
                            unsigned long seed, double *rel_err, gs_error *err) {
  const size_t n = ncells, m = nrows > 0 && (size_t)nrows < n ? (size_t)nrows : 0;
  sym_t s = {k, comp, n, gs_malloc(n * BLOCK * sizeof(double), err)};
  double *blk = gs_malloc(n * BLOCK * sizeof(double), err);
  double *err2 = gs_malloc((size_t)(lr->rank + 1) * sizeof(double), err);
  size_t *rows = m ? gs_malloc(m * sizeof(size_t), err) : NULL;
  gsl_rng *rng = m ? gsl_rng_alloc(gsl_rng_mt19937) : NULL;
  int rc = s.col && blk && err2 && (!m || (rows && rng)) ? GS_OK : GS_ENOMEM;
  if (!rc && m) {
    gsl_rng_set(rng, seed);
    rc = sample_rows(rng, n, m, rows, err);
  }
  if (!rc) rc = residual_norms(&s, lr->lambda, lr->vec, lr->rank, rows, m, blk, err2, NULL, err);
  if (!rc) *rel_err = err2[0] > 0 ? sqrt(err2[lr->rank] / err2[0]) : 0;
  free(s.col);
  free(blk);
  free(err2);
  free(rows);
  if (rng) gsl_rng_free(rng);
  return rc;
}

int gs_kernel_lowrank_build(const gs_kernel *k, size_t ncells, size_t comp, double tol, gs_kernel_lowrank *out,
                            gs_error *err) {
  memset(out, 0, sizeof *out);
  const size_t n = ncells;
  const int sampled = n > GS_LOWRANK_EXACT_MAX_CELLS;
  sym_t s = {k, comp, n, gs_malloc(n * BLOCK * sizeof(double), err)};
  aca_t A = {.n = n, .max_terms = aca_terms_cap(n)};
  A.used = gs_calloc(n, 1, err);
  A.r = gs_malloc(n * sizeof(double), err);
  A.c = gs_malloc(n * sizeof(double), err);
  A.rng = gsl_rng_alloc(gsl_rng_mt19937);
  double *blk = gs_malloc(n * BLOCK * sizeof(double), err), *mu = NULL, *q = NULL, *err2 = NULL, *var = NULL;
  size_t *rows = sampled ? gs_malloc(GS_LOWRANK_SAMPLE_ROWS * sizeof(size_t), err) : NULL;
  int rc = s.col && A.used && A.r && A.c && A.rng && blk && (rows || !sampled) ? GS_OK : GS_ENOMEM;
  if (!rc) {
    gsl_rng_set(A.rng, 20001); /* fixed: the same form in every run */
    A.next = gsl_rng_uniform_int(A.rng, n);
    if (sampled) rc = sample_rows(A.rng, n, GS_LOWRANK_SAMPLE_ROWS, rows, err);
  }
  const double target = tol / GS_ACA_MARGIN;
  double eps = target;
  int found = -1, p = 0, converged = 0;
  for (int round = 0; !rc && found < 0; round++) {
    rc = aca_run(&A, &s, eps, 2 << round, &converged, err);
    if (!rc && !converged) break; /* the cap stopped it: the fallback or the refusal */
    free(mu);
    free(q);
    free(err2);
    free(var);
    mu = q = err2 = var = NULL;
    if (!rc) rc = recompress(&A, &mu, &q, &p, err);
    if (!rc && !(err2 = gs_malloc((size_t)(p + 1) * sizeof(double), err))) rc = GS_ENOMEM;
    if (!rc && sampled && !(var = gs_malloc((2 * (size_t)(p + 1) + 1) * sizeof(double), err))) rc = GS_ENOMEM;
    if (!rc) rc = residual_norms(&s, mu, q, p, rows, GS_LOWRANK_SAMPLE_ROWS, blk, err2, var, err);
    /* squared relative errors: measured, or sampled and raised by 3 standard errors */
#define REL2(r) (sampled ? sampled_bound(err2, var, p, (r), GS_LOWRANK_SAMPLE_ROWS) \
                         : err2[0] > 0 ? err2[(r)] / err2[0] : 0)
    for (int r = 0; !rc && r <= p && found < 0; r++)
      if (REL2(r) <= tol * tol) found = r;
    /* done when the cross approximation itself met its target (so that the
     * truncation decides the rank) or could go no further (the cap, or
     * every row a pivot: round-off decides) */
    const int tight = !rc && REL2(p) <= target * target;
#undef REL2
    if (rc || (found >= 0 && tight) || A.nused == n) break;
    found = -1;
    eps /= 10;
  }
  if (!rc && found >= 0) {
    out->rank = found;
    out->rel_err = err2[0] > 0 ? sqrt(err2[found] / err2[0]) : 0;
    out->sampled_rows = sampled ? GS_LOWRANK_SAMPLE_ROWS : 0;
    out->cross_terms = A.k;
    out->lambda = gs_malloc((size_t)(found ? found : 1) * sizeof(double), err);
    out->vec = gs_malloc((size_t)(found ? found : 1) * n * sizeof(double), err);
    if (!out->lambda || !out->vec) rc = GS_ENOMEM;
    if (!rc && found > 0) {
      memcpy(out->lambda, mu, (size_t)found * sizeof(double));
      memcpy(out->vec, q, (size_t)found * n * sizeof(double));
    }
  }
  const int terms = A.k;
  free(s.col);
  free(blk);
  free(rows);
  free(mu);
  free(q);
  free(err2);
  free(var);
  aca_free(&A);
  if (!rc && found < 0) {
    if (n <= GS_LOWRANK_DENSE_MAX_CELLS) { /* the fallback: the whole matrix */
      gs_kernel_lowrank_free(out);
      rc = gs_kernel_lowrank_build_dense(k, ncells, comp, tol, out, err);
      if (!rc) out->cross_terms = terms;
      return rc;
    }
    rc = gs_error_set(err, GS_EINPUT,
                      "a low-rank form of the kernel within rank_tolerance %g needs more than %d terms on %zu cells "
                      "(adaptive cross approximation did not converge; ~%.0f MiB at that rank, and each term costs "
                      "one transform); loosen rank_tolerance or use method: pairs",
                      tol, GS_LOWRANK_MAX_TERMS, n, mib(n, GS_LOWRANK_MAX_TERMS));
  }
  if (rc) gs_kernel_lowrank_free(out);
  return rc;
}
