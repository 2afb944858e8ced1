/* The nearest word to a misspelt one, for "did you mean ...?" hints. */
#ifndef GRANSIM_CFG_NEAREST_H
#define GRANSIM_CFG_NEAREST_H

#include <stddef.h>

/* Edit distance of a and b: insertions, deletions, substitutions and swaps
 * of two neighbouring characters each count 1 (optimal string alignment,
 * Damerau 1964), ignoring case. */
size_t gs_edit_distance(const char *a, const char *b);

/* Of the n candidates, the one nearest to word if it is near enough to be a
 * plausible misspelling (at most 1 edit for words of up to 4 characters, 2
 * for longer ones, never the whole word); NULL otherwise or if word is one of
 * them.  The first of equally near candidates wins. */
const char *gs_nearest_word(const char *word, const char *const *candidates, size_t n);

#endif
