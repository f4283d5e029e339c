#!/usr/bin/env bash
# Builds HoF and runs every test, as CI does. Does all set-up on a fresh Debian 12 machine:
# installs the packages first (quiet when they are there).
#
#   scripts/test.sh            what CI runs: the three passes below (about 25 minutes on two cores)
#   scripts/test.sh --release  pass 1 only (the quick loop while working)
#   scripts/test.sh --all      every pass at full length (about 50 minutes on two cores)
#
# Passes (docs/reliability.md):
#   1. release  g++ -O3, warnings as errors, every test
#   2. asan     clang 16, AddressSanitizer + UndefinedBehaviorSanitizer (-O1, HoF's assertions
#               on), every test but the window's (Mesa's software OpenGL is not ours to
#               sanitize); in CI also without the few that take minutes there (listed below);
#               then every libFuzzer target from the same build, HOF_FUZZ_SECONDS each
#               (3 in CI, 60 with --all)
#   3. tsan     clang 16, ThreadSanitizer on the threaded tests (lock-free queues, haptic loop, UDP device, sessions
#               with their simulation thread, several bodies, fault injection)
#
# The sanitizer trees are unity builds (CMAKE_UNITY_BUILD in their presets): Eigen's headers,
# parsed once per batch instead of once per file, made them 3-5x faster to build; the release
# tree compiles file by file, so a file that forgets an include still fails there.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=ci
case ${1:-} in
  --release) mode=release ;;
  --all) mode=all ;;
  "") ;;
  *) echo "usage: scripts/test.sh [--release | --all]" >&2; exit 2 ;;
esac
bash scripts/install-deps.sh
start=$(date +%s)
stage() { echo; echo "== test.sh: $1 ($(( $(date +%s) - start )) s so far)"; }

stage "1/3 release build and tests"
cmake --preset release >/dev/null
cmake --build --preset release
ctest --preset release
[[ $mode == release ]] && exit 0

# Sanitizer runs: any report fails the test (halt_on_error); leaks are ASan's job.
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1
stage "2/3 AddressSanitizer + UndefinedBehaviorSanitizer build, tests and fuzzing"
cmake --preset asan >/dev/null
cmake --build --preset asan
# Minutes each under the sanitizers (every example run end to end, the LDLT reference solves of
# the medium liver (compliance coupling, the haptic-rate CG), the allocation count over every model): --all runs them, CI does not.
slow='^(cli\.run_examples|ComplianceCoupling\.|TumourPalpation\.|NoAllocation\.|HapticRateFem\.WarmStartedCg)'
# The OpenGL tests (the window, gl_renderer_test: Mesa under Xvfb) stay out of the sanitizer runs.
if [[ $mode == all ]]; then
  ctest --preset asan -E '^GuiWindow\.|^GlRendererTest\.|^install\.'
else
  ctest --preset asan -E "^GuiWindow\.|^GlRendererTest\.|^install\.|$slow"
fi
HOF_FUZZ_BUILD=build/asan scripts/fuzz.sh "${HOF_FUZZ_SECONDS:-$([[ $mode == all ]] && echo 60 || echo 3)}"

stage "3/3 ThreadSanitizer on the threaded tests"
tsan_tests=(lock_free_test haptics_test replay_device_test scripted_device_test virtual_hand_device_test spacemouse_device_test
            mouse_device_test open_device_test udp_device_test sdk_device_test session_test world_session_test
            fault_injection_test command_seam_test)
cmake --preset tsan >/dev/null
cmake --build --preset tsan --target "${tsan_tests[@]}"
# One CPU for oneTBB (it sizes its pool from the affinity mask): its workers synchronise in an
# uninstrumented library, which TSan would misread; HoF's own threads still interleave.
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
taskset -c 0 ctest --preset tsan -E '^cli\.|^install\.|_NOT_BUILT'
stage "all passes green$([[ $mode == all ]] || echo ' (the slow sanitizer tests and long fuzzing: scripts/test.sh --all)')"
