#!/usr/bin/env bash
# The main job. Does all set-up on a fresh Debian 12 machine, builds `hof`, then generates
# the bundled standard liver models (simple, coarse, medium, fine) into out/models/ and prints
# their statistics. Usage: scripts/run.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target hof
hof=build/release/bin/hof
mkdir -p "$out/models"
for resolution in simple coarse medium fine; do
  "$hof" mesh generate liver --resolution "$resolution" -o "$out/models/liver-$resolution.msh"
done
for resolution in simple coarse medium fine; do
  "$hof" mesh info "$out/models/liver-$resolution.msh"
  echo
done
echo "Models (Gmsh v4.1 volume + OBJ surface) are in $out/models/"
