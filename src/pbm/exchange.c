/* Exchange between compartments along any directed graph (circulation
 * between spray, bulk and impeller zones, Chaudhury 2015 ch. 5), where
 * `transfer` only flows in series.
 *   rates: an n x n matrix, K[i][j] the rate [1/s] at which compartment i's
 *          particles move to j (diagonal 0), as `gransim compartments`
 *          writes it; or
 *   links: a list of {from, to, rate | residence_time}, the sparse form;
 *   file:  the fragment `gransim compartments` writes (its `rates`);
 *   discharge: optional rate [1/s] per compartment at which particles leave
 *          the system as product.
 * dN_i/dt = -(sum_j K_ij + d_i) N_i + sum_j K_ji N_j, the same for carried
 * totals.  Every volume moved is booked as leaving its source and entering
 * its destination in the ledgers, so the balance held = initial + exchanged
 * holds per compartment and the exchange conserves the total to round-off.
 * It reads every compartment's state (gs_mech_type.couples_all). */
#include <math.h>
#include <stdlib.h>

#include "gransim/pbm.h"
#include "pbm/sums.h"

typedef struct {
  size_t ncomp;
  double *out;    /* ncomp: total rate out of each compartment (links + discharge) */
  size_t *first;  /* ncomp + 1: compartment i's incoming links are [first[i], first[i+1]) */
  size_t *source; /* incoming link's source compartment */
  double *k;      /* incoming link's rate [1/s] */
} exchange_t;

static void exchange_free(void *self) {
  exchange_t *X = self;
  if (X) {
    free(X->out);
    free(X->first);
    free(X->source);
    free(X->k);
  }
  free(X);
}

/* The rates K (ncomp x ncomp, row = from) of a `rates` matrix. */
static int read_matrix(gs_cfg_node *mat, size_t ncomp, double *K, gs_error *err) {
  if (gs_cfg_require_kind(mat, GS_CFG_SEQ, err)) return GS_EINPUT;
  if (gs_cfg_size(mat) != ncomp)
    return gs_cfg_fail(mat, err, "expected %zu rows (one per compartment), got %zu", ncomp,
                       gs_cfg_size(mat));
  for (size_t i = 0; i < ncomp; i++) {
    gs_cfg_node *row = gs_cfg_item(mat, i);
    if (gs_cfg_require_kind(row, GS_CFG_SEQ, err)) return GS_EINPUT;
    if (gs_cfg_size(row) != ncomp)
      return gs_cfg_fail(row, err, "expected %zu rates (one per compartment), got %zu", ncomp,
                         gs_cfg_size(row));
    for (size_t j = 0; j < ncomp; j++) {
      gs_cfg_node *e = gs_cfg_item(row, j);
      double v;
      if (gs_cfg_node_double(e, &v, err)) return GS_EINPUT;
      if (!(v >= 0 && v < HUGE_VAL))
        return gs_cfg_fail(e, err, "a rate [1/s] must be finite and >= 0, got %g", v);
      if (i == j && v != 0)
        return gs_cfg_fail(e, err, "the diagonal (from compartment %zu to itself) must be 0", i + 1);
      K[i * ncomp + j] = v;
    }
  }
  return GS_OK;
}

/* The rates K of a `links` list. */
static int read_links(gs_cfg_node *links, size_t ncomp, double *K, gs_error *err) {
  if (gs_cfg_require_kind(links, GS_CFG_SEQ, err)) return GS_EINPUT;
  for (size_t l = 0; l < gs_cfg_size(links); l++) {
    gs_cfg_node *e = gs_cfg_item(links, l);
    if (gs_cfg_require_kind(e, GS_CFG_MAP, err)) return GS_EINPUT;
    long from = 0, to = 0;
    double v = 0;
    int rc = gs_cfg_long_range(e, "from", 1, 1, 1, (long)ncomp, &from, err);
    if (!rc) rc = gs_cfg_long_range(e, "to", 1, 1, 1, (long)ncomp, &to, err);
    if (rc) return rc;
    if (from == to) return gs_cfg_fail(e, err, "a link from compartment %ld to itself", from);
    const int by_rate = gs_cfg_get(e, "rate") != NULL, by_time = gs_cfg_get(e, "residence_time") != NULL;
    if (by_rate == by_time) return gs_cfg_fail(e, err, "give exactly one of 'rate' [1/s] or 'residence_time' [s]");
    rc = gs_cfg_double_range(e, by_rate ? "rate" : "residence_time", 1, 0, 0, 1, HUGE_VAL, 1, &v, err);
    if (!rc) rc = gs_cfg_check_unused(e, err);
    if (rc) return rc;
    double *kij = &K[(size_t)(from - 1) * ncomp + (size_t)(to - 1)];
    if (*kij > 0) return gs_cfg_fail(e, err, "a second link from %ld to %ld", from, to);
    *kij = by_rate ? v : 1.0 / v;
  }
  return GS_OK;
}

/* The rates of a fragment written by `gransim compartments` (its `rates`;
 * the file's other keys are for the reader and the kernel). */
