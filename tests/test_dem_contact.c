/* DEM contact law against theory: head-on restitution and Hertz contact time,
 * Coulomb sliding on an oblique wall impact, rolling resistance (CDT), energy
 * conservation without damping, and collision events counted once. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/dem.h"

static const gs_dem_material MAT = {8e6, 0.2, 0.4, 0.5, 0.0, 500};

static gs_dem *make(double dt, double skin, const double g[3], int damping, int nclass) {
  gs_dem_params p;
  memset(&p, 0, sizeof p);
  p.dt = dt;
  p.skin = skin;
  for (int a = 0; a < 3; a++) {
    p.lo[a] = -0.05;
    p.hi[a] = 0.05;
    p.gravity[a] = g ? g[a] : 0;
  }
  p.damping = damping;
  p.nclass = nclass;
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  if (!d) fprintf(stderr, "%s\n", err.msg);
  return d;
}

/* Hertz contact time of an undamped impact at relative speed v. */
static double hertz_time(double r1, double r2, double m1, double m2, double Estar, double v) {
  double R = r1 * r2 / (r1 + r2), m = m1 * m2 / (m1 + m2);
  return 2.868265699 * pow(m * m / (R * Estar * Estar * v), 0.2);
}

typedef struct {
  double e, tc;
  long events;
} headon;

/* Two spheres approach head on along x; returns the realised restitution and
 * the contact duration (first touch to separation, interpolated in time). */
static headon collide(double e, int damping, double v, double skin, double dt_frac) {
  headon out = {0, 0, -1};
  gs_dem_material m = MAT;
  m.e = e;
  const double r = 1e-3, mass = 500 * 4.0 / 3 * M_PI * r * r * r;
  const double Estar = 1 / (2 * (1 - 0.04) / 8e6);
  double tc0 = hertz_time(r, r, mass, mass, Estar, 2 * v);
  gs_dem *d = make(tc0 * dt_frac, skin, NULL, damping, 2);
  gs_error err = {0};
  int t0 = gs_dem_add_type(d, &m, 0, &err), t1 = gs_dem_add_type(d, &m, 1, &err);
  double x1[3] = {-r - 0.02 * r, 0, 0}, x2[3] = {r + 0.02 * r, 0, 0};
  double v1[3] = {v, 0, 0}, v2[3] = {-v, 0, 0};
  gs_dem_add_particle(d, t0, r, x1, v1, NULL, &err);
  gs_dem_add_particle(d, t1, r, x2, v2, NULL, &err);
  double gap_prev = 0.04 * r, t_start = -1, t_end = -1, tprev = 0;
  for (int s = 0; s < 200000 && t_end < 0; s++) {
    if (gs_dem_run(d, 1, &err)) {
      fprintf(stderr, "%s\n", err.msg);
      break;
    }
    gs_dem_view w;
    gs_dem_get_view(d, &w);
    int a = w.id[0] == 0 ? 0 : 1, b = 1 - a;
    double gap = fabs(w.x[b] - w.x[a]) - 2 * r, t = gs_dem_time(d);
    if (t_start < 0 && gap < 0) t_start = tprev + (t - tprev) * gap_prev / (gap_prev - gap);
    if (t_start >= 0 && gap >= 0) {
      t_end = tprev + (t - tprev) * (-gap_prev) / (gap - gap_prev);
      out.e = (w.vx[b] - w.vx[a]) / (2 * v);
    }
    gap_prev = gap;
    tprev = t;
  }
  out.tc = t_end - t_start;
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  out.events = (long)c.pair_events[0 * 2 + 1];
  gs_dem_free(d);
  return out;
}

