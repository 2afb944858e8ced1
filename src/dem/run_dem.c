/* The DEM run driver: initial fill, feeds at a rate, outlets, sampling,
 * the steady-state detector, time series, VTK files and the progress line.
 *
 * The engine advances in chunks up to the next event (output, sample, VTK
 * frame, feed); events are evaluated between chunks, so they happen on step
 * boundaries. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/progress.h"
#include "gransim/output.h"
#include "dem/dem_internal.h"
#include "dem/dem_stats.h"
#include "dem/dem_vtk.h"

/* steps between two looks at the clock for the progress line */
#define GS_DEM_PROGRESS_STEPS 200

static void dem_progress(gs_progress *line, gs_dem *d, int force) {
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  char extra[96];
  snprintf(extra, sizeof extra, "%zu particles, %zu contacts", v.n, gs_dem_ncontacts(d));
  gs_progress_update(line, gs_dem_time(d), extra, force);
}

static int in_outlet(const double x[3], void *ctx) {
  const gs_dem_case *c = ctx;
  for (size_t k = 0; k < c->noutlets; k++)
    if (gs_dem_region_contains(&c->outlets[k], x)) return 1;
  return 0;
}

int gs_dem_case_insert(gs_dem_case *c, gs_dem_inserter *in, long count, double mass, uint64_t *rng,
                       long *n, double *m, gs_error *err) {
  int types[GS_DEM_MAX_CLASSES];
  double rmin[GS_DEM_MAX_CLASSES], rmax[GS_DEM_MAX_CLASSES], med[GS_DEM_MAX_CLASSES], gsd[GS_DEM_MAX_CLASSES];
  for (size_t k = 0; k < c->nclass; k++) {
    types[k] = c->cls[k].type;
    rmin[k] = c->cls[k].rmin;
    rmax[k] = c->cls[k].rmax;
    med[k] = c->cls[k].median;
    gsd[k] = c->cls[k].gsd;
  }
  gs_dem_psd psd = {c->nclass, types, rmin, rmax, in->frac, in->by_mass, med, gsd};
  return gs_dem_insert(c->dem, &in->reg, &psd, count, mass, in->v, rng, n, m, err);
}

/* Add the engine's current event and impact counts to running totals. */
static void add_totals(const gs_dem *d, uint64_t *events, uint64_t *impacts) {
  gs_dem_counters k;
  gs_dem_get_counters(d, &k);
  for (int i = 0; i < k.nclass * k.nclass; i++) *events += k.pair_events[i];
  for (size_t w = 0; w < k.nwalls; w++)
    for (int i = 0; i < k.nclass; i++) impacts[w] += k.wall_impacts[w * (size_t)k.nclass + i];
}

/* One object's frame (wall w, or the particles when w is SIZE_MAX) and its
 * series file rewritten with the frame's time, so that an interrupted run
 * leaves a series ParaView opens. */
