#!/usr/bin/env bash
# The remote bench (issue 45), never part of the tests:
#
#   bash benches/remote/run.sh DIR [SAMPLES INLINES CROSSLINES] [POINTS]
#
# In DIR: a survey store (default 1000 samples x 1100 inlines x 1200 crosslines of float32,
# a 5.3 GB SEG-Y made by benches/store/make_segy.py, converted with amplitude alone: a
# store of 5.5 GB) and a COPC cloud (default 200 M points from
# benches/points/outcrop.py, as benches/points/copc.sh makes it; reused from DIR when
# there). Both are served by the tests' Range server (tests/servers/range_server.py)
# behind this bench's link (proxy.py: 25 ms each way, 50 MB/s), and drawn from local disk
# and over the link with an empty cache, interleaved by farm-bench:
#   - the store by `store_bench first` (the viewer's path: open to first picture, the
#     coarsest level standing in, then on to the full picture; what was fetched by each);
#   - the cloud by `arbvis render` (its first picture is its whole cut);
# then over the link again on the cache the first run filled (a second process: 304s
# only; what it reads from the cache is what the picture reads). Release build first:
#   cargo build --release --no-default-features --bin arbvis --example store_bench
# Everything it prints goes to DIR/remote-bench.log too.
set -euo pipefail
dir=${1:?usage: run.sh DIR [SAMPLES INLINES CROSSLINES] [POINTS]}
ns=${2:-1000}; ni=${3:-1100}; nx=${4:-1200}; points=${5:-200000000}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=$root/target/release/arbvis
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
exec > >(tee "$dir/remote-bench.log") 2>&1
echo "# $(date -u +%FT%TZ) $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GB; store $ns x $ni x $nx, $points points"

if [ ! -f "$dir/survey.zarr/zarr.json" ]; then
  [ -f "$dir/survey.sgy" ] || python3 "$root/benches/store/make_segy.py" "$dir/survey.sgy" "$ns" "$ni" "$nx"
  /usr/bin/time -f "convert the survey: %e s" "$bin" convert "$dir/survey.sgy" "$dir/survey.zarr" --attributes none
  rm -f "$dir/survey.sgy"
fi
if [ ! -f "$dir/outcrop.copc.laz" ]; then
  [ -f "$dir/outcrop.las" ] || python3 "$root/benches/points/outcrop.py" "$points" "$dir/outcrop.las"
  /usr/bin/time -f "convert the cloud: %e s" "$bin" convert "$dir/outcrop.las" "$dir/outcrop.copc.laz"
  rm -f "$dir/outcrop.las"
fi
echo "store: $(du -sb "$dir/survey.zarr" | cut -f1) bytes; cloud: $(stat -c %s "$dir/outcrop.copc.laz") bytes"

# The server, then the link in front of it; both stopped when this script ends.
coproc SERVER { exec python3 "$root/tests/servers/range_server.py" "$dir"; }
read -r server_port <&"${SERVER[0]}"
coproc LINK { exec python3 "$here/proxy.py" "$server_port" --delay-ms 25 --mbps 50; }
read -r link_port <&"${LINK[0]}"
trap 'kill $SERVER_PID $LINK_PID 2>/dev/null || true' EXIT
url=http://127.0.0.1:$link_port
echo "link: 127.0.0.1:$link_port (25 ms each way, 50 MB/s) to the server on :$server_port"

sed "s|OUTCROP|$dir/outcrop.copc.laz|" "$root/benches/points/outcrop.toml" >"$dir/copc-local.toml"
sed "s|OUTCROP|$url/outcrop.copc.laz|" "$root/benches/points/outcrop.toml" >"$dir/copc-remote.toml"
sb=$root/target/release/examples/store_bench

echo "## store: open to first picture (the viewer's path: the coarsest level first) and on to"
echo "## the full picture (1024x768, 512 MB of bricks), over the link with an empty cache vs"
echo "## from local disk, interleaved; each run's own lines in $dir/store-runs.log"
rm -f "$dir/store-runs.log"
ARBVIS_CACHE_DIR="$dir/cache-bench" farm-bench -n 3 --timeout 1200 \
  --vs "sh -c 'exec $sb first $dir/survey.zarr 1024x768 >>$dir/store-runs.log 2>&1'" \
  -- sh -c "rm -rf $dir/cache-bench && exec $sb first $url/survey.zarr 1024x768 >>$dir/store-runs.log 2>&1"
cat "$dir/store-runs.log"
echo "## store: again over the link, a new process on the cache the last run filled"
ARBVIS_CACHE_DIR="$dir/cache-bench" "$sb" first "$url/survey.zarr" 1024x768
echo "root brick's chunk: $(stat -c %s "$dir/survey.zarr/level_5/amplitude/c/0/0/0") bytes"

echo "## copc: first picture (arbvis render, 1600x900, 1 M points) over the link with an"
echo "## empty cache vs from local disk"
ARBVIS_CACHE_DIR="$dir/cache-bench" farm-bench -n 5 --timeout 900 \
  --vs "$bin render $dir/copc-local.toml -o $dir/copc-local.png" \
  -- sh -c "rm -rf $dir/cache-bench && exec $bin render $dir/copc-remote.toml -o $dir/copc-remote.png"
rm -rf "$dir/cache-copc"
curl -s "http://127.0.0.1:$server_port/_reset" >/dev/null
echo "## copc: the counts, first picture"
ARBVIS_CACHE_DIR="$dir/cache-copc" "$bin" render "$dir/copc-remote.toml" -o "$dir/copc-remote.png" --stats 2>&1 |
  grep -E "fetched|wrote|COPC|points drawn"
echo "server: $(curl -s "http://127.0.0.1:$server_port/_stats")"
curl -s "http://127.0.0.1:$server_port/_reset" >/dev/null
echo "## copc: again, a new process on that cache (what it reads from the cache is what the picture reads)"
ARBVIS_CACHE_DIR="$dir/cache-copc" "$bin" render "$dir/copc-remote.toml" -o "$dir/copc-again.png" 2>&1 | grep -E "fetched"
echo "server: $(curl -s "http://127.0.0.1:$server_port/_stats")"
python3 "$here/same_pixels.py" "$dir/copc-local.png" "$dir/copc-remote.png"
