#!/usr/bin/env bash
# Issue 19's measurements on a large synthetic survey (never run by the tests): generate
# a SEG-Y survey with arbvis's writer, measure the disk's read speed beside the
# conversion, convert it, view it (open to first picture, turning frames against the 256³
# demo, time to full quality, memory), score the LOD policies on a window, render its
# picture, and delete the survey and the store.
#
#   bash benches/store/run.sh [DIR] [SURVEY_GB]
#
# SURVEY_GB defaults to the largest survey (up to 20 GB) that leaves 15 GB of the disk
# free with its store beside it (the store of amplitude + envelope is about 1.9 times the
# survey, amplitude alone about 0.92 times, lz4 included). When the disk cannot hold the
# survey with an amplitude + envelope store, only amplitude is converted (and drawn). PROFILE=debug uses the dev profile (arbvis at opt-level 1,
# dependencies at 2) instead of a release build. Output: DIR/run.log; the picture goes to
# docs/pictures/store-survey.png.
set -euo pipefail
DIR=${1:-/work/store-bench}
mkdir -p "$DIR"
LOG="$DIR/run.log"
exec > >(tee "$LOG") 2>&1
PROFILE=${PROFILE:-release}
if [ "$PROFILE" = release ]; then
    cargo build --release --no-default-features --bin arbvis --example store_bench
else
    cargo build --bin arbvis --example store_bench
fi
BIN=target/$PROFILE/arbvis
SB=target/$PROFILE/examples/store_bench
avail=$(df --output=avail -B1 "$DIR" | tail -1)
keep=$((15 * 1024 * 1024 * 1024))
if [ -n "${2:-}" ]; then
    gb=$2
else
    gb=$(( (avail - keep) * 10 / 35 / 1000000000 ))
    [ "$gb" -gt 20 ] && gb=20
fi
[ "$gb" -ge 1 ] || { echo "not enough disk: $avail bytes free, 15 GB must stay free"; exit 1; }
if [ $(( (avail - keep) / 1000000000 )) -ge $(( gb * 29 / 10 )) ]; then envelope=yes; else envelope=no; fi
echo "== envelope converted too: $envelope"
# ns = 1000 samples; inlines = crosslines from the size.
side=$(python3 -c "import math; print(int(math.sqrt($gb * 1e9 / (240 + 4000))))")
echo "== disk before: $(df -h "$DIR" | tail -1)"
echo "== survey: 1000 samples x $side crosslines x $side inlines (~$gb GB)"
SGY="$DIR/survey.sgy"
STORE="$DIR/survey.zarr"
rm -rf "$STORE"
/usr/bin/time -f "generate: %e s, peak %M KB" $SB generate "$SGY" 1000 "$side" "$side"
ls -l "$SGY"
# The disk's own read speed, the file out of the page cache first (dd's nocache drops a
# file's cached pages; O_DIRECT bypasses the cache).
dd if="$SGY" iflag=nocache count=0 status=none
echo "== disk read speed (O_DIRECT, 16 MiB blocks):"
dd if="$SGY" of=/dev/null bs=16M iflag=direct 2>&1 | tail -1
dd if="$SGY" iflag=nocache count=0 status=none
echo "== convert (amplitude only):"
/usr/bin/time -f "convert: %e s wall, %U s user, %S s system, peak %M KB" \
    $BIN convert "$SGY" "$STORE" --attributes none
du -sh "$STORE"
if [ "$envelope" = yes ]; then
    rm -rf "$STORE"
    dd if="$SGY" iflag=nocache count=0 status=none
    echo "== convert (amplitude + envelope):"
    /usr/bin/time -f "convert: %e s wall, %U s user, %S s system, peak %M KB" \
        $BIN convert "$SGY" "$STORE" --attributes envelope
    du -sh "$STORE"
fi
echo "== disk with survey and store: $(df -h "$DIR" | tail -1)"
echo "== view (1280x800 window; interactive frames at half the side):"
/usr/bin/time -f "view: %e s, peak %M KB" $SB view "$STORE" 1280x800
echo "== view, precise (the ray caster through the page table):"
/usr/bin/time -f "view: %e s, peak %M KB" $SB view "$STORE" 1280x800 precise
echo "== LOD error on a 192³ window:"
$SB error "$STORE" 192
echo "== the picture:"
# Time down the screen (the v3o2-sum demo's camera), the whole survey with a margin, the
# strong reflections (amplitude beyond ±0.6 of ±1.5) opaque, the rest clear.
cat > "$DIR/survey.toml" <<TOML
size = [1024, 768]
background = [0.0, 0.0, 0.0, 1.0]
[camera]
rotation = [0.326506, -0.092296, -0.701057, 0.627211]
zoom = 0.85
[technique.opacity3d]
slices = 384
[technique.opacity3d.primary]
volume = { store = "survey.zarr" }
attribute = "amplitude"
quantize = { range = [-1.5, 1.5] }
table = { builtin = "seismic", alpha = [[0.0, 0.9], [0.3, 0.0], [0.7, 0.0], [1.0, 0.9]] }
[technique.opacity3d.store]
gpu_memory = "1G"
TOML
if [ "$envelope" = yes ]; then
    cat >> "$DIR/survey.toml" <<TOML
[technique.opacity3d.secondary]
volume = { store = "survey.zarr" }
attribute = "envelope"
table = { builtin = "inferno", alpha = [[0.0, 0.0], [0.6, 0.0], [1.0, 0.5]] }
coefficients = [0.6, 0.6, 0.6, 0.6]
TOML
fi
/usr/bin/time -f "render: %e s, peak %M KB" $BIN render "$DIR/survey.toml" -o docs/pictures/store-survey.png --stats | tail -4
rm -rf "$SGY" "$STORE"
echo "== disk after cleanup: $(df -h "$DIR" | tail -1)"
