/* The bowl of a bowl-and-impeller granulator (generate: {type: bowl}): a
 * cylindrical vessel of inner diameter D and inner height H with walls of
 * thickness t, its inner bottom rim at z = 0 of the bowl's frame (axis z,
 * gravity along -z), flat or dished (a spherical cap of depth h below the
 * rim), open at the top or closed by a lid.  The wall is modelled as the
 * solid it is, so the mesh is closed with normals pointing out of the metal:
 * on the inner surface they point into the bowl, towards the particles.  The
 * cup is one surface of revolution; with a lid the hollow vessel is two (the
 * outside and the cavity).  The source paper gives no dimensions (De et al.
 * 2025, Fig. 4 only): docs/models.md, "The generated bowl and impeller". */
#include <math.h>
#include <stdlib.h>

#include "dem/dem_case.h"
#include "dem/dem_generate.h"

#define MAX_PROFILE 1024

/* The inner bottom from the axis outward: (0, -h) to (R, 0) on the cap, or
 * the flat disc's centre and rim; returns the number of points. */
static size_t bottom(double R, double h, int rings, double dz, double *r, double *z) {
  if (h <= 0) {
    r[0] = 0, z[0] = dz;
    r[1] = R, z[1] = dz;
    return 2;
  }
  /* the sphere through the rim and the lowest point; h < R keeps the cap
   * shallower than a hemisphere */
  const double rho = (R * R + h * h) / (2 * h), th = asin(R / rho);
  for (int j = 0; j <= rings; j++) {
    double a = th * j / rings;
    r[j] = rho * sin(a);
    z[j] = rho - h - rho * cos(a) + dz;
  }
  r[rings] = R, z[rings] = dz; /* exactly on the rim, where the side starts */
  return (size_t)rings + 1;
}

static int build(gs_cfg_node *n, gs_dem_tris *out, gs_dem_gen_motion *motion, gs_error *err) {
  (void)motion;
  double D, H, t, h, origin[3];
  long seg, rings;
  int lid, dished;
  static const char *const kinds[] = {"flat", "dished", NULL};
  const double zero[3] = {0, 0, 0};
  int rc = gs_cfg_double_range(n, "diameter", 1, 0, 0, 1, HUGE_VAL, 0, &D, err);
  if (!rc) rc = gs_cfg_double_range(n, "height", 1, 0, 0, 1, HUGE_VAL, 0, &H, err);
  if (!rc) rc = gs_cfg_double_range(n, "wall_thickness", 0, 0.02 * D, 0, 1, HUGE_VAL, 0, &t, err);
  if (!rc) rc = gs_cfg_bool_opt(n, "lid", 0, &lid, err);
  if (!rc) rc = gs_cfg_enum_opt(n, "bottom", kinds, 0, &dished, err);
  if (!rc && dished) rc = gs_cfg_double_range(n, "dish_depth", 1, 0, 0, 1, 0.5 * D, 1, &h, err);
  else if (!rc) h = 0;
  if (!rc && !dished && gs_cfg_get(n, "dish_depth"))
    rc = gs_cfg_fail(gs_cfg_get(n, "dish_depth"), err, "only a dished bottom has a depth (bottom: dished)");
  if (!rc) rc = gs_cfg_long_range(n, "segments", 0, 48, 8, 1024, &seg, err);
  if (!rc) rc = gs_cfg_long_range(n, "dish_rings", 0, 8, 2, 64, &rings, err);
  if (!rc) rc = gs_dem_case_vec3(n, "origin", 0, zero, origin, err);
  if (rc) return rc;
  const double R = 0.5 * D, Ro = R + t;
  double r[MAX_PROFILE], z[MAX_PROFILE];
  size_t np = 0;
  /* outer bottom (the inner one shifted down by t, so the bottom is t thick
   * everywhere along z), then the outer side */
  np = bottom(R, h, (int)rings, -t, r, z);
  if (h > 0) r[np] = Ro, z[np++] = -t;
  else r[np - 1] = Ro;
  if (!lid) {
    /* the cup: up the outside, across the rim, down the inside, in along the
     * inner bottom to the axis (counter-clockwise: the metal on the left) */
    r[np] = Ro, z[np++] = H;
    r[np] = R, z[np++] = H;
    double br[MAX_PROFILE / 2], bz[MAX_PROFILE / 2];
    size_t nb = bottom(R, h, (int)rings, 0, br, bz);
    for (size_t j = nb; j-- > 0;) r[np] = br[j], z[np++] = bz[j];
    return gs_dem_tris_revolve(out, r, z, np, (int)seg, origin, err);
  }
  /* the hollow vessel: its outside, then the cavity turned the other way */
  r[np] = Ro, z[np++] = H + t;
  r[np] = 0, z[np++] = H + t;
  rc = gs_dem_tris_revolve(out, r, z, np, (int)seg, origin, err);
  if (rc) return rc;
  np = 0;
  r[np] = 0, z[np++] = H;
  r[np] = R, z[np++] = H;
  double br[MAX_PROFILE / 2], bz[MAX_PROFILE / 2];
  size_t nb = bottom(R, h, (int)rings, 0, br, bz);
  for (size_t j = nb; j-- > 0;) r[np] = br[j], z[np++] = bz[j];
  return gs_dem_tris_revolve(out, r, z, np, (int)seg, origin, err);
}

const gs_dem_generator gs_dem_gen_bowl = {
    .name = "bowl",
    .summary = "cylindrical bowl of a given diameter and height, flat or dished bottom, optional lid",
    .build = build,
};
