#!/usr/bin/env bash
# Fuzzes every file reader (and one run end to end) with libFuzzer: builds build/fuzz with
# clang++-16 (ASan + UBSan), makes the seed corpora (fuzz/make-seeds.sh), then runs each
# target SECONDS (default 60) two at a time. New inputs that reach new code are kept in
# build/fuzz/corpus/<target>/ (reused by the next run), crashes in
# build/fuzz/artifacts/<target>/, logs in build/fuzz/logs/. Prints one line per target and
# exits non-zero if any target found a crash, a leak, a timeout or ran out of memory.
#
#   scripts/fuzz.sh                 # every target, 60 s each (what CI runs)
#   scripts/fuzz.sh 300 msh scn     # two targets, 5 minutes each
#
# Reproduce a crash: build/fuzz/bin/fuzz_<target> build/fuzz/artifacts/<target>/crash-...
# (docs/reliability.md, "Fuzzing"). Needs clang-16 and libclang-rt-16-dev (Debian), python3.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
[[ $# -gt 0 ]] && shift
all=(msh obj stl off vtu sofa_legacy scn hof x3d trajectory udp session)
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=("${all[@]}")
jobs=${HOF_FUZZ_JOBS:-2}
# HOF_FUZZ_BUILD=build/asan: use a tree already configured with HOF_FUZZ=ON (the asan preset,
# which test.sh builds anyway) instead of configuring build/fuzz.
build=${HOF_FUZZ_BUILD:-build/fuzz}
# HOF_FUZZ_KEEP_GOING=1 (the long documented runs): libFuzzer's fork mode, which saves a
# crash and goes on fuzzing, so that one run finds every crash rather than the first.
keep_going=${HOF_FUZZ_KEEP_GOING:-0}
# Symbolised stack traces (clang 16's runtime reads any llvm-symbolizer).
if [[ -z ${ASAN_SYMBOLIZER_PATH:-} ]]; then
  for s in /usr/lib/llvm-16/bin/llvm-symbolizer /usr/bin/llvm-symbolizer-16 "$(readlink -f /usr/bin/llvm-symbolizer 2>/dev/null)"; do
    [[ -x $s ]] && { export ASAN_SYMBOLIZER_PATH=$s; break; }
  done
fi

# Largest input per target: a few times the seeds, small enough to keep executions quick.
max_len() {
  case $1 in
    udp) echo 256 ;;
    trajectory | sofa_legacy) echo 16384 ;;
    msh | obj | stl | off | vtu) echo 32768 ;;
    *) echo 65536 ;;
  esac
}
dictionary() {
  case $1 in
    scn | hof | x3d | session | vtu) echo fuzz/dict/xml.dict ;;
    *) echo "fuzz/dict/$1.dict" ;;
  esac
}

start=$(date +%s)
if [[ -z ${HOF_FUZZ_BUILD:-} ]]; then
  echo "fuzz: configuring and building $build (clang++-16, ASan + UBSan + libFuzzer)"
  cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="${HOF_FUZZ_CXX:-clang++-16}" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHOF_FUZZ=ON -DHOF_BUILD_TESTS=OFF -DHOF_BUILD_BENCH=OFF >/dev/null
else
  echo "fuzz: building the targets in $build"
fi
cmake --build "$build" -j "$jobs" --target "${targets[@]/#/fuzz_}" | tail -n 1
echo "fuzz: seeds"
fuzz/make-seeds.sh "$build/seeds" >/dev/null
mkdir -p "$build/logs"
touch "$build/logs/.started"
# The targets write each input to a scratch folder of their own under TMPDIR; a crashed
# process leaves its folder behind, so they live here and go at the end.
export TMPDIR=$PWD/$build/tmp
rm -rf "$TMPDIR" && mkdir -p "$TMPDIR"

run_target() {
  local t=$1 dict
  local corpus=$build/corpus/$t artifacts=$build/artifacts/$t
  mkdir -p "$corpus" "$artifacts"
  dict=$(dictionary "$t")
  local options=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="$(max_len "$t")"
                 -artifact_prefix="$artifacts/" -print_final_stats=1 -close_fd_mask=1)
  [[ -f $dict ]] && options+=(-dict="$dict")
  [[ $keep_going == 1 ]] && options+=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  "$build/bin/fuzz_$t" "${options[@]}" "$corpus" "$build/seeds/$t" >"$build/logs/$t.log" 2>&1
}

summary() {
  local t=$1 status=$2 log=$build/logs/$1.log
  local last execs cov ft corpus found
  last=$(grep -aE '^#[0-9]+' "$log" | tail -n 1 || true)
  execs=$(grep -aoE 'stat::number_of_executed_units: [0-9]+' "$log" | grep -oE '[0-9]+$' || true)
  [[ -z $execs ]] && execs=$(sed -nE 's/^#([0-9]+).*/\1/p' <<<"$last")
  cov=$(grep -oE 'cov: [0-9]+' <<<"$last" | grep -oE '[0-9]+' || true)
  ft=$(grep -oE 'ft: [0-9]+' <<<"$last" | grep -oE '[0-9]+' || true)
  corpus=$(find "$build/corpus/$t" -type f | wc -l)
  # What this run wrote (artifacts of earlier runs stay until removed).
  found=$(find "$build/artifacts/$t" -type f -newer "$build/logs/.started" -printf '%f ' 2>/dev/null || true)
  [[ -n $found && $status -eq 0 ]] && status=1
  [[ $status -ne 0 ]] && failed=1
  printf 'fuzz_%-12s execs %9s  cov %6s  ft %7s  corpus %5s  %s\n' "$t" "${execs:-?}" "${cov:-?}" "${ft:-?}" "$corpus" \
    "$([[ $status -eq 0 ]] && echo ok || echo "FOUND (exit $status): ${found:-see $log}")"
}

echo "fuzz: ${#targets[@]} target(s), ${seconds} s each, $jobs at a time"
declare -A pid_of
failed=0
running=0
for t in "${targets[@]}"; do
  if (( running >= jobs )); then
    wait -n -p done_pid && status=0 || status=$?
    for k in "${!pid_of[@]}"; do [[ ${pid_of[$k]} == "$done_pid" ]] && { summary "$k" "$status"; unset "pid_of[$k]"; }; done
    running=$((running - 1))
  fi
  echo "fuzz: fuzz_$t started"
  run_target "$t" &
  pid_of[$t]=$!
  running=$((running + 1))
done
while (( running > 0 )); do
  wait -n -p done_pid && status=0 || status=$?
  for k in "${!pid_of[@]}"; do [[ ${pid_of[$k]} == "$done_pid" ]] && { summary "$k" "$status"; unset "pid_of[$k]"; }; done
  running=$((running - 1))
done
rm -rf "$TMPDIR"
echo "fuzz: done in $(( $(date +%s) - start )) s$([[ $failed -ne 0 ]] && echo "; FOUND PROBLEMS (see $build/artifacts, $build/logs)")"
exit $failed