static void test_headon(void) {
  const double r = 1e-3, mass = 500 * 4.0 / 3 * M_PI * r * r * r;
  const double Estar = 1 / (2 * (1 - 0.04) / 8e6);
  /* undamped: Hertz contact time and e = 1 */
  headon h = collide(1.0, GS_DEM_DAMPING_EXACT, 0.5, 2e-4, 1.0 / 400);
  double tc = hertz_time(r, r, mass, mass, Estar, 1.0);
  fprintf(stderr, "e=1: restitution %.6f, contact time %.6g s vs Hertz %.6g s (%.3f %%)\n", h.e,
          h.tc, tc, 100 * (h.tc / tc - 1));
  CHECK_REL(h.tc, tc, 0.02);
  CHECK_REL(h.e, 1.0, 0.01);
  CHECK(h.events == 1);
  /* damped: the prescribed restitution, at two speeds (it must not depend on v) */
  const double es[] = {0.2, 0.4, 0.7, 0.9};
  for (int k = 0; k < 4; k++)
    for (double v = 0.1; v < 5; v *= 10) {
      h = collide(es[k], GS_DEM_DAMPING_EXACT, v, 2e-4, 1.0 / 400);
      fprintf(stderr, "e=%.2f v=%.1f: restitution %.6f (%.3f %%)\n", es[k], v, h.e,
              100 * (h.e / es[k] - 1));
      CHECK_REL(h.e, es[k], 0.01);
      CHECK(h.events == 1);
    }
  /* LIGGGHTS' closed form realises what the impact equation predicts for its c */
  double c = gs_dem_damping_coefficient(0.4, GS_DEM_DAMPING_LIGGGHTS);
  h = collide(0.4, GS_DEM_DAMPING_LIGGGHTS, 0.5, 2e-4, 1.0 / 400);
  fprintf(stderr, "liggghts damping, e=0.4 prescribed: realised %.4f, predicted %.4f\n", h.e,
          gs_dem_restitution_of(c));
  CHECK_REL(h.e, gs_dem_restitution_of(c), 0.01);
  /* a long contact (slow impact, tiny step, small skin so the lists are rebuilt
   * during the contact) is one event, and history survives the rebuilds */
  h = collide(0.4, GS_DEM_DAMPING_EXACT, 0.05, 2e-6, 1.0 / 3000);
  fprintf(stderr, "slow impact: %ld event(s), restitution %.5f\n", h.events, h.e);
  CHECK(h.events == 1);
  CHECK_REL(h.e, 0.4, 0.01);
}

/* Sphere hits a plane at 45 degrees and more: in gross sliding the tangential
 * impulse is mu times the normal impulse, so the tangential velocity drops by
 * mu (1 + e) vn and the spin becomes 5/2 of that over r; at small angles the
 * contact sticks: the tangential impulse stays well inside the Coulomb bound
 * and the sphere leaves nearly rolling (the Mindlin tangential spring gives
 * back part of its energy, so the slip is small but not zero). */
static void oblique(double vn0, double vt0, double *dvt, double *wr, double *slip) {
  gs_dem_material m = MAT;
  m.e = 0.9;
  m.mu_s = 0.3;
  gs_dem *d = make(2e-7, 2e-4, NULL, GS_DEM_DAMPING_EXACT, 1);
  gs_error err = {0};
  int t = gs_dem_add_type(d, &m, 0, &err);
  double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
  gs_dem_add_plane(d, "floor", o, nz, &m, &err);
  const double r = 1e-3;
  double x[3] = {0, 0, r * 1.01}, v[3] = {vt0, 0, -vn0};
  gs_dem_add_particle(d, t, r, x, v, NULL, &err);
  for (int s = 0; s < 100; s++) {
    gs_dem_run(d, 100, &err);
    gs_dem_view w;
    gs_dem_get_view(d, &w);
    if (w.z[0] > r * 1.02 && w.vz[0] > 0) break;
  }
  gs_dem_view w;
  gs_dem_get_view(d, &w);
  *dvt = vt0 - w.vx[0];
  *wr = w.wy[0] * r;     /* rolling in +x spins about +y */
  *slip = w.vx[0] - *wr; /* contact point velocity */
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  CHECK(c.wall_impacts[0] == 1);
  gs_dem_free(d);
}

static void test_oblique(void) {
  const double e = 0.9, mu = 0.3, vn = 0.5;
  double dvt, wr, slip;
  /* sliding throughout: vt0 > 7/2 mu (1+e) vn */
  oblique(vn, 3.0, &dvt, &wr, &slip);
  double want = mu * (1 + e) * vn;
  fprintf(stderr, "sliding: dvt %.5f (Coulomb %.5f), w r %.5f (want %.5f)\n", dvt, want, wr, 2.5 * want);
  CHECK_REL(dvt, want, 0.03);
  CHECK_REL(wr, 2.5 * want, 0.03);
  /* sticking: vt0 well below the limit; the sphere rolls away */
  oblique(vn, 0.2, &dvt, &wr, &slip);
  fprintf(stderr, "sticking: dvt %.5f (bound %.5f), slip %.5f of vt0 0.2, rolling %.4f\n", dvt, want,
          slip, 0.2 * 5 / 7);
  CHECK(dvt < 0.5 * want);            /* well inside the Coulomb bound: no gross sliding */
  CHECK_REL(wr, 2.5 * dvt, 0.03);     /* spin from the same tangential impulse */
  CHECK(fabs(slip) < 0.5 * 0.2);      /* far from the frictionless slip vt0 */
}

