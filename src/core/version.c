/* The version strings: see include/gransim/version.h.  gransim_version.h is
 * generated at build time (cmake/version.cmake). */
#include "gransim/version.h"

#include "gransim_version.h"

const char *gs_version_number(void) { return GRANSIM_VERSION_NUMBER; }
const char *gs_version(void) { return GRANSIM_VERSION_TEXT; }
