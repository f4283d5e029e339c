#!/usr/bin/env bash
# hof run never loses a session's results: a disk that fills during the run, and the report
# folder removed while the session runs. Usage: report_faults.sh HOF SOURCE_DIR WORK_DIR
set -u
hof=$1 source=$2 work=$3
project="$source/examples/liver-palpation-simple.hof"
rm -rf "$work" && mkdir -p "$work"
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# 1. A full disk: files may grow to 1 KiB only (ulimit -f; SIGXFSZ ignored, so writes fail
#    with EFBIG as they fail with ENOSPC on a full disk). The telemetry is cut short and
#    summary.json cannot be written: the summary goes to the terminal, the status says so.
err=$( (trap '' XFSZ; ulimit -f 1; exec "$hof" run "$project" --deterministic --seconds 1 --quiet --out "$work/full") 2>&1 >/dev/null)
rc=$?
[ "$rc" -eq 3 ] || fail "full disk: exit status $rc, expected 3"
grep -q "summary.json" <<<"$err" || fail "full disk: summary.json's failure not named: $err"
grep -q '"max_force_n"' <<<"$err" || fail "full disk: the summary was not printed instead"
grep -q "telemetry.csv is incomplete" <<<"$err" || fail "full disk: the cut telemetry was not reported"
ls "$work/full" | grep -q '\.tmp-' && fail "full disk: a temporary file was left in the report folder"

# 2. Room for the summary but not for the whole telemetry (64 KiB): summary.json is written,
#    and says the telemetry is incomplete; the status is 3.
err=$( (trap '' XFSZ; ulimit -f 64; exec "$hof" run "$project" --deterministic --seconds 1 --quiet --out "$work/tight") 2>&1 >/dev/null)
rc=$?
[ "$rc" -eq 3 ] || fail "tight disk: exit status $rc, expected 3 ($err)"
grep -q '"telemetry_problem"' "$work/tight/summary.json" 2>/dev/null || fail "tight disk: summary.json does not record the cut telemetry"

# 3. The report folder removed while the session runs (real time, 3 s): it is made again with
#    the whole telemetry and the summary.
"$hof" run "$project" --seconds 3 --quiet --out "$work/removed" 2>"$work/removed.err" >/dev/null &
pid=$!
for _ in $(seq 1 600); do  # up to 30 s for the session to start (a loaded machine)
  [ -s "$work/removed/telemetry.csv" ] && break
  sleep 0.05
done
rm -rf "$work/removed"
wait "$pid"
rc=$?
[ "$rc" -eq 0 ] || fail "folder removed: exit status $rc ($(cat "$work/removed.err"))"
[ -s "$work/removed/summary.json" ] || fail "folder removed: no summary.json"
rows=$(wc -l <"$work/removed/telemetry.csv" 2>/dev/null || echo 0)
[ "$rows" -gt 1000 ] || fail "folder removed: telemetry has $rows rows (the rows before the removal were lost)"
grep -q "removed during the run" "$work/removed.err" || fail "folder removed: not reported"

[ "$failures" -eq 0 ] && echo "report faults: all handled"
exit "$failures"
