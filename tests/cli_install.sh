# cmake --install into a temporary prefix puts the command, the shared and the
# static library, the headers, gransim.pc, the man page and bash completion in
# the GNUInstallDirs layout; a small C program built with
# `pkg-config --cflags --libs gransim` (and --static, against libgransim.a)
# runs a case through the installed library.
source "$(dirname "$0")/cli-lib.sh" "$@"
BUILD=$(dirname "$BIN")
[ -f "$BUILD/CMakeCache.txt" ] || fail "$BUILD is not the build folder of $BIN"
PREFIX=$WORK/prefix
run_rc 0 cmake --install "$BUILD" --prefix "$PREFIX"
libdir=$(sed -n 's/^CMAKE_INSTALL_LIBDIR:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
for f in bin/gransim "$libdir/libgransim.so" "$libdir/libgransim.a" "$libdir/pkgconfig/gransim.pc" \
         include/gransim/case.h include/gransim/run.h include/gransim/api.h include/gransim/version.h \
         share/man/man1/gransim.1 share/bash-completion/completions/gransim share/doc/gransim/LICENSE \
         share/doc/gransim/CHANGELOG.md; do
  [ -e "$PREFIX/$f" ] || fail "cmake --install left out $f"
done
run_rc 0 "$PREFIX/bin/gransim" --version
# the completion script loads and offers subcommands and a subcommand's options
out=$(bash -c 'source "$1"; COMP_WORDS=(gransim sw); COMP_CWORD=1; _gransim; echo "${COMPREPLY[*]}"' _ \
      "$PREFIX/share/bash-completion/completions/gransim")
[ "$out" = sweep ] || fail "completion of 'gransim sw' gave '$out', expected 'sweep'"
out=$(bash -c 'source "$1"; COMP_WORDS=(gransim dem --ch); COMP_CWORD=2; _gransim; echo "${COMPREPLY[*]}"' _ \
      "$PREFIX/share/bash-completion/completions/gransim")
[ "$out" = --check ] || fail "completion of 'gransim dem --ch' gave '$out', expected '--check'"
# the man page formats without warnings
if command -v groff >/dev/null; then
  groff -man -Tutf8 -ww -z "$PREFIX/share/man/man1/gransim.1" 2>"$WORK/groff" || fail "groff failed on gransim.1"
  [ ! -s "$WORK/groff" ] || { cat "$WORK/groff" >&2; fail "groff warns about gransim.1"; }
fi

# A library user: validate and run a one-axis constant-kernel aggregation case
# given as text; the number halves to N0 / (1 + beta0 N0 t / 2) = 1/2 at t = 2.
cat >"$WORK/user.c" <<'C'
#include <gransim/api.h>
#include <gransim/version.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
int main(int argc, char **argv) {
  const char *text =
      "grid: {axes: [{name: solid, type: geometric, min: 1.0e-5, ratio: 1.25, cells: 80, zero_first: true}]}\n"
      "initial: {type: exponential, number: 1, mean: 0.01}\n"
      "mechanisms: [{type: aggregation, kernel: {type: constant, beta0: 1}}]\n"
      "output: {end: 2, count: 3}\n";
  gs_error err = {0};
  gs_api_case *c = gs_api_case_from_text(text, "user-case", &err);
  if (!c) { fprintf(stderr, "%s\n", err.msg); return 1; }
  /* a misspelt key is refused with the file name and key in the message */
  if (gs_api_case_set(c, "output.ned", "3", &err) == 0 || !strstr(err.msg, "ned")) {
    fprintf(stderr, "setting output.ned should have failed: %s\n", err.msg);
    return 1;
  }
  if (gs_api_case_run(c, argv[1], 0, &err)) { fprintf(stderr, "%s\n", err.msg); return 1; }
  gs_api_case_free(c);
  /* summary.csv: "time [s],compartment,M0 [1],..."; one row per output time */
  char file[4096], line[4096];
  snprintf(file, sizeof file, "%s/summary.csv", argv[1]);
  FILE *fp = fopen(file, "r");
  double m0[3] = {0};
  int rows = 0;
  if (!fp || !fgets(line, sizeof line, fp) || strncmp(line, "time [s],compartment,M0", 23)) return 1;
  while (rows < 3 && fgets(line, sizeof line, fp)) {
    double t;
    int comp;
    if (sscanf(line, "%lf,%d,%lf", &t, &comp, &m0[rows]) == 3) rows++;
  }
  fclose(fp);
  printf("gransim %s: M0 %.6f %.6f %.6f\n", gs_version(), m0[0], m0[1], m0[2]);
  (void)argc;
  return fabs(m0[2] - 0.5) < 1e-4 && fabs(m0[1] - 2.0 / 3.0) < 1e-4 ? 0 : 1;
}
C
export PKG_CONFIG_PATH=$PREFIX/$libdir/pkgconfig
cflags=$(pkg-config --cflags gransim) || fail "pkg-config does not find gransim in $PKG_CONFIG_PATH"
[[ $cflags == *"-I$PREFIX/"*include* ]] || fail "pkg-config --cflags gives '$cflags'"
# a sanitized build (scripts/test-sanitize): the user's program is sanitized
# too, since ASan's runtime must come first in a process that loads the library
san=""
! grep -q '^GRANSIM_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt" || san="-fsanitize=address,undefined"
# shared: the program finds libgransim.so by its run path
run_rc 0 cc -std=c11 $san -o "$WORK/user-shared" "$WORK/user.c" $cflags $(pkg-config --libs gransim) -lm \
  -Wl,-rpath,"$PREFIX/$libdir"
ldd "$WORK/user-shared" >"$WORK/ldd" # (not piped into grep -q: pipefail and SIGPIPE)
grep -q "$PREFIX/$libdir/libgransim.so" "$WORK/ldd" || fail "user-shared is not linked to the installed libgransim.so"
run_rc 0 "$WORK/user-shared" "$WORK/out-shared"
stdout_has "M0 1.000000 0.666667 0.500000"
# static: libgransim.a and everything pkg-config --static names
libs=$(pkg-config --static --libs gransim)
[[ $libs == *-lsundials_cvode* ]] || fail "pkg-config --static --libs lacks SUNDIALS: '$libs'"
static_libs=${libs//-lgransim/-l:libgransim.a}
run_rc 0 cc -std=c11 $san -o "$WORK/user-static" "$WORK/user.c" $cflags $static_libs -lm
ldd "$WORK/user-static" >"$WORK/ldd"
! grep -q libgransim "$WORK/ldd" || fail "user-static should not need libgransim.so"
run_rc 0 "$WORK/user-static" "$WORK/out-static"
stdout_has "M0 1.000000 0.666667 0.500000"

# the Python package, installed, finds the installed library by itself
pydir=$(sed -n 's/^GRANSIM_PYTHON_INSTALL_DIR:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
python=$(sed -n 's/^GRANSIM_PYTHON:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
[ -f "$PREFIX/$pydir/gransim/__init__.py" ] || fail "the Python package is not in $PREFIX/$pydir"
# (a sanitized library in an unsanitized interpreter: its runtimes preloaded,
# and the interpreter's own leaks not ours to judge)
preload=()
[ -z "$san" ] || preload=(LD_PRELOAD="$(cc -print-file-name=libasan.so) $(cc -print-file-name=libubsan.so)"
                          ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0")
(cd "$WORK" && env -u GRANSIM_LIBRARY "${preload[@]}" PYTHONPATH="$PREFIX/$pydir" "$python" -c '
import gransim, os, sys
lib = gransim._lib._name
assert os.path.realpath(lib).startswith(os.path.realpath(sys.argv[1])), lib
print(gransim.version())' "$PREFIX") >"$WORK/stdout" 2>"$WORK/stderr" || { show_output; fail "the installed Python package does not load its library"; }
echo "cli_install: ok"
