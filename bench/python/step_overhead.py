#!/usr/bin/env python3
"""What the Python module costs per step over the C++ call it makes.

`world.step(1000)` timed from Python against the same 1,000 steps in C++ (`hof run
--deterministic --steps 1000`, whose summary.json times Session::run_virtual alone), on the
same project; and `world.run()` timed from Python against the wall time the session itself
measured (the difference is the module: the GIL released and taken back, the signal checks,
the telemetry turned into arrays and the summary into a dict).

    PYTHONPATH=build/release/python python3 bench/python/step_overhead.py [PROJECT] [--repeat N]
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import tempfile
import time

import hof

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("project", nargs="?", type=pathlib.Path, default=ROOT / "examples" / "liver-palpation-medium-fem.hof")
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--hof", type=pathlib.Path, default=ROOT / "build" / "release" / "bin" / "hof")
    args = parser.parse_args()
    steps = 1000

    python_s = []
    for _ in range(args.repeat):
        world = hof.load(args.project)
        start = time.perf_counter()
        world.step(steps)
        python_s.append(time.perf_counter() - start)

    cpp_s = []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(args.repeat):
            subprocess.run([str(args.hof), "run", str(args.project), "--deterministic", "--quiet", "--steps", str(steps),
                            "--out", out], check=True)
            cpp_s.append(json.loads((pathlib.Path(out) / "summary.json").read_text())["wall_s"])

    run_overhead = []
    for _ in range(args.repeat):
        world = hof.load(args.project)
        start = time.perf_counter()
        report, telemetry = world.run(steps * world.dt)
        run_overhead.append((time.perf_counter() - start - report["wall_s"]) / report["simulation"]["steps"])

    py, cpp = statistics.median(python_s), statistics.median(cpp_s)
    print(f"project: {args.project.name}, {steps} steps, median of {args.repeat}")
    print(f"  world.step({steps}) from Python   {1e3 * py:8.1f} ms  ({1e6 * py / steps:.1f} us/step; min {1e3 * min(python_s):.1f})")
    print(f"  the same steps in C++ (hof run)  {1e3 * cpp:8.1f} ms  ({1e6 * cpp / steps:.1f} us/step; min {1e3 * min(cpp_s):.1f})")
    print(f"  difference                       {100 * (py / cpp - 1):+8.2f} %")
    print(f"  world.run(): the module's own time per step (telemetry arrays, summary dict) "
          f"{1e6 * statistics.median(run_overhead):.2f} us")


if __name__ == "__main__":
    main()
