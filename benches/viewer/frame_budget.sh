#!/usr/bin/env bash
# The viewer's frame budget (issue 53): for each built-in demo and each scene of
# scenes/data and scenes/store, the time of a dragging frame (`measure 20 interactive`: the
# camera turned 2 degrees a frame at the interactive quality, `budget` unless QUALITY says
# otherwise) and of the full picture (`measure 3 full`), in a window of each SIZES, under
# Xvfb on the machine's GL (llvmpipe here), from the release build with the viewer.
#
#   bash benches/viewer/frame_budget.sh                    # every scene, 1280x800 and 1920x1080
#   SIZES=1280x800 bash benches/viewer/frame_budget.sh scenes/data/f3.toml --demo v3o2-sum
#
# Prints one table row a scene and size: ms per dragging frame, the scale the budget chose
# (1/N of each side), ms per full picture. Scenes whose data is not there (a store or COPC
# file made by `arbvis convert`, see each scene's `data_from`) are made first.
set -euo pipefail
cd "$(dirname "$0")/../.."
SIZES=${SIZES:-"1280x800 1920x1080"}
QUALITY=${QUALITY:-budget}
cargo build --release -q
bin=target/release/arbvis

if [ ! -e f3.zarr ]; then "$bin" convert data/seismic/f3.sgy f3.zarr >/dev/null; fi
if [ ! -e autzen.copc.laz ]; then "$bin" convert data/points/autzen_trim.laz autzen.copc.laz >/dev/null; fi

if [ "$#" -gt 0 ]; then
  scenes=("$@")
else
  scenes=()
  for d in $("$bin" render --demo 2>&1); do scenes+=("--demo" "$d"); done
  scenes+=(scenes/data/*.toml scenes/store/*.toml)
fi

display=:87
Xvfb "$display" -screen 0 2000x1200x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
trap 'kill $xvfb 2>/dev/null || true' EXIT
sleep 1

script=$(mktemp)
run() { # SIZE ARGS...: one row
  local size=$1; shift
  local w=${size%x*} h=${size#*x}
  printf 'set Interactive quality %s\nresize %s %s\nwait 10\nmeasure 20 interactive\nmeasure 3 full\n' \
    "$QUALITY" "$w" "$h" >"$script"
  local out
  out=$(DISPLAY=$display "$bin" view "$@" --script "$script" 2>&1) || { echo "| $* | $size | failed: $(echo "$out" | tail -1) |"; return; }
  local drag full scale
  drag=$(echo "$out" | sed -n 's/^measure interactive: .* \([0-9.]*\) ms per frame.*/\1/p')
  scale=$(echo "$out" | sed -n 's/^measure interactive: .*(scale 1\/\([0-9.]*\)).*/\1/p')
  full=$(echo "$out" | sed -n 's/^measure full: .* \([0-9.]*\) ms per frame.*/\1/p')
  echo "| $* | $size | $drag | 1/$scale | $full |"
}

echo "| scene | window | dragging frame (ms) | scale | full picture (ms) |"
echo "|---|---|---|---|---|"
for size in $SIZES; do
  i=0
  while [ $i -lt ${#scenes[@]} ]; do
    if [ "${scenes[$i]}" = "--demo" ]; then
      run "$size" --demo "${scenes[$((i + 1))]}"; i=$((i + 2))
    else
      run "$size" "${scenes[$i]}"; i=$((i + 1))
    fi
  done
done
rm -f "$script"
