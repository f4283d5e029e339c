#!/usr/bin/env bash
# Regenerates the screenshots of README.md and docs/user-guide.md through the window's own
# scripted path (hof gui --script) in a virtual X server: nothing is drawn by hand.
# Usage: scripts/screenshots.sh   (writes docs/images/*.png)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target hof
mkdir -p docs/images
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/press.txt" <<'ACTIONS'
# the liver at rest, then pressed 15 mm deep by the mouse stylus
wait 1
screenshot docs/images/gui-liver.png
mouse 800 330 0.015
wait 2.5
screenshot docs/images/gui-press.png
set graphics@colorBy displacement
set graphics@renderMode shaded+wireframe
wait 0.5
screenshot docs/images/gui-displacement.png
show mechanics
wait 0.3
screenshot docs/images/gui-mechanics.png
quit
ACTIONS
cat > "$work/stress.txt" <<'ACTIONS'
# the scene tree's edits: a Neo-Hookean liver (E 5.4 kPa, nu 0.45) with a stiff region,
# pressed, coloured by von Mises stress
show mechanics
region Liver sphere 0 0 0.04 0.025 54000
replace mechanics/Liver/FEM TetrahedronHyperelasticityFEMForceField materialName=NeoHookean "ParameterSet=1862.0689655172414 18000"
set graphics@colorBy stress
mouse 835 330 0.015
wait 3
screenshot docs/images/gui-stress.png
quit
ACTIONS
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/liver-palpation-medium-fem.hof \
  --size 1280x720 --script "$work/press.txt"
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/liver-palpation-medium-fem.hof \
  --size 1280x720 --script "$work/stress.txt"
cat > "$work/needle.txt" <<'ACTIONS'
# the scripted insert-hold-extract of examples/needle-liver.hof: the needle through the
# capsule, then relaxing; the Needle panel
wait 4.6
screenshot docs/images/gui-needle.png
show needle
wait 2.6
screenshot docs/images/gui-needle-editor.png
quit
ACTIONS
cat > "$work/cube.txt" <<'ACTIONS'
wait 3.4
screenshot docs/images/gui-needle-cube.png
quit
ACTIONS
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/needle-liver.hof \
  --size 1280x720 --script "$work/needle.txt"
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/needle-cube.hof \
  --size 1280x720 --script "$work/cube.txt"
cat > "$work/tumour.txt" <<'ACTIONS'
# the palpation sweep of examples/liver-tumour-palpation.hof, pressing above the tumour
wait 9.5
screenshot docs/images/gui-tumour.png
quit
ACTIONS
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/liver-tumour-palpation.hof \
  --size 1280x720 --script "$work/tumour.txt"
cat > "$work/contacts.txt" <<'ACTIONS'
# organs resting on each other: a capsule on the mouse stylus, turned and pressed onto the
# liver; the contacts between the bodies drawn (points, force arrows); the Tool panel
wait 1
contacts on
tool capsule 0.08 0.006
rotate 0 1 0 60
show tool
mouse 800 330 -0.01
wait 0.5
mouse 800 330 0.01
wait 2
screenshot docs/images/gui-tool-contacts.png
quit
ACTIONS
xvfb-run -a -s "-screen 0 1280x720x24" build/release/bin/hof gui examples/organs-in-contact.hof \
  --size 1280x720 --script "$work/contacts.txt"
build/release/bin/hof run examples/liver-tumour-palpation.hof --headless --deterministic --quiet --out "$work/tumour-run"
cp "$work/tumour-run/palpation.png" docs/images/tumour-palpation.png
# The needle's force against depth, as `hof run` plots it.
build/release/bin/hof run examples/needle-liver.hof --headless --deterministic --quiet --out "$work/needle-run"
cp "$work/needle-run/force_vs_depth.png" docs/images/needle-force-vs-depth.png
cp "$work/needle-run/needle_force_over_time.png" docs/images/needle-force-over-time.png
echo "screenshots: docs/images/gui-liver.png gui-press.png gui-displacement.png gui-mechanics.png gui-stress.png" \
     "gui-needle.png gui-needle-editor.png gui-needle-cube.png needle-force-vs-depth.png needle-force-over-time.png" \
     "gui-tumour.png tumour-palpation.png gui-tool-contacts.png"
