#!/usr/bin/env bash
# Soak test: a long real-time haptic session, watched from outside. Samples the process's
# resident memory every 5 s, then reads the report and checks what must hold for hours:
# no haptic period above 2 ms, no memory growth after the warm-up, every force finite and
# within the device's limit. Plots memory and the force over time.
#
#   scripts/soak.sh [SECONDS] [PROJECT] [OUT]     (defaults: 600, the fine liver, out/soak)
#   SOAK_GUI=1 scripts/soak.sh ...                (the window under Xvfb instead of hof run)
#   SOAK_ARGS="--sim-threads 2" scripts/soak.sh   (more options for hof run / hof gui)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
project=${2:-examples/liver-palpation-fine.hof}
out=${3:-out/soak}
hof=build/release/bin/hof
[ -x "$hof" ] || { echo "soak: build first (scripts/test.sh or cmake --build --preset release)" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out"
# A palpation that never ends: the project's own script would finish after a few seconds.
device="scripted:palpate,start=0.0;0;0.09,direction=0;0;-1,approach=0.04,depth=0.006,speed=0.03,hold=0.3,step=0.01;0;0,count=5,repeat=forever"

if [ "${SOAK_GUI:-0}" = 1 ]; then
  printf 'wait %s\nscreenshot %s/gui-end.png\nquit\n' "$seconds" "$out" >"$out/script.txt"
  xvfb-run -a -s "-screen 0 1280x720x24" "$hof" gui "$project" --device "$device" --size 1280x720 --script "$out/script.txt" ${SOAK_ARGS:-} \
    >"$out/run.log" 2>&1 &
else
  "$hof" run "$project" --device "$device" --seconds "$seconds" --telemetry-rate 100 --quiet --out "$out" ${SOAK_ARGS:-} \
    >"$out/run.log" 2>&1 &
fi
pid=$!
echo "soak: ${seconds} s of $project (pid $pid); memory every 5 s in $out/rss.dat"
echo "# t_s rss_MiB" >"$out/rss.dat"
start=$(date +%s)
while kill -0 "$pid" 2>/dev/null; do
  now=$(( $(date +%s) - start ))
  # The hof process itself (xvfb-run starts it as a child in the window case).
  target=$pid
  if [ "${SOAK_GUI:-0}" = 1 ]; then target=$(pgrep -n -f "bin/hof gui" || echo "$pid"); fi
  rss=$(awk '/VmRSS/ {print $2}' "/proc/$target/status" 2>/dev/null || true)
  [ -n "$rss" ] && echo "$now $(awk -v k="$rss" 'BEGIN {printf "%.1f", k / 1024}')" >>"$out/rss.dat"
  printf '\rsoak: %4d / %d s' "$now" "$seconds"
  sleep 5
done
wait "$pid" || { echo; echo "soak: the run failed:" >&2; cat "$out/run.log" >&2; exit 1; }
echo

# Memory: the largest sample after the first minute against the first one after it.
read -r first last max < <(awk 'NR > 1 && $1 >= 60 { if (!f) f = $2; l = $2; if ($2 > m) m = $2 } END { print f + 0, l + 0, m + 0 }' "$out/rss.dat")
gnuplot -e "set terminal pngcairo size 960,400; set output '$out/rss.png'; set xlabel 'time (s)'; set ylabel 'resident memory (MiB)'; set yrange [0:*]; set grid; set key bottom right; plot '$out/rss.dat' using 1:2 with lines title 'hof: resident memory'" 2>/dev/null || true

status=0
if [ -f "$out/summary.json" ]; then
  python3 - "$out" "$first" "$last" "$max" <<'PY' || status=1
import csv, json, math, sys
out, first, last, peak = sys.argv[1], *map(float, sys.argv[2:])
s = json.load(open(f"{out}/summary.json"))
h = s["haptic"]
limit = 8.0  # the virtual device's limit (the soak's device)
worst, bad, rows = 0.0, 0, 0
with open(f"{out}/telemetry.csv") as f:
    for r in csv.DictReader(f):
        rows += 1
        F = math.sqrt(sum(float(r[k]) ** 2 for k in ("force_x", "force_y", "force_z")))
        if not math.isfinite(F) or F > limit + 1e-9: bad += 1
        worst = max(worst, F)
growth = last - first
print(f"soak: {s['wall_s']:.0f} s wall, {h['ticks']} haptic ticks at {h['rate_hz']:.1f} Hz; period p50 {1e6*h['period_p50_s']:.0f} us, "
      f"p99 {1e6*h['period_p99_s']:.0f} us, max {1e6*h['period_max_s']:.0f} us; ticks over 2 ms: {h['periods_over_2ms']}; overruns {h['overruns']}")
print(f"soak: simulation {s['simulation']['steps']} steps ({s['simulation']['steps_per_s']:.0f}/s); contact {s['contact_time_s']:.0f} s; "
      f"max force {s['max_force_n']:.3f} N; presses {len(s['presses'])}; diverged {s['diverged']}")
print(f"soak: haptic thread scheduling {h.get('scheduling', '?')}; memory locked {h.get('memory_locked', '?')}; "
      f"CPUs kept awake {h.get('cpus_kept_awake', '?')} ({h.get('keep_awake', '?')}); "
      f"CPU time stolen by the host during the run {s.get('host_cpu_steal_s', float('nan')):.1f} s")
print(f"soak: memory after 60 s {first:.1f} MiB, at the end {last:.1f} MiB (growth {growth:+.1f} MiB), peak {peak:.1f} MiB")
print(f"soak: telemetry rows {rows}, force anomalies (non-finite or above {limit} N) {bad}, largest force {worst:.3f} N")
ok = h["periods_over_2ms"] == 0 and bad == 0 and not s["diverged"] and growth < 0.05 * max(first, 1.0) + 2.0
print("soak: " + ("PASS" if ok else "FAIL"))
sys.exit(0 if ok else 1)
PY
else
  tail -5 "$out/run.log"
fi
exit $status
