# Every complete example in docs/case-files.md passes `gransim check`.
# Examples are the fenced code blocks whose first line is "# example: NAME";
# they are written to NAME in one directory (so a case finds its table files).
source "$(dirname "$0")/cli-lib.sh" "$@"

doc=$SRC/docs/case-files.md
[ -f "$doc" ] || fail "$doc not found"
ex=$WORK/examples
mkdir -p "$ex"
awk -v dir="$ex" '
  /^```/ { if (inblock) { if (out) close(out); out = ""; inblock = 0 } else { inblock = 1; first = 1 }; next }
  inblock && first { first = 0; if ($0 ~ /^# example: [A-Za-z0-9._-]+$/) out = dir "/" $3 }
  out { print > out }' "$doc"

n=0
for f in "$ex"/*.yaml; do
  [ -e "$f" ] || break
  run_rc 0 "$BIN" check "$f"
  stdout_has "$(basename "$f"): valid"
  n=$((n + 1))
done
[ "$n" -ge 3 ] || fail "found $n complete examples in $doc, expected at least 3"

echo "cli_doc_examples: ok ($n examples)"
