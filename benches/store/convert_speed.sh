#!/usr/bin/env bash
# Conversion speed against what the disk can do (issue 26, item 5; never run by the tests).
# Generates a 2.08 GB IEEE-float SEG-Y (1000 samples x 700 x 700 traces), then, three
# rounds each, interleaved, each run after `sync` with the previous output removed:
#   - the disk's read speed (dd, O_DIRECT, 16 MiB blocks) and its durable write speed for
#     a store (`cp -r` of an amplitude store, then `sync`): the floor a conversion that
#     writes that store can reach;
#   - `arbvis convert` of amplitude alone and of amplitude + envelope (the default), with
#     the default compression (lz4) and with zstd level 1 (the default before).
#
#   bash benches/store/convert_speed.sh [DIR]     (SETTLE=seconds between runs, 61 default)
set -euo pipefail
DIR=${1:-/work/convert-speed}
mkdir -p "$DIR"
cargo build --release --no-default-features --bin arbvis --example store_bench
BIN=$PWD/target/release/arbvis
SURVEY=$DIR/s.sgy
[ -f "$SURVEY" ] || target/release/examples/store_bench generate "$SURVEY" 1000 700 700
bytes=$(stat -c %s "$SURVEY")
cat "$SURVEY" > /dev/null   # the survey in the page cache, as a conversion rereads it
rm -rf "$DIR/floor.zarr" "$DIR/out"
"$BIN" convert "$SURVEY" "$DIR/floor.zarr" --attributes none > /dev/null 2>&1
echo "survey: $bytes bytes; store of amplitude: $(du -sb "$DIR/floor.zarr" | cut -f1) bytes"
# A file system without a journal (this machine's ext4) skips, on every file it creates,
# each inode freed in the last 60 s (ext4's recently_deleted): removing the last run's
# 2,400 chunk files and converting at once spent 30 % of the conversion in that scan
# (perf, 2026-11-27), a cost no first conversion pays. So each run waits the window out.
timed() { # LABEL COMMAND...: run after sync, print seconds and MB/s of the survey
    local label=$1; shift
    rm -rf "$DIR/out" "$DIR/copy"; sync; sleep "${SETTLE:-61}"
    local s e
    s=$(date +%s.%N); "$@" > /dev/null 2>&1; e=$(date +%s.%N)
    awk -v l="$label" -v s="$s" -v e="$e" -v b="$bytes" \
        'BEGIN { printf "%-34s %6.2f s  %5.0f MB/s of the survey\n", l, e - s, b / (e - s) / 1e6 }'
}
for round in 1 2 3; do
    echo "round $round"
    dd if="$SURVEY" of=/dev/null bs=16M iflag=direct 2>&1 | tail -1 | sed 's/^/  disk read: /'
    timed "  copy of the store + sync (floor)" sh -c "cp -r '$DIR/floor.zarr' '$DIR/copy' && sync"
    timed "  convert, amplitude, lz4" "$BIN" convert "$SURVEY" "$DIR/out" --attributes none
    timed "  convert, amplitude, zstd:1" "$BIN" convert "$SURVEY" "$DIR/out" --attributes none --compression zstd
    timed "  convert, amplitude + envelope, lz4" "$BIN" convert "$SURVEY" "$DIR/out"
    timed "  convert, amplitude + envelope, zstd" "$BIN" convert "$SURVEY" "$DIR/out" --compression zstd
done
rm -rf "$DIR/out" "$DIR/copy" "$DIR/floor.zarr"
