/* The fuzzing harnesses' common part.  Each fuzz_<reader>.c defines
 * LLVMFuzzerTestOneInput, which hands one input to one of gransim's readers
 * and frees what it built: a reader must answer any input with GS_OK or a
 * gransim error, never a crash, a hang, a leak or undefined behaviour.
 * Built with GRANSIM_FUZZ=ON the harness is a libFuzzer target; otherwise
 * replay.c supplies a main that feeds it the files of the checked-in corpus
 * (the CTest test fuzz_corpus). */
#ifndef GRANSIM_FUZZ_HARNESS_H
#define GRANSIM_FUZZ_HARNESS_H

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Most readers take a path: the input is written to a file of this process
 * (under $TMPDIR or /tmp, named with the suffix, e.g. ".stl") whose path is
 * returned (static storage; NULL if it cannot be written). */
const char *fuzz_input_file(const uint8_t *data, size_t size, const char *suffix);
/* The input as a NUL-terminated string (malloc'd; NULL when out of memory). */
char *fuzz_input_text(const uint8_t *data, size_t size);

#endif
