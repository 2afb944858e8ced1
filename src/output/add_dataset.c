/* Datasets added to a published result.h5 by a layer above (the coupling's
 * /coupling/cycles), with their units and dimensions attributes. */
#include <hdf5.h>

#include "gransim/output.h"
#include "output/h5_setup.h"
#include "output/units.h"

int gs_output_add_dataset(const char *h5_path, const char *path, int rank, const unsigned long long *dims,
                          const double *data, const char *units, const char *dimensions, gs_error *err) {
  gs_h5_setup();
  hid_t f = H5Fopen(h5_path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) return gs_error_set(err, GS_EIO, "%s: cannot open to add %s", h5_path, path);
  hsize_t d[8];
  for (int i = 0; i < rank && i < 8; i++) d[i] = (hsize_t)dims[i];
  /* written again on a resume that publishes again */
  if (H5Lexists(f, path, H5P_DEFAULT) > 0) H5Ldelete(f, path, H5P_DEFAULT);
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  hid_t sp = H5Screate_simple(rank, d, NULL);
  hid_t ds = sp < 0 ? -1 : H5Dcreate2(f, path, H5T_IEEE_F64LE, sp, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  int ok = ds >= 0 && H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (ds >= 0) H5Dclose(ds);
  if (ok) ok = gs_h5_describe(f, path, units, dimensions) >= 0;
  if (sp >= 0) H5Sclose(sp);
  H5Pclose(lcpl);
  if (H5Fclose(f) < 0) ok = 0;
  return ok ? GS_OK : gs_error_set(err, GS_EIO, "%s: cannot write the dataset %s", h5_path, path);
}
