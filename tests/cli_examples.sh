# Every example in examples/ runs from a fresh `git clone` of the source tree
# (so a file the examples need that is not in git, or one outside the
# repository, fails here), at its full length: all take seconds. A case with a
# top-level `coupling:` section runs with `gransim couple`, one with `dem:` with
# `gransim dem`, the rest with `gransim run`; each result is then plotted
# with the clone's own plotting script.  An example that takes minutes says
# `# cli_examples: quick variant in tests/NAME.sh` and runs there instead.
source "$(dirname "$0")/cli-lib.sh" "$@"
command -v git >/dev/null || fail "git is not installed"
git -C "$SRC" rev-parse --git-dir >/dev/null 2>&1 || fail "$SRC is not a git checkout: cannot test a fresh clone"
git clone -q "$SRC" "$WORK/clone" || fail "git clone $SRC"
n=0
for case in "$WORK"/clone/examples/*.yaml; do
  name=$(basename "$case" .yaml)
  # an example of minutes runs in a quick variant in the test it names
  grep -q '^# cli_examples: quick variant in tests/' "$case" && continue
  if grep -q '^coupling:' "$case"; then cmd=couple
  elif grep -q '^dem:' "$case"; then cmd=dem
  else cmd=run
  fi
  # from another folder: paths inside the case are relative to the case file
  ( cd "$WORK" && "$BIN" "$cmd" "$case" --out "$WORK/out/$name" --quiet ) >"$WORK/$name.log" 2>&1 ||
    { cat "$WORK/$name.log" >&2; fail "examples/$name.yaml: gransim $cmd failed in a fresh clone"; }
  GRANSIM_PLOT_SCRIPT=$WORK/clone/scripts/gransim-plot "$BIN" plot "$WORK/out/$name" --format png >"$WORK/$name.plot" 2>&1 ||
    { cat "$WORK/$name.plot" >&2; fail "examples/$name.yaml: gransim plot failed"; }
  [ -s "$WORK/out/$name/plots/$( [ $cmd = dem ] && echo collisions || echo sizes).png" ] ||
    fail "examples/$name.yaml: no plots"
  n=$((n + 1))
done
[ "$n" -ge 5 ] || fail "only $n examples found"
echo "cli_examples: $n examples ran and plotted from a fresh clone"
