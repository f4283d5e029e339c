#!/usr/bin/env bash
# HoF as others get it (tests/CMakeLists.txt runs this as ctest's install.* tests):
#   install  - cmake --install into a temporary prefix, moved elsewhere (relocatable); the
#              installed hof runs a bundled example; every public header compiles on its own
#              and none includes a detail/ one; hof.pc links a program
#   outoftree - examples/out-of-tree configured and built against that prefix alone, and run
#   deb      - the Debian package: its control fields, its files, and hof --version from it
# Usage: install_test.sh install|outoftree|deb BUILD_DIR SOURCE_DIR
set -euo pipefail
what=$1
build=$(cd "$2" && pwd)
source=$(cd "$3" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "install_test ($what): $*" >&2; exit 1; }

install_moved() {
  cmake --install "$build" --prefix "$work/first" >/dev/null
  # Relocatable: everything must work from wherever the tree is moved to.
  mv "$work/first" "$work/prefix"
  echo "$work/prefix"
}

case $what in
install)
  prefix=$(install_moved)
  version=$("$prefix/bin/hof" --version)
  [[ $version == "hof $(sed -n 's/^project(HoF VERSION \([0-9.]*\).*/\1/p' "$source/CMakeLists.txt")" ]] || fail "hof --version says '$version'"
  for f in lib/libhof_core.a lib/libhof_app.a include/hof/core/version.h include/hof/coupling/session.h \
           lib/cmake/HoF/HoFConfig.cmake lib/cmake/HoF/HoFConfigVersion.cmake lib/cmake/HoF/HoFTargets.cmake \
           lib/pkgconfig/hof.pc share/hof/examples/liver-palpation-simple.hof share/hof/data/models/liver-simple.msh \
           share/doc/HoF/README.md share/doc/HoF/CHANGELOG.md; do
    [[ -e $prefix/$f ]] || fail "not installed: $f"
  done
  [[ -z $(find "$prefix/include" -path '*/detail*') ]] || fail "a detail/ header is installed"
  if grep -rn '#include "hof/[a-z]*/detail/' "$prefix/include"; then fail "a public header includes a detail/ one"; fi
  # The installed program runs an installed example (its models found beside it).
  (cd "$work" && "$prefix/bin/hof" run "$prefix/share/hof/examples/liver-palpation-simple.hof" --deterministic --quiet \
     --seconds 1 --out "$work/report") || fail "the installed hof could not run an installed example"
  grep -q '"contact_time_s"' "$work/report/summary.json" || fail "no summary written"
  # Every public header compiles on its own (included first in a translation unit).
  headers=$(cd "$prefix/include" && find hof -name '*.h' | sort)
  count=0
  for h in $headers; do
    printf '#include <%s>\nint main() { return 0; }\n' "$h" > "$work/h_$count.cpp"
    count=$((count + 1))
  done
  ls "$work"/h_*.cpp | xargs -P "$(nproc)" -I{} sh -c \
    'g++ -std=c++23 -fsyntax-only -I"$1/include" -isystem /usr/include/eigen3 "$2" 2>"$2.log" || { echo "$2"; sed -n 1p "$2"; head -5 "$2.log"; exit 255; }' \
    _ "$prefix" {} || fail "a public header does not compile on its own (above)"
  echo "install: $count public headers compile on their own"
  # hof.pc: a program compiled and linked with pkg-config alone.
  cat > "$work/pc.cpp" <<'CPP'
#include <hof/core/version.h>
#include <hof/mesh/liver_generator.h>
#include <cstdio>
int main() {
  auto liver = hof::mesh::generate_liver(hof::mesh::LiverResolution::kSimple);
  if (!liver) return 1;
  std::printf("%s %zu\n", hof::kVersion, liver->tets.size());
  return liver->tets.empty() ? 1 : 0;
}
CPP
  export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
  [[ $(pkg-config --modversion hof) == "${version#hof }" ]] || fail "pkg-config --modversion hof"
  # shellcheck disable=SC2046
  g++ "$work/pc.cpp" -o "$work/pc" $(pkg-config --cflags hof) $(pkg-config --static --libs hof) || fail "hof.pc does not link a program"
  "$work/pc" | grep -q "${version#hof } " || fail "the pkg-config program did not run"
  echo "install: OK ($prefix)"
  ;;
outoftree)
  prefix=$(install_moved)
  cmake -S "$source/examples/out-of-tree" -B "$work/probe" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" \
        -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON -DCMAKE_BUILD_TYPE=Release >/dev/null || fail "configure"
  grep -q "HoF_DIR:PATH=$prefix/lib/cmake/HoF" "$work/probe/CMakeCache.txt" || fail "HoF found elsewhere than the install"
  cmake --build "$work/probe" >/dev/null || fail "build"
  out=$("$work/probe/vibrating_probe") || fail "run: $out"
  echo "$out"
  grep -q "the probe vibrated on" <<<"$out" || fail "unexpected output"
  # A component HoF does not have is refused by find_package.
  mkdir -p "$work/bad"
  printf 'cmake_minimum_required(VERSION 3.25)\nproject(bad CXX)\nfind_package(HoF 0.2 REQUIRED COMPONENTS teleportation)\n' > "$work/bad/CMakeLists.txt"
  if cmake -S "$work/bad" -B "$work/bad/build" -DCMAKE_PREFIX_PATH="$prefix" >"$work/bad.log" 2>&1; then fail "an unknown component was accepted"; fi
  grep -q "no component 'teleportation'" "$work/bad.log" || fail "the unknown component is not named: $(cat "$work/bad.log")"
  ;;
deb)
  (cd "$build" && cpack -G DEB -B "$work/deb" >/dev/null) || fail "cpack"
  deb=$(ls "$work"/deb/hof_*_amd64.deb) || fail "no hof_<version>_amd64.deb"
  info=$(dpkg-deb --info "$deb")
  for field in "Package: hof" "Architecture: amd64" "Depends:"; do grep -q "$field" <<<"$info" || fail "control has no '$field'"; done
  depends=$(sed -n 's/^ Depends: //p' <<<"$info")
  for package in libtbb12 libpugixml1v5 libglfw3 libepoxy0 libsodium23 libspnav0 libtet1.5 libcholmod3 libsuitesparse-dev gnuplot-nox; do
    grep -q "$package" <<<"$depends" || fail "Depends lacks $package: $depends"
  done
  contents=$(dpkg-deb --contents "$deb")
  for f in ./usr/bin/hof ./usr/lib/libhof_core.a ./usr/include/hof/core/version.h ./usr/lib/cmake/HoF/HoFConfig.cmake \
           ./usr/share/hof/examples/liver-palpation-simple.hof ./usr/share/hof/data/models/liver-simple.msh; do
    grep -q " $f\$" <<<"$(awk '{print " "$6}' <<<"$contents")" || fail "the package lacks $f"
  done
  dpkg-deb -x "$deb" "$work/root"
  "$work/root/usr/bin/hof" --version | grep -q "^hof " || fail "hof --version from the package"
  # The Python module from the package, when it was built: imported by Debian's python3.
  if [[ -d $work/root/usr/lib/python3/dist-packages/hof ]]; then
    grep -q "python3-numpy" <<<"$depends" || fail "the Python module is packaged but python3-numpy is not a dependency"
    PYTHONPATH=$work/root/usr/lib/python3/dist-packages /usr/bin/python3 -c \
      "import hof; m = hof.mesh.generate_liver('simple'); assert len(m.tets) > 0" || fail "the packaged Python module"
  fi
  echo "deb: $(basename "$deb"): Depends: $depends"
  ;;
*) fail "unknown test $what" ;;
esac
