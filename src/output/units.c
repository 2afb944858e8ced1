/* SI units of the result files (units.h).  Grid coordinates and carried
 * quantities are volumes [m^3] (docs/case-files.md), so their means, totals
 * and ledger entries are too; numbers of particles are counts [1]. */
#include <stdio.h>
#include <string.h>

#include "output/units.h"

const char *gs_summary_unit(const char *column) {
  static const char *const fixed[][2] = {{"time", "s"}, {"M0", "1"},  {"M1", "m^3"}, {"M2", "m^6"},
                                         {"d10", "m"},  {"d50", "m"}, {"d90", "m"},
                                         {"porosity", "1"}, {"liquid_content", "1"}};
  if (!strncmp(column, "ci_", 3)) column += 3; /* a confidence half-width: the statistic's unit */
  for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
    if (!strcmp(column, fixed[i][0])) return fixed[i][1];
  if (!strncmp(column, "mean_", 5) || !strncmp(column, "total_", 6)) return "m^3";
  return NULL;
}

void gs_summary_header(const char *column, char *buf, size_t n) {
  const char *u = gs_summary_unit(column);
  if (u) snprintf(buf, n, "%s [%s]", column, u);
  else snprintf(buf, n, "%s", column);
}

herr_t gs_h5_str_attr(hid_t loc, const char *name, const char *value) {
  if (H5Aexists(loc, name) > 0 && H5Adelete(loc, name) < 0) return -1;
  hid_t type = H5Tcopy(H5T_C_S1);
  if (type < 0) return -1;
  hid_t space = H5Screate(H5S_SCALAR), attr = H5I_INVALID_HID;
  herr_t st = -1;
  if (space >= 0 && H5Tset_size(type, strlen(value) + 1) >= 0 &&
      H5Tset_strpad(type, H5T_STR_NULLTERM) >= 0 && H5Tset_cset(type, H5T_CSET_UTF8) >= 0 &&
      (attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT)) >= 0)
    st = H5Awrite(attr, type, value);
  if (attr >= 0 && H5Aclose(attr) < 0) st = -1;
  if (space >= 0) H5Sclose(space);
  H5Tclose(type);
  return st;
}

herr_t gs_h5_i64_attr(hid_t loc, const char *name, long long value) {
  hid_t space = H5Screate(H5S_SCALAR);
  if (space < 0) return -1;
  hid_t attr = H5Acreate2(loc, name, H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t st = attr >= 0 ? H5Awrite(attr, H5T_NATIVE_LLONG, &value) : -1;
  if (attr >= 0 && H5Aclose(attr) < 0) st = -1;
  H5Sclose(space);
  return st;
}

herr_t gs_h5_describe(hid_t loc, const char *path, const char *units, const char *dimensions) {
  hid_t d = H5Oopen(loc, path, H5P_DEFAULT);
  if (d < 0) return -1;
  herr_t st = gs_h5_str_attr(d, "units", units);
  if (st >= 0) st = gs_h5_str_attr(d, "dimensions", dimensions);
  if (H5Oclose(d) < 0) st = -1;
  return st;
}
