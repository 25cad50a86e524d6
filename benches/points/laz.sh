#!/usr/bin/env bash
# LAZ to COPC at the speed of the decoder (issue 42, item 4), never part of the tests:
#
#   bash benches/points/laz.sh DIR [POINTS ...]      (default: 50000000 200000000)
#
# For each size, in DIR (about 46 bytes a point: the LAZ, the same points as LAS, and the
# COPC outputs): an airborne-lidar-like cloud of point format 7 written by make_laz.py as
# LAZ (laspy + lazrs, chunks of 50,000) and as LAS (skipped when present); then
# `arbvis convert` of each to COPC under /usr/bin/time (points a second, peak memory), and
# the floor: laspy + lazrs decoding the same LAZ alone, one thread (Lazrs) and on every
# core (LazrsParallel), best of three. Release build (cargo build --release
# --no-default-features first). Everything it prints goes to DIR/laz-bench.log too.
set -euo pipefail
dir=${1:?usage: laz.sh DIR [POINTS ...]}
shift
sizes=("${@:-50000000 200000000}")
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=$root/target/release/arbvis
mkdir -p "$dir"
exec > >(tee "$dir/laz-bench.log") 2>&1
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GB"
for n in ${sizes[@]}; do
  laz=$dir/p$n.laz
  las=$dir/p$n.las
  [ -f "$laz" ] || python3 "$here/make_laz.py" "$laz" "$n"
  [ -f "$las" ] || python3 "$here/make_laz.py" "$las" "$n" --las
  for input in "$laz" "$las"; do
    out=$dir/out.copc.laz
    rm -f "$out"
    cat "$input" > /dev/null   # in the page cache, as the floor's file is
    /usr/bin/time -f "%e %U %S %M" -o "$dir/time.txt" "$bin" convert "$input" "$out" > /dev/null
    read -r wall user sys kb < "$dir/time.txt"
    awk -v f="$(basename "$input")" -v n="$n" -v w="$wall" -v u="$user" -v s="$sys" -v k="$kb" \
      'BEGIN { printf "convert %-16s %9d points in %7.2f s = %5.2f M points/s (CPU %.1f s), peak %.2f GB\n", f, n, w, n / w / 1e6, u + s, k / 1048576 }'
  done
  rm -f "$dir/out.copc.laz" "$dir/time.txt"
  python3 "$here/laz_floor.py" "$laz" --chunked 2000000
done