/* A sphere rolling on a plane stops after v0^2 / (2 * 5/7 mu_r g) under the
 * constant-directional torque mu_r * Fn * r. */
static void test_rolling(void) {
  gs_dem_material m = MAT;
  m.mu_r = 0.2;
  m.e = 0.5;
  const double g[3] = {0, 0, -9.81};
  gs_dem *d = make(2e-6, 2e-4, g, GS_DEM_DAMPING_EXACT, 1);
  gs_error err = {0};
  int t = gs_dem_add_type(d, &m, 0, &err);
  double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
  gs_dem_add_plane(d, "floor", o, nz, &m, &err);
  const double r = 1e-3, v0 = 0.05;
  /* start at the static overlap under its own weight, already rolling */
  const double mass = 500 * 4.0 / 3 * M_PI * r * r * r;
  const double Estar = 1 / ((1 - 0.04) / 8e6 * 2);
  double delta = pow(mass * 9.81 / (4.0 / 3 * Estar * sqrt(r)), 2.0 / 3);
  double x[3] = {0, 0, r - delta}, v[3] = {v0, 0, 0}, w0[3] = {0, v0 / r, 0};
  gs_dem_add_particle(d, t, r, x, v, w0, &err);
  double xstop = -1;
  for (int s = 0; s < 2000 && xstop < 0; s++) {
    gs_dem_run(d, 50, &err);
    gs_dem_view w;
    gs_dem_get_view(d, &w);
    if (w.vx[0] <= 1e-4) xstop = w.x[0];
  }
  double want = v0 * v0 / (2 * 5.0 / 7 * 0.2 * 9.81);
  fprintf(stderr, "rolling friction: stops after %.6g m, theory %.6g m\n", xstop, want);
  CHECK_REL(xstop, want, 0.05);
  gs_dem_free(d);
}

/* Elastic (e = 1), frictionless spheres in a closed box under gravity: kinetic
 * + potential + Hertz elastic energy is conserved. */
static double total_energy(gs_dem *d, const double *lo, const double *hi, double Estar) {
  gs_dem_view w;
  gs_dem_get_view(d, &w);
  double et, er, e = 0;
  gs_dem_kinetic_energy(d, &et, &er);
  e = et + er;
  for (size_t i = 0; i < w.n; i++) {
    e += w.m[i] * 9.81 * w.z[i];
    for (size_t j = i + 1; j < w.n; j++) {
      double dx = w.x[i] - w.x[j], dy = w.y[i] - w.y[j], dz = w.z[i] - w.z[j];
      double ov = w.r[i] + w.r[j] - sqrt(dx * dx + dy * dy + dz * dz);
      double R = w.r[i] * w.r[j] / (w.r[i] + w.r[j]);
      if (ov > 0) e += 8.0 / 15 * Estar * sqrt(R) * pow(ov, 2.5);
    }
    const double pos[3] = {w.x[i], w.y[i], w.z[i]};
    for (int a = 0; a < 3; a++) {
      double o1 = w.r[i] - (pos[a] - lo[a]), o2 = w.r[i] - (hi[a] - pos[a]);
      /* same material on both sides: the wall pair has the same E*, R* = r */
      if (o1 > 0) e += 8.0 / 15 * Estar * sqrt(w.r[i]) * pow(o1, 2.5);
      if (o2 > 0) e += 8.0 / 15 * Estar * sqrt(w.r[i]) * pow(o2, 2.5);
    }
  }
  return e;
}

