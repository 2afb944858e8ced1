/* gransim — the version of the library.
 *
 * The number is the CMake project version (semantic versioning, CHANGELOG.md);
 * a build from a git checkout adds `git describe` in parentheses, so that a
 * result file names the commit it came from. */
#ifndef GRANSIM_VERSION_H
#define GRANSIM_VERSION_H

#ifdef __cplusplus
extern "C" {
#endif

/* "0.2.0" */
const char *gs_version_number(void);
/* "0.2.0 (v0.2.0-3-gabc1234-dirty)", or the number alone outside a git checkout */
const char *gs_version(void);

#ifdef __cplusplus
}
#endif
#endif
