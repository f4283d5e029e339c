#!/usr/bin/env bash
# Installs every Debian 12 package HoF needs to build, test and run.
# Idempotent: when everything is present it does nothing and prints nothing.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libtet1.5-dev libpugixml-dev libglfw3-dev libimgui-dev libepoxy-dev
  libfmt-dev nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev libtbb-dev libsuitesparse-dev
  gnuplot-nox xvfb xauth libgl1-mesa-dri libspnav-dev libsodium-dev
  clang-16 libclang-rt-16-dev clang-format-14
  # The BLAS that CHOLMOD's supernodal factorisation runs on (Debian's alternatives select it
  # for libblas.so.3; with the reference BLAS the direct solver is 5× slower): serial, so that
  # it starts no threads beside TBB's. docs/performance.md, "The sparse direct solver".
  libopenblas0-serial
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-scipy
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${#missing[@]} package(s): ${missing[*]}" >&2
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done" >&2
