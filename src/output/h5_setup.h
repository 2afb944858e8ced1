/* What every writer of HDF5 files in gransim needs from the library: the
 * set-up before first use, and the cause of the last failure in words. */
#ifndef GRANSIM_IO_H5_SETUP_H
#define GRANSIM_IO_H5_SETUP_H

#include <stddef.h>

/* Errors come back through gs_error (HDF5's own stack dump on stderr would
 * only duplicate and precede the message), and no clean-up at exit: after a
 * write failure (a full disk) H5Fclose fails and leaves the file half
 * closed, and HDF5 1.10's exit handler then crashed closing it again (status
 * 139 after the error message).  Every file is closed explicitly anyway.
 * The exit handler can only be refused before the library's first use, so
 * this comes before any other HDF5 call; later calls change nothing else. */
void gs_h5_setup(void);

/* The innermost description on HDF5's error stack (nearest the cause, e.g.
 * the system's message), "" when there is none; call it before the next
 * HDF5 call clears the stack. */
void gs_h5_cause(char *buf, size_t len);

#endif
