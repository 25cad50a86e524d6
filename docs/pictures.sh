#!/usr/bin/env bash
# Renders the README's pictures with arbvis itself (opaque PNGs, as a browser shows them).
# Run from the repository root: bash docs/pictures.sh
set -euo pipefail
cargo build --release --quiet
arbvis=target/release/arbvis
out=docs/pictures
mkdir -p "$out"
for demo in v3o2-sum v3o2-product cellproj-planar cellproj-spherical cellproj-spherical-precise \
            clip-sphere clip-mesh; do
  "$arbvis" render --demo "$demo" -o "$out/$demo.png"
done
for demo in splats-section splats-section-precise; do
  "$arbvis" render --demo "$demo" --size 1200x675 -o "$out/$demo.png"
done
# Real data (data/, which travels with the clone).
for s in f3 f3-minimal icbm152 post autzen bunny bracket-volume post-volume; do
  "$arbvis" render "scenes/data/$s.toml" -o "$out/data-$s.png"
done
"$arbvis" render scenes/data/bracket-volume.toml --fidelity faithful -o "$out/data-bracket-volume-faithful.png"
"$arbvis" render scenes/data/f3-minimal.toml --size 640x480 --legend --axes -o "$out/data-f3-figure.png"
"$arbvis" render scenes/data/bracket-layers.toml --legend -o "$out/data-bracket-layers.png"
"$arbvis" render scenes/data/f3-horizon.toml --legend -o "$out/data-f3-horizon.png"
"$arbvis" render scenes/data/f3-interpretation.toml --legend --axes -o "$out/data-f3-interpretation.png"
"$arbvis" render scenes/data/f3-interpretation.toml --fidelity precise --legend --axes -o "$out/data-f3-interpretation-precise.png"
"$arbvis" render scenes/bench/cellproj-seed-volume.toml -o "$out/cellproj-seed-volume.png"
# The README's Python example (scripts/python-tests.sh makes target/python-venv).
if [ -x target/python-venv/bin/python ]; then
  (cd "$out" && ../../target/python-venv/bin/python -c '
import arbvis
scene = arbvis.Scene.demo("v3o2-sum")
scene["technique.opacity3d.primary.coefficients"] = [0.0, 0.0, 0.0, 0.0]
with arbvis.Renderer(scene) as renderer:
    arbvis.write_png("v3o2-sum-python.png", renderer.render())')
fi
# NASA's CFD meshes (`python3 benches/meshes.py nasa` downloads them into target/meshes).
if [ -f target/meshes/bluntfin.vtk ] && [ -f target/meshes/oxygen-post.vtk ]; then
  "$arbvis" render scenes/meshes/bluntfin-volume.toml -o "$out/nasa-bluntfin-volume.png"
  "$arbvis" render scenes/meshes/bluntfin-volume.toml --fidelity faithful \
    -o "$out/nasa-bluntfin-volume-faithful.png"
  "$arbvis" render scenes/meshes/oxygen-post-volume.toml -o "$out/nasa-oxygen-post-volume.png"
fi
# The outcrop cloud of the COPC bench (benches/points/copc.sh DIR writes DIR/outcrop.toml
# over 200 million points): OUTCROP=DIR bash docs/pictures.sh.
if [ -n "${OUTCROP:-}" ] && [ -f "$OUTCROP/outcrop.toml" ]; then
  "$arbvis" render "$OUTCROP/outcrop.toml" --size 1200x675 -o "$out/outcrop-copc.png"
fi
