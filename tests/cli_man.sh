# The man page (docs/gransim.1) and the bash completion
# (scripts/gransim-completion.bash) know every subcommand and every option
# that the subcommands' --help texts name.
source "$(dirname "$0")/cli-lib.sh" "$@"
MAN=$SRC/docs/gransim.1
COMPLETION=$SRC/scripts/gransim-completion.bash
# the man page's text with roff's escaped hyphens as plain ones
sed 's/\\-/-/g' "$MAN" >"$WORK/man.txt"
run_rc 0 "$BIN" --help
commands=$(sed -n 's/^  \([a-z][a-z-]*\) .*/\1/p' "$WORK/stdout" | sort -u)
[ -n "$commands" ] || fail "no commands found in gransim --help"
for cmd in $commands; do
  grep -q "^\.BI\? \"\?$cmd[ \"]" "$WORK/man.txt" || grep -q "^\.B $cmd$" "$WORK/man.txt" ||
    fail "the man page has no entry for the command '$cmd'"
  grep -q "^    $cmd)" "$COMPLETION" || fail "the bash completion does not know the command '$cmd'"
  [ "$cmd" = list ] && continue
  "$BIN" "$cmd" --help >"$WORK/help" 2>&1 || true
  # the options of the usage lines and of the option lists (not those named in prose)
  opts=$(grep -E -- '^(usage:| +\[| +--| +gransim )' "$WORK/help" | grep -o -- '--[A-Za-z][A-Za-z-]*' | sort -u || true)
  for o in $opts; do
    grep -q -- "$o\b" "$WORK/man.txt" || fail "the man page lacks '$o' of gransim $cmd"
    sed -n "/^    $cmd)/p" "$COMPLETION" | grep -q -- "[ \"]$o[ \"]" ||
      fail "the bash completion lacks '$o' of gransim $cmd"
  done
done
# the man page names the project's version
version=$(sed -n 's/^project(gransim VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")
grep -q "^\.TH GRANSIM 1 .* \"gransim $version\"" "$MAN" || fail "docs/gransim.1's .TH line does not name gransim $version"
echo "cli_man: ok"
