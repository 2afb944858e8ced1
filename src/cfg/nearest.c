/* Nearest-word hints: see nearest.h. */
#include "cfg/nearest.h"

#include <ctype.h>
#include <string.h>

/* Keys and names are short: longer words are compared by their first
 * characters only, which is enough to tell a typo. */
#define MAXLEN 64

size_t gs_edit_distance(const char *a, const char *b) {
  size_t la = strlen(a), lb = strlen(b);
  if (la > MAXLEN) la = MAXLEN;
  if (lb > MAXLEN) lb = MAXLEN;
  size_t d[MAXLEN + 1][MAXLEN + 1];
  for (size_t i = 0; i <= la; i++) d[i][0] = i;
  for (size_t j = 0; j <= lb; j++) d[0][j] = j;
  for (size_t i = 1; i <= la; i++)
    for (size_t j = 1; j <= lb; j++) {
      const int ca = tolower((unsigned char)a[i - 1]), cb = tolower((unsigned char)b[j - 1]);
      size_t best = d[i - 1][j - 1] + (ca != cb);
      if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
      if (i > 1 && j > 1 && ca == tolower((unsigned char)b[j - 2]) && tolower((unsigned char)a[i - 2]) == cb &&
          d[i - 2][j - 2] + 1 < best)
        best = d[i - 2][j - 2] + 1;
      d[i][j] = best;
    }
  return d[la][lb];
}

const char *gs_nearest_word(const char *word, const char *const *candidates, size_t n) {
  const char *best = NULL;
  size_t best_d = (size_t)-1;
  for (size_t i = 0; i < n; i++) {
    if (!candidates[i]) continue;
    if (!strcmp(word, candidates[i])) return NULL;
    const size_t d = gs_edit_distance(word, candidates[i]);
    if (d < best_d) best_d = d, best = candidates[i];
  }
  if (!best) return NULL;
  const size_t len = strlen(best) < strlen(word) ? strlen(best) : strlen(word);
  const size_t limit = len <= 4 ? 1 : 2;
  return best_d <= limit && best_d < len ? best : NULL;
}