static void test_energy(void) {
  gs_dem_material m = MAT;
  m.e = 1.0;
  m.mu_s = 0;
  const double g[3] = {0, 0, -9.81};
  gs_dem *d = make(1e-6, 3e-4, g, GS_DEM_DAMPING_EXACT, 1);
  gs_error err = {0};
  int t = gs_dem_add_type(d, &m, 0, &err);
  const double lo[3] = {-0.006, -0.006, 0}, hi[3] = {0.006, 0.006, 0.012};
  for (int a = 0; a < 3; a++) {
    double pl[3] = {0, 0, 0}, nl[3] = {0, 0, 0}, ph[3] = {0, 0, 0}, nh[3] = {0, 0, 0};
    pl[a] = lo[a], nl[a] = 1, ph[a] = hi[a], nh[a] = -1;
    gs_dem_add_plane(d, "lo", pl, nl, &m, &err);
    gs_dem_add_plane(d, "hi", ph, nh, &m, &err);
  }
  unsigned s = 12345;
  int placed = 0;
  for (int i = 0; i < 4 && placed < 60; i++)
    for (int j = 0; j < 4; j++)
      for (int k = 0; k < 4; k++) {
        s = s * 1103515245u + 12345u;
        double x[3] = {-0.0045 + 0.003 * i, -0.0045 + 0.003 * j, 0.0015 + 0.003 * k};
        double v[3] = {((s >> 8) % 1000) / 1000.0 - 0.5, ((s >> 12) % 1000) / 1000.0 - 0.5,
                       ((s >> 16) % 1000) / 1000.0 - 0.5};
        double r = 0.8e-3 + 0.4e-3 * ((s >> 4) % 100) / 100.0;
        gs_dem_add_particle(d, t, r, x, v, NULL, &err);
        placed++;
      }
  const double Estar = 1 / (2 * (1 - 0.04) / 8e6);
  gs_dem_run(d, 1, &err);
  double e0 = total_energy(d, lo, hi, Estar);
  gs_dem_run(d, 20000, &err);
  double e1 = total_energy(d, lo, hi, Estar);
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  fprintf(stderr, "energy: %.8g -> %.8g J (%.4f %%), %llu collisions\n", e0, e1,
          100 * (e1 / e0 - 1), (unsigned long long)c.pair_events[0]);
  CHECK_REL(e1, e0, 0.002);
  CHECK(c.pair_events[0] > 50); /* the test must actually exercise contacts */
  gs_dem_free(d);
}

/* A static stack (sphere on sphere on a floor) is one contact each, however
 * many steps and list rebuilds it lasts. */
static int never(const double x[3], void *ctx) {
  (void)ctx;
  return x[0] > 1;
}

static void test_count_once(void) {
  gs_dem_material m = MAT;
  const double g[3] = {0, 0, -9.81};
  gs_dem *d = make(5e-6, 1e-4, g, GS_DEM_DAMPING_EXACT, 2);
  gs_error err = {0};
  int t0 = gs_dem_add_type(d, &m, 0, &err), t1 = gs_dem_add_type(d, &m, 1, &err);
  double o[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
  gs_dem_add_plane(d, "floor", o, nz, &m, &err);
  /* start at the static Hertz overlaps: floor carries 2 m g, the pair m g */
  const double r = 1e-3, mg = 500 * 4.0 / 3 * M_PI * r * r * r * 9.81;
  const double Estar = 1 / (2 * (1 - 0.04) / 8e6);
  double df = pow(2 * mg / (4.0 / 3 * Estar * sqrt(r)), 2.0 / 3);
  double dp = pow(mg / (4.0 / 3 * Estar * sqrt(r / 2)), 2.0 / 3);
  double x1[3] = {0, 0, r - df}, x2[3] = {0, 0, r - df + 2 * r - dp};
  gs_dem_add_particle(d, t0, 1e-3, x1, NULL, NULL, &err);
  gs_dem_add_particle(d, t1, 1e-3, x2, NULL, NULL, &err);
  gs_dem_remove_if(d, never, NULL); /* forces a list rebuild every 200 steps */
  gs_dem_run(d, 20000, &err);
  gs_dem_counters c;
  gs_dem_get_counters(d, &c);
  fprintf(stderr, "static stack: %llu pair event(s), %llu floor impact(s), %llu rebuilds\n",
          (unsigned long long)c.pair_events[1], (unsigned long long)c.wall_impacts[0],
          (unsigned long long)c.rebuilds);
  CHECK(c.pair_events[1] == 1);
  CHECK(c.pair_events[0] == 0 && c.pair_events[3] == 0);
  CHECK(c.wall_impacts[0] == 1);
  CHECK(c.rebuilds >= 50);
  CHECK(gs_dem_ncontacts(d) == 1);
  gs_dem_free(d);
}

int main(void) {
  test_headon();
  test_oblique();
  test_rolling();
  test_energy();
  test_count_once();
  TEST_EXIT();
}
