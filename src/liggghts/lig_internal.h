/* Inside the LIGGGHTS engine: the exclusion decks (deck.c), the thermo rows
 * the runner collects (run_liggghts.c) and the reduction (tables.c). */
#ifndef GRANSIM_LIG_INTERNAL_H
#define GRANSIM_LIG_INTERNAL_H
#include <stddef.h>
#include <stdio.h>

#include "dem/dem_case.h"

/* thermo_style custom step atoms ke c_rke cpu v_hn v_hm v_nc v_nin v_tq0 ..
 * (deck.c): GS_LIG_THERMO_COLS columns, then one per wall */
#define GS_LIG_THERMO_COLS 9
typedef struct {
  size_t n, cap;
  size_t ncol; /* GS_LIG_THERMO_COLS + the case's walls (gs_lig_thermo_cols) */
  double *row; /* per row: time [s], atoms, kinetic energy, rotational energy, cpu seconds, hold-up number and
                  mass [kg], pair contacts, particles inserted by the feeds so far, then per wall the torque of
                  the particles about its rotation axis [N m] (0 for a wall that does not move) */
} gs_lig_thermo;
/* The columns of a thermo row of case c. */
size_t gs_lig_thermo_cols(const gs_dem_case *c);
/* One line of LIGGGHTS' screen output: a thermo line (th->ncol numbers,
 * nothing else) at a multiple of the output interval out_every and later
 * than the last row is added to th as a row at time step * dt (1); any other
 * line is left (0); -1: out of memory.  cpu_acc[2] (zero at the start)
 * carries the cpu seconds across LIGGGHTS' runs, which restart its clock. */
int gs_lig_thermo_add(gs_lig_thermo *th, const char *line, double dt, double out_every, double cpu_acc[2]);
/* Whether line is a thermo line of th's columns (1, its step in *step) or not (0). */
int gs_lig_thermo_step(const gs_lig_thermo *th, const char *line, double *step);

/* A deck that only reads mesh `wall` and writes the facets LIGGGHTS refuses
 * to ex_wall<wall>.txt (element_exclusion_list write). */
int gs_lig_write_exclusion_deck(const gs_dem_case *c, size_t wall, const char *path, gs_error *err);
/* Steps between the contact lists the events are counted from: a third of
 * the Hertz contact time of two of the smallest particles at 10 m/s. */
long gs_lig_event_every(const gs_dem_case *c);
/* The name under which the deck reads wall w's mesh: a copy beside the deck,
 * wall<w>_<file name>, so that the folder runs anywhere (a cluster). */
void gs_lig_mesh_name(const gs_dem_case *c, size_t w, char *buf, size_t n);
/* Write plane wall w (walls[w].plane) as an STL mesh to path: the polygon
 * in which it cuts the box (plane_mesh.c). */
int gs_lig_write_plane_mesh(const gs_dem_case *c, size_t w, const char *path, gs_error *err);
/* The radii standing for class i in a feed (deck.c): its radius (1), or
 * GS_LIG_RADII radii of equal-number bins of its range or truncated
 * lognormal, each bin's (mean r^3)^(1/3). */
#define GS_LIG_RADII 16
int gs_lig_class_radii(const gs_dem_case *c, size_t i, double *r);
/* Remove the collision/impact/ppcoll dumps of an earlier run from dir. */
int gs_lig_clear_dumps(const char *dir, gs_error *err);
/* Remove the tables a reduction writes from out (before a run, and after a
 * failed reduction: all of them or none). */
void gs_lig_remove_tables(const gs_dem_case *c, const char *out);
/* The text frames out/vtk/particles_<step>.dump as out/vtk/particles_NNNNNN.vtp
 * at time step x dt and the series out/vtk/particles.pvd, the embedded
 * engine's files (frames.c); the dumps removed once all are converted.
 * Nothing to do without frames. */
int gs_lig_vtk_frames(const gs_dem_case *c, const char *out, gs_error *err);
/* The statistics window of a reduction: from t0 to t1 [s]; t_steady: when the
 * steady-state detector fired (< 0: not run, or it did not fire). */
typedef struct {
  double t0, t1, t_steady;
} gs_lig_window;
/* Reduce out/liggghts/post into out's tables (those of src/dem/stats.c) over
 * the window wdw. */
int gs_lig_reduce(const gs_dem_case *c, const char *out, const gs_lig_thermo *th, const gs_lig_window *wdw,
                  gs_error *err);
/* The deck in two parts (deck.c): all before its runs; and its runs from
 * step from to step to, with what happens between them (rotation.start, the
 * statistics window's dumps), without loops when unrolled (commands on
 * standard input).  gs_lig_write_deck is the two, from 0 to gs_lig_steps. */
int gs_lig_write_setup(const gs_dem_case *c, FILE *fp, const char *data_file, const char *exclusion, gs_error *err);
void gs_lig_write_runs(const gs_dem_case *c, FILE *fp, long from, long to, int unrolled);
/* The case's steps: its duration / time step. */
long gs_lig_steps(const gs_dem_case *c);

/* One contact list of an events file (tables.c): its rows (ncol numbers
 * each) into *rows, their number in *n; returns its step + 1, 0 at the end,
 * -1 when unreadable. */
long gs_lig_next_list(FILE *fp, size_t ncol, double **rows, size_t *cap, size_t *n);

/* The steady-state detector on the dumps (steady.c). */
typedef struct {
  long smp_k;                     /* steps between samples */
  double t_agitate;               /* the last rotation.start: samples up to it are left out */
  long pos;                       /* events_pp.txt: where the next list starts */
  size_t lists;                   /* lists read */
  unsigned long long *prev, *cur; /* the last list's pairs, sorted */
  size_t nprev;
  double *rows;
  size_t caprows;
  double *ev; /* contacts that began per sample interval j: steps ((j-1) smp_k, j smp_k] */
  size_t cap_ev;
  double *t, *m, *cr, *ke; /* per sample: time [s], hold-up mass [kg], collision rate [1/s], kinetic energy [J] */
  size_t ns, cap, k_ag; /* samples, room, the first sample after t_agitate */
  double t_steady;      /* when the detector fired, or -1 */
} gs_lig_steady;
void gs_lig_steady_init(gs_lig_steady *s, const gs_dem_case *c);
/* The samples up to step upto from the dumps in post, each through the
 * detector (s->t_steady once it fired). */
int gs_lig_steady_update(gs_lig_steady *s, const gs_dem_case *c, const char *post, long upto, gs_error *err);
/* The error of a run that did not become steady, with the last figures. */
int gs_lig_steady_not_reached(const gs_lig_steady *s, const gs_dem_case *c, gs_error *err);
void gs_lig_steady_free(gs_lig_steady *s);
#endif
