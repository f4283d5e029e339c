#!/usr/bin/env bash
# The main job. Does all set-up on a fresh Debian 12 machine and builds `hof`. Then:
#  - with a display ($DISPLAY or $WAYLAND_DISPLAY set): opens the window on the bundled medium
#    liver (physiologic tissue: co-rotational FEM, E = 5.4 kPa, nu = 0.45). Left-drag onto the
#    liver: the mouse is the stylus; the wheel or W/S presses it in;
#  - without one (or with --headless): runs a headless haptic session on it (the default probe
#    presses it about 1.5 cm deep at about 1 N) and writes the report to out/report/
#    (telemetry, summary, final state, plots). Deterministic (virtual time): the same report
#    every run.
# Usage: scripts/run.sh [--headless] [PROJECT.hof] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
headless=0
if [ "${1:-}" = "--headless" ]; then headless=1; shift; fi
project=${1:-examples/liver-palpation-medium-fem.hof}
out=${2:-out/report}
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target hof
if [ "$headless" = 0 ] && [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]; then
  exec build/release/bin/hof gui "$project"
fi
build/release/bin/hof run "$project" --headless --deterministic --seconds 4 --out "$out"
echo "Report: $out/summary.json, $out/telemetry.csv, plots $out/*.png"
