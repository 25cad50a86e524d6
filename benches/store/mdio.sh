#!/usr/bin/env bash
# MDIO at scale (never run by the tests): a SEG-Y survey written with numpy
# (benches/store/make_segy.py, not arbvis's writer), ingested by mdio-python
# (`pip install multidimio`; its worker processes), then opened by arbvis as it is (first
# picture, turning frames against the 256³ demo, memory), given its levels in place by
# `arbvis convert DATASET`, and opened again. Deletes what it made at the end.
#
#   bash benches/store/mdio.sh [DIR] [INLINES] [CROSSLINES]
#
# Defaults: /work/mdio-bench, 1100 x 1100 traces of 1000 samples (5.1 GB).
set -euo pipefail
DIR=${1:-/work/mdio-bench}
NI=${2:-1100}
NX=${3:-1100}
mkdir -p "$DIR"
exec > >(tee "$DIR/run.log") 2>&1
cargo build --release --no-default-features --bin arbvis --example store_bench
BIN=$PWD/target/release/arbvis
SB=$PWD/target/release/examples/store_bench
SGY="$DIR/survey.sgy"
MDIO="$DIR/survey.mdio"
rm -rf "$MDIO"
echo "== SEG-Y with numpy: 1000 samples x $NI inlines x $NX crosslines"
/usr/bin/time -f "make_segy: %e s, peak %M KB" python3 benches/store/make_segy.py "$SGY" 1000 "$NI" "$NX"
ls -l "$SGY"
cat > "$DIR/ingest.py" <<'PY'
import sys
from mdio import segy_to_mdio
from mdio.builder.template_registry import get_template
from segy.standards import get_segy_standard
from segy.schema import HeaderField

def main():
    spec = get_segy_standard(1.0).customize(trace_header_fields=[
        HeaderField(name="inline", byte=189, format="int32"),
        HeaderField(name="crossline", byte=193, format="int32"),
        HeaderField(name="cdp_x", byte=181, format="int32"),
        HeaderField(name="cdp_y", byte=185, format="int32"),
    ])
    segy_to_mdio(segy_spec=spec, mdio_template=get_template("PostStack3DTime"),
                 input_path=sys.argv[1], output_path=sys.argv[2], overwrite=True)

if __name__ == "__main__":
    main()
PY
echo "== mdio-python ingests it:"
/usr/bin/time -f "segy_to_mdio: %e s wall, %U s user, %S s system, peak %M KB" python3 "$DIR/ingest.py" "$SGY" "$MDIO"
du -sh "$MDIO"
echo "== arbvis inspect:"
$BIN inspect "$MDIO"
echo "== arbvis views it as it is (one level; 1280x800; interactive frames at half the side):"
/usr/bin/time -f "view: %e s, peak %M KB" $SB view "$MDIO" 1280x800
echo "== arbvis convert, in place (levels, ranges, envelope beside MDIO's arrays):"
/usr/bin/time -f "convert: %e s wall, %U s user, %S s system, peak %M KB" $BIN convert "$MDIO"
du -sh "$MDIO"
echo "== arbvis views it with its levels:"
/usr/bin/time -f "view: %e s, peak %M KB" $SB view "$MDIO" 1280x800
rm -rf "$SGY" "$MDIO"
