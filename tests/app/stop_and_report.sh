#!/usr/bin/env bash
# What a new user meets at the end of a run (issue 35): Ctrl-C or SIGTERM stops cleanly with the
# whole report; a run too short for the default probe says so; plots are titled by the project;
# `hof check` on a folder says it is a folder. Usage: stop_and_report.sh HOF SOURCE_DIR WORK_DIR
set -u
hof=$1 source=$2 work=$3
project="$source/examples/liver-palpation-simple.hof"
rm -rf "$work" && mkdir -p "$work"
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# 1. A signal during a real-time run: the run ends after its step, writes summary.json (saying
#    which signal stopped it), whole telemetry rows and the plots, and exits 128 + the signal.
for signal in INT TERM; do
  out="$work/stopped-$signal"
  "$hof" run "$project" --seconds 60 --quiet --out "$out" 2>"$work/stderr-$signal" &
  pid=$!
  for _ in $(seq 1 100); do [ -s "$out/telemetry.csv" ] && break; sleep 0.1; done
  sleep 1
  kill -s "$signal" "$pid"
  wait "$pid"
  rc=$?
  expected=$([ "$signal" = INT ] && echo 130 || echo 143)
  [ "$rc" -eq "$expected" ] || fail "SIG$signal: exit status $rc, expected $expected ($(cat "$work/stderr-$signal"))"
  grep -q "\"stopped_by\": \"SIG$signal\"" "$out/summary.json" 2>/dev/null || fail "SIG$signal: summary.json missing or without stopped_by"
  grep -q "SIG$signal: the run stopped after" "$work/stderr-$signal" || fail "SIG$signal: not said on the terminal"
  columns=$(head -1 "$out/telemetry.csv" | awk -F, '{print NF}')
  bad_rows=$(awk -F, -v n="$columns" 'NF != n' "$out/telemetry.csv" | wc -l)
  [ "$bad_rows" -eq 0 ] || fail "SIG$signal: $bad_rows telemetry row(s) cut short"
  [ "$(wc -l <"$out/telemetry.csv")" -gt 100 ] || fail "SIG$signal: the telemetry of what ran is missing"
  simulated=$(sed -n 's/.*"simulated_s": \([0-9.e+-]*\).*/\1/p' "$out/summary.json")
  awk -v s="$simulated" 'BEGIN { exit !(s > 0.5 && s < 30) }' || fail "SIG$signal: simulated_s $simulated is not what ran"
  if command -v gnuplot >/dev/null; then
    [ -s "$out/force_over_time.png" ] || fail "SIG$signal: no plots"
  fi
done

# 2. A run that ends before the default probe arrives says so, with the time it needs.
err=$("$hof" run "$source/examples/liver-simple-springs.scn" --deterministic --seconds 0.5 --quiet 2>&1 >/dev/null)
grep -q "before the default probe reached the surface: it needs about 1.0 s to arrive" <<<"$err" ||
  fail "short run: no warning that the probe had not arrived: $err"
err=$("$hof" run "$source/examples/liver-simple-springs.scn" --deterministic --quiet 2>&1 >/dev/null)
grep -q "before the default probe" <<<"$err" && fail "a run long enough warned that the probe had not arrived"

# 3. Plots are titled by the project that ran (with its scene), not by the scene alone.
"$hof" run "$source/examples/liver-palpation-medium-fem.hof" --deterministic --seconds 0.2 --quiet --out "$work/title" 2>/dev/null
grep -q "set title 'liver-palpation-medium-fem.hof (scene liver-medium-fem.scn)" "$work/title/plots.gp" ||
  fail "plot title: $(grep -m1 'set title' "$work/title/plots.gp")"
grep -q "every tick 1000 us: virtual time" "$work/title/plots.gp" || fail "the virtual-time period histogram does not say so"

# 4. hof check on a folder.
err=$("$hof" check "$source/examples" 2>&1)
rc=$?
[ "$rc" -ne 0 ] && grep -q "is a folder" <<<"$err" || fail "hof check on a folder: status $rc: $err"

# 5. A device that never gives a reading (a UDP bridge not sending) is named, not silent.
err=$("$hof" run "$project" --seconds 1 --device udp:0 --quiet 2>&1 >/dev/null)
grep -q "the device gave no reading in the whole run" <<<"$err" || fail "a silent device: $err"
# The device named by --device is said to be the option's, not the project's.
err=$("$hof" run "$project" --seconds 1 --device dhd --quiet 2>&1 >/dev/null)
grep -q "the device given by --device" <<<"$err" || fail "--device error names the project: $err"

# 6. A volume mesh converted to a surface format keeps only the surface's nodes.
"$hof" mesh convert "$source/data/models/liver-simple.msh" "$work/liver-surface.obj" --quiet 2>/dev/null
info=$("$hof" mesh info "$work/liver-surface.obj" 2>&1)
grep -q "used by no element" <<<"$info" && fail "the converted OBJ has vertices of no face: $info"
[ "$(grep -c '^v ' "$work/liver-surface.obj")" -gt 100 ] || fail "the converted OBJ has no surface"

[ "$failures" -eq 0 ] && echo "all stop-and-report checks passed"
exit $((failures > 0))
