#!/usr/bin/env bash
# Builds HoF and runs every test, as CI does. Does all set-up on a fresh Debian 12 machine:
# installs the packages first (quiet when they are there).
#
#   scripts/test.sh           the Release pass (what CI runs)
#   scripts/test.sh --all     every pass below (about 40 minutes on two cores)
#
# Passes (docs/reliability.md):
#   1. release  -O3, warnings as errors, every test
#   2. asan     AddressSanitizer + UndefinedBehaviorSanitizer (-O1, assertions on), every test
#               but the window's (Mesa's software OpenGL is not ours to sanitize)
#   3. tsan     ThreadSanitizer on the threaded tests (haptic loop, UDP device, sessions with
#               their simulation thread, fault injection)
#   4. fuzz     every libFuzzer target for HOF_FUZZ_SECONDS (20) seconds, two at a time
set -euo pipefail
cd "$(dirname "$0")/.."
quick=1
[[ ${1:-} == --all ]] && quick=0
bash scripts/install-deps.sh
start=$(date +%s)
stage() { echo; echo "== test.sh: $1 ($(( $(date +%s) - start )) s so far)"; }

stage "1/4 release build and tests"
cmake --preset release >/dev/null
cmake --build --preset release
ctest --preset release
[[ $quick == 1 ]] && exit 0

# Sanitizer runs: any report fails the test (halt_on_error); leaks are ASan's job.
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1
stage "2/4 AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake --preset asan >/dev/null
cmake --build --preset asan
ctest --preset asan -E '^GuiWindow\.'

stage "3/4 ThreadSanitizer on the threaded tests"
tsan_tests=(haptics_test device_test session_test world_session_test fault_injection_test)
cmake --preset tsan >/dev/null
cmake --build --preset tsan --target "${tsan_tests[@]}"
# One CPU for oneTBB (it sizes its pool from the affinity mask): its workers synchronise in an
# uninstrumented library, which TSan would misread; HoF's own threads still interleave.
export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
taskset -c 0 ctest --preset tsan -E '^cli\.|_NOT_BUILT'

stage "4/4 fuzzing every reader (${HOF_FUZZ_SECONDS:-20} s per target)"
scripts/fuzz.sh "${HOF_FUZZ_SECONDS:-20}"
stage "all passes green"
