#!/usr/bin/env bash
# The main job. Does all set-up on a fresh Debian 12 machine, builds `hof`, then runs a
# headless haptic session on the bundled medium liver (physiologic tissue: co-rotational FEM,
# E = 5.4 kPa, nu = 0.45; the default probe presses it about 1.5 cm deep at about 1 N) and
# writes its report to out/report/ (telemetry, summary, final state, plots). Deterministic (virtual time): the same report every run.
# Usage: scripts/run.sh [PROJECT.hof] [OUT_DIR]   (the GUI is a later issue)
set -euo pipefail
cd "$(dirname "$0")/.."
project=${1:-examples/liver-palpation-medium-fem.hof}
out=${2:-out/report}
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target hof
build/release/bin/hof run "$project" --headless --deterministic --seconds 4 --out "$out"
echo "Report: $out/summary.json, $out/telemetry.csv, plots $out/*.png"
