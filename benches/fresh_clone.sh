#!/usr/bin/env bash
# The README's fresh-clone measurements, in the order a newcomer runs the README: a clone of
# this checkout's HEAD in a temporary folder, then the main job cold, the tests (after it),
# and, after touching one technique file, its rebuild and that technique's tests; each step
# timed, `target/` measured. Logs beside the clone.
set -u
d=$(mktemp -d /tmp/fresh.XXXX) && git clone -q "$(cd "$(dirname "$0")/.." && pwd)" "$d" && cd "$d" || exit 1
echo "clone $d at $(git log --oneline | head -1)"
uptime
s=$(date +%s); date -u +%H:%M:%S
cargo run -q --no-default-features -- render --demo v3o2-sum -o v3o2-sum.png --stats > "$d.main.log" 2>&1; rc=$?
e=$(date +%s); echo "main job cold: rc=$rc $((e-s)) s"; tail -3 "$d.main.log"
du -sh target
uptime
s=$(date +%s); date -u +%H:%M:%S
bash scripts/test.sh > "$d.tests.log" 2>&1; rc=$?
e=$(date +%s); echo "tests after the main job: rc=$rc $((e-s)) s"; date -u +%H:%M:%S
grep -E "^test result" "$d.tests.log" | awk '{s+=$4; f+=$6} END {print "Rust passed", s, "failed", f}'
grep -E "^[0-9]+ passed" "$d.tests.log" | tail -1
grep -E "Finished .test. profile" "$d.tests.log" | head -2
du -sh target
uptime
printf '\n/// Touched for the rebuild measurement.\npub fn touched_for_timing() {}\n' >> crates/arbvis-techniques/src/techniques/splats/renderer.rs
s=$(date +%s)
cargo test --workspace --no-run -q > "$d.rebuild.log" 2>&1; rc=$?
e=$(date +%s); echo "rebuild after touching splats/renderer.rs: rc=$rc $((e-s)) s"
s=$(date +%s)
cargo test -q --workspace --test it splats > "$d.splats.log" 2>&1; rc=$?
e=$(date +%s); echo "then the splats tests (cargo test --workspace --test it splats): rc=$rc $((e-s)) s"
grep -E "^test result" "$d.splats.log"
uptime
