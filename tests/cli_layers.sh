# The folders under src/ are layers (docs/architecture.md): a file may include
# the headers of its own layer and of the layers below it, never above.  The
# public headers in include/gransim/ belong to the layer of their module.
# Fails naming every include that points upward.
#
# Usage: bash cli_layers.sh GRANSIM_BINARY SOURCE_DIR
set -euo pipefail
SRC=$2
cd "$SRC"
# lowest first; one line per layer: folder, then the public headers it owns
LAYERS="core error parallel threads version
cfg cfg
grid grid
kernel kernel
pbm pbm distribution
ode integrator
case case
output output
run run
swa swa
demdata dem_data
dem dem
cfd cfd
liggghts liggghts
study study
couple couple
api api
cli"
declare -A rank_of_folder rank_of_header
r=0
while read -r folder headers; do
  rank_of_folder[$folder]=$r
  for h in $headers; do rank_of_header[$h]=$r; done
  r=$((r + 1))
done <<<"$LAYERS"
bad=0
check() { # check FILE RANK: every include of FILE at or below RANK
  local file=$1 rank=$2 inc target trank
  while read -r inc; do
    case $inc in
      gransim/*) target=${inc#gransim/}; target=${target%.h}; trank=${rank_of_header[$target]:-} ;;
      */*) target=${inc%%/*}; trank=${rank_of_folder[$target]:-} ;;
      *) continue ;;
    esac
    if [ -z "$trank" ]; then
      echo "cli_layers: $file includes $inc, which belongs to no layer" >&2
      bad=1
    elif [ "$trank" -gt "$rank" ]; then
      echo "cli_layers: $file includes $inc from a layer above its own" >&2
      bad=1
    fi
  done < <(sed -n 's/^#include "\([^"]*\)".*/\1/p' "$file")
}
for dir in src/*/; do
  folder=$(basename "$dir")
  [ -n "${rank_of_folder[$folder]:-}" ] || { echo "cli_layers: src/$folder is not a layer" >&2; bad=1; continue; }
  for f in "$dir"*.c "$dir"*.h; do [ -e "$f" ] && check "$f" "${rank_of_folder[$folder]}"; done
done
for f in include/gransim/*.h; do
  h=$(basename "$f" .h)
  [ -n "${rank_of_header[$h]:-}" ] || { echo "cli_layers: $f belongs to no layer" >&2; bad=1; continue; }
  check "$f" "${rank_of_header[$h]}"
done
[ $bad -eq 0 ] || exit 1
echo "cli_layers: every include points down the layers"