static int read_fragment(gs_cfg_node *fn, const char *dir, size_t ncomp, double *K, gs_error *err) {
  gs_cfg *cfg = gs_cfg_fragment_load(fn, dir, ncomp, err);
  if (!cfg) return GS_EINPUT;
  gs_cfg_node *mat = NULL;
  int rc = gs_cfg_seq_req(gs_cfg_root(cfg), "rates", &mat, err);
  if (!rc) rc = read_matrix(mat, ncomp, K, err);
  gs_cfg_free(cfg);
  return rc;
}

/* Incoming links per compartment (CSR by destination) and totals out. */
static int build(exchange_t *X, const double *K, const double *discharge, gs_error *err) {
  const size_t n = X->ncomp;
  size_t nlinks = 0;
  for (size_t i = 0; i < n * n; i++) nlinks += K[i] > 0;
  X->out = gs_calloc(n, sizeof(double), err);
  X->first = gs_calloc(n + 1, sizeof(size_t), err);
  X->source = gs_calloc(nlinks + 1, sizeof(size_t), err);
  X->k = gs_calloc(nlinks + 1, sizeof(double), err);
  if (!X->out || !X->first || !X->source || !X->k) return GS_ENOMEM;
  size_t at = 0;
  for (size_t j = 0; j < n; j++) {
    X->first[j] = at;
    for (size_t i = 0; i < n; i++)
      if (K[i * n + j] > 0) {
        X->source[at] = i;
        X->k[at++] = K[i * n + j];
      }
  }
  X->first[n] = at;
  for (size_t i = 0; i < n; i++) {
    X->out[i] = discharge ? discharge[i] : 0;
    for (size_t j = 0; j < n; j++) X->out[i] += K[i * n + j];
  }
  return GS_OK;
}

static int exchange_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  const size_t n = m->grid.ncomp;
  exchange_t *X = gs_calloc(1, sizeof *X, err);
  double *K = gs_calloc(n * n, sizeof(double), err), *discharge = NULL;
  int rc = X && K ? GS_OK : GS_ENOMEM;
  if (!rc) X->ncomp = n;
  gs_cfg_node *mat = rc ? NULL : gs_cfg_get(node, "rates"), *links = rc ? NULL : gs_cfg_get(node, "links");
  gs_cfg_node *file = rc ? NULL : gs_cfg_get(node, "file");
  if (!rc && !!mat + !!links + !!file != 1)
    rc = gs_cfg_fail(node, err, "give exactly one of 'rates' (a matrix, row = from), 'links' "
                                "(a list of {from, to, rate | residence_time}) or 'file' (a fragment of "
                                "gransim compartments)");
  if (!rc) rc = mat ? read_matrix(mat, n, K, err) : links ? read_links(links, n, K, err) : read_fragment(file, m->dir, n, K, err);
  if (!rc && gs_cfg_get(node, "discharge"))
    rc = (discharge = gs_calloc(n, sizeof(double), err)) ? gs_cfg_per_comp(node, "discharge", 0, 0, 0, 0, n, discharge, err) : GS_ENOMEM;
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc) rc = build(X, K, discharge, err);
  free(K);
  free(discharge);
  if (rc) {
    exchange_free(X);
    return rc;
  }
  *self = X;
  return GS_OK;
}

/* Volumes moved by rate k from numbers N and carried totals of src. */
static void moved_volumes(const gs_model *m, const gs_eval *ev, const double *y, size_t src,
                          double k, double *moved) {
  const gs_grid *g = &m->grid;
  const size_t n = g->ncells, dim = (size_t)g->dim;
  const double *N = gs_eval_numbers_c(m, ev, y, src);
  for (size_t a = 0; a < dim; a++) moved[a] = k * gs_dot_strided(N, g->x + a, dim, n);
  for (int q = 0; q < m->ncarried; q++)
    moved[dim + (size_t)q] = k * gs_sum(gs_eval_carried_c(m, ev, y, src, q), n);
}

/* Compartment comp's loss to every link and discharge, and its gains from
 * the compartments linked into it. */
static void exchange_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                           double t, const double *y, double *dydt, double *dledger) {
  (void)t;
  const exchange_t *X = self;
  const size_t n = m->grid.ncells;
  double *ledger = gs_eval_ledger(m, ev, dledger, comp), moved[GS_MAX_VOL];
  for (size_t l = X->first[comp]; l <= X->first[comp + 1]; l++) {
    const int own = l == X->first[comp + 1]; /* the last pass: what leaves comp */
    const size_t src = own ? comp : X->source[l];
    const double f = own ? -X->out[comp] : X->k[l];
    if (f == 0) continue;
    gs_add_scaled(gs_eval_numbers(m, ev, dydt, comp), gs_eval_numbers_c(m, ev, y, src), f, n);
    for (int q = 0; q < m->ncarried; q++)
      gs_add_scaled(gs_eval_carried(m, ev, dydt, comp, q), gs_eval_carried_c(m, ev, y, src, q), f, n);
    moved_volumes(m, ev, y, src, f, moved);
    for (int a = 0; a < m->nvol; a++) ledger[a] += moved[a];
  }
}

const gs_mech_type gs_mech_exchange = {
    .name = "exchange",
    .summary = "exchange between compartments along any directed graph (rate matrix or links)",
    .create = exchange_create,
    .rates = exchange_rates,
    .free = exchange_free,
    .couples_all = 1,
};
