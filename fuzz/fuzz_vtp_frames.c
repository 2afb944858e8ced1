/* Harness: a particle frame of the embedded DEM (.vtp), the reader of gransim compartments. */
#include "demdata/vtp_frames.h"
#include "harness.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_input_file(data, size, ".vtp");
  gs_error err = {0};
  gs_zone_frames fr = {0};
  if (path) gs_vtp_frame_read(&fr, path, 0.5, &err);
  gs_zone_frames_free(&fr);
  return 0;
}
