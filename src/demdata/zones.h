/* Compartments (zones) of a granulator identified from DEM particle frames
 * (Chaudhury 2015, ch. 3.3): every particle of every frame is a point of
 * position and velocity, scaled (positions by L, the RMS distance of the
 * particles from their mean position; velocities by U, the RMS deviation of
 * their velocity from its mean; times `velocity_weight`), clustered by
 * k-means (kmeans.h).  A zone's hold-up, solid volume and mean speed are
 * frame averages; the exchange rate K_ij is the number of particles seen
 * in zone i in one frame and in zone j in the next, over the particle-time
 * spent in zone i between frames: the maximum-likelihood first-order rate
 * when frames are close (K dt << 1; see docs/models.md). */
#ifndef GRANSIM_DEMDATA_ZONES_H
#define GRANSIM_DEMDATA_ZONES_H
#include <stddef.h>

#include "gransim/error.h"

typedef struct {
  double t;        /* s */
  size_t n;        /* particles */
  long *id;        /* n particle ids (unique within a frame) */
  double *x, *v;   /* 3n positions [m], velocities [m/s] */
  double *volume;  /* n particle volumes [m^3], or NULL (unknown: hold-ups in numbers only) */
} gs_zone_frame;

typedef struct {
  size_t nframe, cap;
  gs_zone_frame *f;
  char source[512]; /* what they were read from, for the fragment's header */
} gs_zone_frames;

typedef struct {
  size_t k;
  double L, U;            /* feature scales [m], [m/s] */
  double velocity_weight; /* w: velocities count as w v / U */
  double silhouette;      /* simplified silhouette of the clustering */
  double sil_by_k[16];    /* silhouette per k tried (index k), 0 where not tried */
  size_t kmin, kmax;      /* the range tried (kmin == kmax: k given) */
  size_t nsample;         /* points clustered (particle-frames) */
  double *centre;         /* k * 3: mean position [m] */
  double *holdup;         /* k: mean particles per frame */
  double *solid;          /* k: mean solid volume per frame [m^3], or NULL */
  double *speed;          /* k: mean particle speed |v| [m/s] */
  double *rate, *rate_sd; /* k * k: K_ij [1/s] (row = from) and its standard error sqrt(n_ij)/T_i */
  double *crossings;      /* k * k: n_ij */
  double *exposure;       /* k: T_i, particle-seconds in zone i between frames */
  double max_rate_dt;     /* largest K_i dt (total out of a zone), the estimator's bias scale */
  size_t *label;          /* nsample: zone of each particle-frame, frame by frame */
} gs_zones;

/* Append a frame (taken over: its arrays are owned by frames from here). */
int gs_zone_frames_add(gs_zone_frames *fr, gs_zone_frame *f, gs_error *err);
/* Read LIGGGHTS/LAMMPS dump files (one snapshot each, columns id x y z vx
 * vy vz, and radius or diameter if present); t = TIMESTEP * time_step. */
int gs_zone_frames_read_dump(gs_zone_frames *fr, const char *path, double time_step, gs_error *err);
/* Leave out the frames before t0 (the fill settling, the start-up). */
void gs_zone_frames_keep_from(gs_zone_frames *fr, double t0);
/* Order the frames by time; refuse fewer than two or a repeated time. */
int gs_zone_frames_sort(gs_zone_frames *fr, gs_error *err);
void gs_zone_frames_free(gs_zone_frames *fr);

/* Cluster into k zones (k = 0: the k in [2, kmax] of largest silhouette). */
int gs_zones_identify(const gs_zone_frames *fr, size_t k, size_t kmax, double velocity_weight,
                      unsigned long seed, gs_zones *z, gs_error *err);
/* The case fragment: compartments, the exchange rates, velocities, hold-ups. */
int gs_zones_write(const gs_zones *z, const gs_zone_frames *fr, const char *path, gs_error *err);
void gs_zones_free(gs_zones *z);
#endif
