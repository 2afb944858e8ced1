/* The impeller of a bowl-and-impeller granulator (generate: {type:
 * impeller}): a cylindrical hub on the bowl's axis (z) with n straight
 * blades, each a box of the given length (from the hub's surface to the
 * tip), height and thickness, turned about its own radial centre line by the
 * pitch angle (0: a vertical flat paddle, 45: the usual pitched blade) and
 * set `clearance` above the bowl's bottom (z = 0 at the origin).  Hub and
 * blades are separate closed boxes and cylinders that overlap, each with
 * outward normals; a blade's inner end lies inside the hub, so no particle
 * can reach the faces hidden there.  With `rpm` the impeller turns about z
 * through the origin (counter-clockwise seen from above for rpm > 0), from
 * `start` on: a granulator's bed settles with the impeller at rest. */
#include <math.h>
#include <string.h>

#include "dem/dem_case.h"
#include "dem/dem_generate.h"

/* A box [x0, x1] x [-hy, hy] x [-hz, hz] turned by pitch about x, lifted by
 * zc, turned by phi about z and moved to origin: 12 outward triangles. */
static int blade(gs_dem_tris *out, double x0, double x1, double hy, double hz, double pitch, double zc,
                 double phi, const double origin[3], gs_error *err) {
  double p[8][3];
  const double cp = cos(pitch), sp = sin(pitch), cf = cos(phi), sf = sin(phi);
  for (int k = 0; k < 8; k++) {
    double x = k & 1 ? x1 : x0, y = k & 2 ? hy : -hy, z = k & 4 ? hz : -hz;
    double y1 = cp * y - sp * z, z1 = sp * y + cp * z + zc;
    p[k][0] = origin[0] + cf * x - sf * y1;
    p[k][1] = origin[1] + sf * x + cf * y1;
    p[k][2] = origin[2] + z1;
  }
  /* the six faces as corner quadruples, counter-clockwise seen from outside */
  static const int face[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  int rc = GS_OK;
  for (int f = 0; f < 6 && !rc; f++) {
    const int *q = face[f];
    if (!(rc = gs_dem_tris_add(out, p[q[0]], p[q[1]], p[q[2]], err)))
      rc = gs_dem_tris_add(out, p[q[0]], p[q[2]], p[q[3]], err);
  }
  return rc;
}

static int build(gs_cfg_node *n, gs_dem_tris *out, gs_dem_gen_motion *motion, gs_error *err) {
  long nb, seg;
  double L, b, th, pitch, dh, hh, c, rpm, start, origin[3];
  const double zero[3] = {0, 0, 0};
  int rc = gs_cfg_long_range(n, "blades", 0, 3, 1, 64, &nb, err);
  if (!rc) rc = gs_cfg_double_range(n, "blade_length", 1, 0, 0, 1, HUGE_VAL, 0, &L, err);
  if (!rc) rc = gs_cfg_double_range(n, "blade_height", 1, 0, 0, 1, HUGE_VAL, 0, &b, err);
  if (!rc) rc = gs_cfg_double_range(n, "blade_thickness", 0, 0.1 * b, 0, 1, HUGE_VAL, 0, &th, err);
  if (!rc) rc = gs_cfg_double_range(n, "pitch", 0, 45, 0, 0, 90, 1, &pitch, err);
  if (!rc) rc = gs_cfg_double_range(n, "hub_diameter", 1, 0, 0, 1, HUGE_VAL, 0, &dh, err);
  if (!rc) rc = gs_cfg_double_range(n, "clearance", 1, 0, 0, 0, HUGE_VAL, 0, &c, err);
  if (!rc) rc = gs_cfg_double_opt(n, "rpm", 0, &rpm, err);
  if (!rc) rc = gs_cfg_double_range(n, "start", 0, 0, 0, 0, HUGE_VAL, 0, &start, err);
  if (!rc && rpm == 0 && gs_cfg_get(n, "start"))
    rc = gs_cfg_fail(gs_cfg_get(n, "start"), err, "a start time needs an impeller that turns (rpm)");
  if (!rc) rc = gs_cfg_long_range(n, "segments", 0, 24, 6, 1024, &seg, err);
  if (!rc) rc = gs_dem_case_vec3(n, "origin", 0, zero, origin, err);
  if (rc) return rc;
  const double a = pitch * M_PI / 180, rh = 0.5 * dh;
  /* the blade's cross-section after the pitch: its half extents across (y)
   * and up (z) */
  const double ey = 0.5 * b * sin(a) + 0.5 * th * cos(a), ez = 0.5 * b * cos(a) + 0.5 * th * sin(a);
  if (!rc) rc = gs_cfg_double_range(n, "hub_height", 0, 2 * ez, 2 * ez * (1 - 1e-12), 0, HUGE_VAL, 0, &hh, err);
  if (rc) return rc;
  /* the blade's inner end hides inside the hub (the polygon's inscribed
   * circle), which needs a hub wider than the pitched blade */
  const double inner = rh * cos(M_PI / (double)seg), x0 = 0.5 * rh;
  if (!(hypot(x0, ey) < inner))
    return gs_cfg_fail(gs_cfg_get(n, "hub_diameter"), err,
                       "the hub (diameter %g m) is narrower than the pitched blade (%g m across): the blades' "
                       "inner ends would stick out of it; widen the hub or thin the blades", dh, 2 * ey);
  double r[4] = {0, rh, rh, 0}, z[4] = {c, c, c + hh, c + hh};
  rc = gs_dem_tris_revolve(out, r, z, 4, (int)seg, origin, err);
  for (long k = 0; k < nb && !rc; k++)
    rc = blade(out, x0, rh + L, 0.5 * th, 0.5 * b, a, c + ez, 2 * M_PI * (double)k / (double)nb, origin, err);
  if (rc) return rc;
  if (rpm != 0) {
    motion->rotating = 1;
    memcpy(motion->origin, origin, sizeof motion->origin);
    motion->axis[0] = motion->axis[1] = 0;
    motion->axis[2] = 1;
    motion->omega = rpm * 2 * M_PI / 60;
    motion->start = start;
  }
  return GS_OK;
}

const gs_dem_generator gs_dem_gen_impeller = {
    .name = "impeller",
    .summary = "hub with pitched straight blades on the bowl's axis, turning at rpm",
    .build = build,
};