static int vtk_frame(const gs_dem *d, const char *vdir, const char *stem, size_t w, long frame,
                     const double *times, char *path, size_t n, gs_error *err) {
  snprintf(path, n, "%s/%s_%06ld.vtp", vdir, stem, frame);
  int rc = w == SIZE_MAX ? gs_dem_write_vtp_particles(d, path, err)
                         : gs_dem_write_vtp_wall(d, w, path, err);
  if (!rc) {
    snprintf(path, n, "%s/%s.pvd", vdir, stem);
    rc = gs_dem_write_pvd(path, stem, times, frame + 1, err);
  }
  return rc;
}

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int gs_dem_case_run(gs_dem_case *c, const char *dir, int progress, gs_error *err) {
  if (gs_output_mkdir_p(dir, err)) return err->code;
  char path[8400], vdir[4200];
  snprintf(vdir, sizeof vdir, "%s/vtk", dir);
  if (c->vtk_every > 0 && mkdir(vdir, 0777) && errno != EEXIST)
    return gs_error_set(err, GS_EIO, "%s: cannot create: %s", vdir, strerror(errno));
  int rc = gs_dem_case_write_geometry(c, dir, NULL, err);
  if (rc) return rc;
  gs_dem *d = c->dem;
  const double dt = c->prm.dt;
  uint64_t rng = c->seed;
  gs_dem_stats st;
  if ((rc = gs_dem_stats_init(&st, c, err))) return rc;
  gs_dem_health health;
  gs_dem_health_init(&health, c);
  long cap = 1024, ns = 0, frame_cap = 64;
  double *frame_t = malloc((size_t)frame_cap * sizeof *frame_t); /* times of the VTK frames */
  /* the detector's series: hold-up mass, collision rate, kinetic energy (statistics.steady.quantities) */
  double *ser_m = malloc(cap * sizeof(double)), *ser_c = malloc(cap * sizeof(double)),
         *ser_k = malloc(cap * sizeof(double));
  if (!ser_m || !ser_c || !ser_k || !frame_t) rc = gs_error_set(err, GS_ENOMEM, "out of memory");

  /* initial fill */
  for (size_t k = 0; k < c->nfill && !rc; k++) {
    long n;
    double m;
    rc = gs_dem_case_insert(c, &c->fill[k], c->fill[k].count, c->fill[k].mass, &rng, &n, &m, err);
    if (!rc) health.inserted += n;
    if (!rc && n < c->fill[k].count && !isfinite(c->fill[k].mass))
      fprintf(stderr, "gransim: warning: fill[%zu]: region full after %ld of %ld particles\n", k, n,
              c->fill[k].count);
    if (!rc && isfinite(c->fill[k].mass) && m < 0.99 * c->fill[k].mass)
      fprintf(stderr, "gransim: warning: fill[%zu]: region full after %.4g of %.4g kg\n", k, m,
              c->fill[k].mass);
    if (!rc && progress) fprintf(stderr, "gransim dem: fill[%zu]: %ld particles, %.4g kg\n", k, n, m);
  }
  if (c->noutlets) gs_dem_remove_if(d, in_outlet, c);
  /* (the time step was checked against the Rayleigh time when the case was read) */

  char ts_path[4300];
  FILE *ts = rc ? NULL : gs_dem_table_open(dir, "timeseries.csv", ts_path, sizeof ts_path, err);
  if (!rc && !ts) rc = err->code;
  if (ts) {
    fprintf(ts, "time,particles,holdup_number,holdup_mass,kinetic_energy,rotational_energy,contacts,"
            "collisions_per_s");
    for (size_t w = 0; w < gs_dem_nwalls(d); w++) fprintf(ts, ",impacts_per_s_%s", gs_dem_wall_name(d, w));
    for (size_t w = 0; w < gs_dem_nwalls(d); w++) fprintf(ts, ",torque_axis_%s", gs_dem_wall_name(d, w));
    fprintf(ts, ",lost,steady,wall_seconds\n");
  }

  const long nsteps = (long)ceil(c->duration / dt - 1e-9);
  const long out_k = (long)fmax(1, round(c->out_every / dt));
  const long smp_k = (long)fmax(1, round(c->sample_every / dt));
  const long vtk_k = c->vtk_every > 0 ? (long)fmax(1, round(c->vtk_every / dt)) : 0;
  const long start_k = (long)round(c->stats_start / dt);
  long step = 0, frame = 0;
  int steady = 0, stats_on = !c->start_steady && start_k == 0, stop = 0;
  double t_steady = -1, t0wall = wall_seconds(), t_agitate = 0;
  long k_agitate = 0; /* the first sample the steady-state detector sees */
  for (size_t w = 0; w < c->nwall_src; w++)
    if (c->wall_src[w].rotating) t_agitate = fmax(t_agitate, c->wall_src[w].spin_start);
  uint64_t prev_events = 0, out_events = 0, out_imp[GS_DEM_MAX_WALLS] = {0};
  /* the engine's counters restart with the statistics window; the time series
   * keeps running totals across that reset */
  uint64_t base_events = 0, base_imp[GS_DEM_MAX_WALLS] = {0};
  double psteps = 0;
  long prev_out_step = 0;
  /* the progress line: on a terminal only (nothing in pipes or CI logs) */
  const int show = progress && isatty(STDERR_FILENO);
  gs_progress line;
  if (show) gs_progress_start(&line, "gransim dem", "s", 0.0, nsteps * dt);
  if (!rc) rc = gs_dem_run(d, 0, err); /* place the fill so that t = 0 is reported */
  if (!rc) rc = gs_dem_wet_start(c, dir, err);
  if (!rc) rc = gs_dem_health_check(&health, c, 1, err);
  if (!rc) gs_dem_stats_reset(&st, c, 0);
  const int stepped = !rc; /* from here a failure still writes the tables */
  while (!rc && step <= nsteps) {
    /* events at this step */
    if (!c->start_steady && !stats_on && step >= start_k) {
      add_totals(d, &base_events, base_imp);
      gs_dem_stats_reset(&st, c, gs_dem_time(d));
      prev_events = 0;
      stats_on = 1;
    }
    for (size_t k = 0; k < c->nfeed && !rc; k++) {
      gs_dem_inserter *f = &c->feed[k];
      double t = gs_dem_time(d);
      if (t + 0.5 * dt < f->next_t || t >= f->end) continue;
      /* insert one interval's worth at the start of each interval */
      double span = fmin(t + f->every, f->end) - f->start;
      long n;
      double m;
      if (f->mass_rate > 0) rc = gs_dem_case_insert(c, f, LONG_MAX, f->mass_rate * span - f->done_m, &rng, &n, &m, err);
      else rc = gs_dem_case_insert(c, f, (long)floor(f->number_rate * span - f->done_n + 0.5), HUGE_VAL, &rng, &n, &m, err);
      if (!rc) health.inserted += n;
      f->done_n += (double)n;
      f->done_m += m;
      f->next_t += f->every;
    }
    if (!rc && step % smp_k == 0 && step > 0) {
      gs_dem_counters k;
      gs_dem_get_counters(d, &k);
      uint64_t ev = 0;
      for (int i = 0; i < k.nclass * k.nclass; i++) ev += k.pair_events[i];
      double hn, hm;
      gs_dem_holdup(c, &hn, &hm);
      if (ns == cap) {
        cap *= 2;
        double *a = realloc(ser_m, cap * sizeof(double)), *b = realloc(ser_c, cap * sizeof(double)),
               *e = realloc(ser_k, cap * sizeof(double));
        if (a) ser_m = a;
        if (b) ser_c = b;
        if (e) ser_k = e;
        if (!a || !b || !e) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
      }
      double et, er;
      gs_dem_kinetic_energy(d, &et, &er);
      if (!rc) {
        ser_m[ns] = hm;
        ser_k[ns] = et + er;
        ser_c[ns] = (double)(ev - (ev >= prev_events ? prev_events : ev)) / (smp_k * dt);
        ns++;
        prev_events = ev;
      }
      int open_window = 0;
      /* a bed at rest before its walls turn is not the steady state sought:
       * the detector's window holds samples from the last rotation start on */
      if (gs_dem_time(d) <= t_agitate * (1 + 1e-12)) k_agitate = ns;
      const double *watched[3], *all[3] = {ser_m + k_agitate, ser_c + k_agitate, ser_k + k_agitate};
      int nq = 0;
      for (int q = 0; q < 3; q++) /* in the order of gs_dem_steady_quantities */
        if (c->steady_q & (1u << q)) watched[nq++] = all[q];
      if (!rc && !steady && gs_dem_is_steady_n(watched, nq, ns - k_agitate, c->steady_window, c->steady_tol)) {
        steady = 1;
        t_steady = gs_dem_time(d);
        if (progress) fprintf(stderr, "gransim dem: steady state at t = %.6g s\n", t_steady);
        open_window = c->start_steady;
      }
      if (!rc && c->observer.sample) {
        gs_dem_view v;
        gs_dem_get_view(d, &v);
        gs_dem_sample smp = {.t = gs_dem_time(d), .step = gs_dem_step_count(d), .particles = v.n,
                             .holdup_mass = hm, .collisions_per_s = ser_c[ns - 1], .kinetic_energy = et + er,
                             .steady = steady, .window = stats_on};
        int ow = 0;
        rc = c->observer.sample(&smp, c->observer.user, &ow, &stop, err);
        open_window |= ow;
      }
      if (!rc && open_window && !stats_on) {
        add_totals(d, &base_events, base_imp);
        gs_dem_stats_reset(&st, c, gs_dem_time(d));
        prev_events = 0;
        stats_on = 1;
      }
      if (!rc && stats_on) rc = gs_dem_stats_sample(&st, c, err);
    }
    if (!rc && step % out_k == 0) {
      gs_dem_counters k;
      gs_dem_get_counters(d, &k);
      double span = (step - prev_out_step) * dt, et, er, hn, hm;
      gs_dem_kinetic_energy(d, &et, &er);
      gs_dem_holdup(c, &hn, &hm);
      gs_dem_view v;
      gs_dem_get_view(d, &v);
      uint64_t ev = base_events;
      for (int i = 0; i < k.nclass * k.nclass; i++) ev += k.pair_events[i];
      fprintf(ts, "%.9g,%zu,%.0f,%.9g,%.9g,%.9g,%zu,%.9g", gs_dem_time(d), v.n, hn, hm, et, er,
              gs_dem_ncontacts(d), span > 0 ? (double)(ev - out_events) / span : 0);
      out_events = ev;
      for (size_t w = 0; w < k.nwalls; w++) {
        uint64_t im = base_imp[w];
        for (int i = 0; i < k.nclass; i++) im += k.wall_impacts[w * (size_t)k.nclass + i];
        fprintf(ts, ",%.9g", span > 0 ? (double)(im - out_imp[w]) / span : 0);
        out_imp[w] = im;
      }
      for (size_t w = 0; w < k.nwalls; w++) fprintf(ts, ",%.9g", gs_dem_wall_axial_torque(d, w));
      fprintf(ts, ",%llu,%d,%.6f\n", (unsigned long long)k.lost, steady, wall_seconds() - t0wall);
      prev_out_step = step;
      if (!rc) rc = gs_dem_wet_output(c, err);
    }
    if (!rc && vtk_k && step % vtk_k == 0) {
      if (frame == frame_cap) {
        double *nt = realloc(frame_t, 2 * (size_t)frame_cap * sizeof *nt);
        if (!nt) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
        else frame_t = nt, frame_cap *= 2;
      }
      if (!rc) frame_t[frame] = gs_dem_time(d);
      if (!rc) rc = vtk_frame(d, vdir, "particles", SIZE_MAX, frame, frame_t, path, sizeof path, err);
      for (size_t w = 0; w < gs_dem_nwalls(d) && !rc; w++)
        if (gs_dem_wall_triangles(d, w, NULL))
          rc = vtk_frame(d, vdir, gs_dem_wall_name(d, w), w, frame, frame_t, path, sizeof path, err);
      frame++;
    }
    if (rc || stop || step == nsteps) break; /* a failed event above stops the run here */
    /* advance to the next event */
    long next = nsteps;
    long cand[4] = {(step / out_k + 1) * out_k, (step / smp_k + 1) * smp_k,
                    vtk_k ? (step / vtk_k + 1) * vtk_k : nsteps, start_k > step ? start_k : nsteps};
    for (int q = 0; q < 4; q++)
      if (cand[q] < next) next = cand[q];
    for (size_t k = 0; k < c->nfeed; k++) {
      long fk = (long)ceil(c->feed[k].next_t / dt - 1e-9);
      if (fk > step && fk < next && c->feed[k].next_t < c->feed[k].end) next = fk;
    }
    {
      gs_dem_view v;
      gs_dem_get_view(d, &v);
      psteps += (double)v.n * (double)(next - step);
    }
    /* in pieces while a progress line shows, so that it moves between output
     * times (a step does the same whatever piece it is in) */
    const long piece = show ? GS_DEM_PROGRESS_STEPS : next - step;
    while (!rc && step < next) {
      const long k = next - step < piece ? next - step : piece;
      rc = gs_dem_wet_advance(c, k, err);
      step += k;
      if (!rc && show) dem_progress(&line, d, 0);
    }
    rc = rc ? gs_dem_health_explain(c, rc, err) : gs_dem_health_check(&health, c, 0, err);
  }
  if (show && !rc) dem_progress(&line, d, 1); /* the end, whatever the throttle */
  if (show) gs_progress_end(&line);
  if (!rc && progress) {
    double el = wall_seconds() - t0wall;
    gs_dem_counters k;
    gs_dem_get_counters(d, &k);
    fprintf(stderr, "gransim dem: %ld steps in %.2f s, %.4g particle-steps/s, %llu neighbour-list "
            "rebuilds%s\n", step, el, el > 0 ? psteps / el : 0, (unsigned long long)k.rebuilds,
            t_steady >= 0 ? "" : "; steady state not reached");
  }
  if (ts) {
    gs_error cerr = {0};
    int crc = gs_dem_table_close(ts, ts_path, rc ? &cerr : err);
    if (!rc) rc = crc;
  }
  if (ts && !rc) {
    const char *names[GS_DEM_MAX_WALLS];
    for (size_t w = 0; w < gs_dem_nwalls(d); w++) names[w] = gs_dem_wall_name(d, w);
    rc = gs_dem_timeseries_meta(ts_path, "hold-up, energies, contacts, collision and impact rates (per second "
                                "since the previous row) and torques on the walls about their rotation axis, "
                                "every output.every seconds", gs_dem_nwalls(d), names, err);
  }
  {
    gs_error werr = {0};
    int wrc = gs_dem_wet_finish(c, rc ? &werr : err);
    if (!rc) rc = wrc;
  }
  if (!rc && !gs_dem_stats_have_window(&st, c, gs_dem_time(d), t_steady)) {
    if (c->start_steady) {
      char q[96];
      gs_dem_steady_quantities_join(c->steady_q, ", ", q, sizeof q);
      fprintf(stderr, "gransim: warning: %s: statistics.start is 'steady' but the steady state was not reached "
              "by t = %.6g s (%s within %g of their means over %ld samples): there is no statistics window, so the "
              "rates in the tables are nan; run longer, or set statistics.start to a time or loosen "
              "statistics.steady\n", c->path, gs_dem_time(d), q, c->steady_tol, c->steady_window);
    } else
      fprintf(stderr, "gransim: warning: %s: no sample in the statistics window (statistics.start %.6g s, "
              "sample_every %.6g s, duration %.6g s): the rates in the tables are nan\n", c->path, c->stats_start,
              c->sample_every, c->duration);
  }
  if (!rc) {
    rc = gs_dem_stats_write(&st, c, dir, gs_dem_time(d), t_steady, NULL, err);
  } else if (stepped) {
    /* a run stopped part-way (a refusal, a numerical failure, the gas phase)
     * leaves its collision and impact tables up to there, as its other
     * outputs; the error reported stays the one that stopped it */
    gs_error terr = {0};
    gs_dem_stats_write(&st, c, dir, gs_dem_time(d), t_steady, err->msg, &terr);
  }
  gs_dem_stats_free(&st);
  free(ser_m);
  free(ser_c);
  free(ser_k);
  free(frame_t);
  return rc;
}
