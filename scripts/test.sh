#!/usr/bin/env bash
# Builds HoF (Release, warnings as errors) and runs every test. Does all set-up on a fresh
# Debian 12 machine: installs the packages first (quiet when they are there).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release
ctest --preset release
