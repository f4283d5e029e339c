#!/usr/bin/env python3
"""Golden outputs of the bundled examples: record them, compare two recordings.

A change of structure must keep behaviour. Before it, record what every bundled example does
in deterministic (virtual-time) mode — its summary without the figures that depend on the
machine, its telemetry — and what the Python examples print; after it, record again and
compare. Identical files are reported as bit-identical; otherwise every number is compared
within a relative tolerance and the worst difference is named.

    tools/golden_outputs.py record OUT_DIR [--hof build/release/bin/hof] [--python-path DIR]
                                           [--only REGEX] [--seconds S] [--telemetry-rate HZ]
    tools/golden_outputs.py compare EXPECTED_DIR ACTUAL_DIR [--rtol 1e-9] [--atol 1e-12]
    tools/golden_outputs.py check GOLDEN_DIR WORK_DIR [--hof BIN]

`check` records again with the options kept in GOLDEN_DIR/recipe.json and compares: the test
that keeps the comparison (tests/data/golden, ctest cli.golden_outputs). After a change meant
to alter behaviour, record that folder again with the recipe's options and say why in the
commit.

The comparison exits 1 on a difference, naming the file, the row and the column.
"""

import argparse
import json
import math
import os
import pathlib
import re
import subprocess
import sys

SOURCE = pathlib.Path(__file__).resolve().parents[1]

# Keys of summary.json that measure the machine, not the simulation.
MACHINE_KEYS = {
    "graphics_equivalent_fps",
    "peak_rss_bytes",
    "wall_s",
    "steps_per_s",
    "host_cpu_steal_s",
    "cpu_placement",
    "cpus_kept_awake",
    "keep_awake",
    "memory_locked",
    "scheduling",
}


def strip_machine(value):
    if isinstance(value, dict):
        return {k: strip_machine(v) for k, v in value.items() if k not in MACHINE_KEYS}
    if isinstance(value, list):
        return [strip_machine(v) for v in value]
    return value


def bundled_examples():
    examples = SOURCE / "examples"
    return sorted(examples.glob("*.hof")) + sorted(examples.glob("*.scn"))


def python_examples():
    return sorted((SOURCE / "examples" / "python").glob("*.py"))


def record(args):
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    only = re.compile(args.only) if args.only else None
    for example in bundled_examples():
        if only and not only.search(example.name):
            continue
        run_dir = out / "runs" / example.name
        command = [args.hof, "run", str(example.relative_to(SOURCE)), "--headless",
                   "--deterministic", "--out", str(run_dir)]
        if args.seconds:
            command += ["--seconds", str(args.seconds)]
        if args.telemetry_rate:
            command += ["--telemetry-rate", str(args.telemetry_rate)]
        result = subprocess.run(command, cwd=SOURCE, capture_output=True, text=True)
        if result.returncode != 0:
            sys.exit(f"{example.name}: hof run exited {result.returncode}\n{result.stderr}")
        summary = strip_machine(json.loads((run_dir / "summary.json").read_text()))
        target = out / example.name
        target.mkdir(exist_ok=True)
        (target / "summary.json").write_text(json.dumps(summary, indent=1, sort_keys=True) + "\n")
        (target / "telemetry.csv").write_bytes((run_dir / "telemetry.csv").read_bytes())
        print(f"recorded {example.name}", flush=True)
    if args.python_path:
        env = dict(os.environ, PYTHONPATH=args.python_path, MPLBACKEND="Agg")
        for script in python_examples():
            if only and not only.search(script.name):
                continue
            work = out / "runs" / script.stem
            work.mkdir(parents=True, exist_ok=True)
            result = subprocess.run([args.python, str(script), "--out", str(work)], cwd=SOURCE,
                                    env=env, capture_output=True, text=True)
            if result.returncode != 0:
                sys.exit(f"{script.name}: exited {result.returncode}\n{result.stderr}")
            # The output folder differs from one recording to the next: name it OUT.
            printed = result.stdout.replace(str(work), "OUT")
            (out / f"{script.stem}.stdout.txt").write_text(printed)
            print(f"recorded {script.name}", flush=True)


NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|inf", re.IGNORECASE)


class Worst:
    def __init__(self):
        self.relative = 0.0
        self.where = ""


def numbers_close(a, b, rtol, atol):
    if math.isnan(a) and math.isnan(b):
        return True, 0.0
    difference = abs(a - b)
    scale = max(abs(a), abs(b))
    return difference <= atol + rtol * scale, difference / scale if scale > 0 else difference


def compare_text(expected, actual, name, rtol, atol, worst):
    """Line by line, token by token; numbers within tolerance, other text exactly."""
    expected_lines = expected.splitlines()
    actual_lines = actual.splitlines()
    if len(expected_lines) != len(actual_lines):
        return f"{name}: {len(expected_lines)} lines expected, {len(actual_lines)} found"
    for row, (e_line, a_line) in enumerate(zip(expected_lines, actual_lines), start=1):
        if e_line == a_line:
            continue
        e_numbers = NUMBER.findall(e_line)
        a_numbers = NUMBER.findall(a_line)
        if NUMBER.sub("#", e_line) != NUMBER.sub("#", a_line) or len(e_numbers) != len(a_numbers):
            return f"{name}:{row}: text differs\n  expected {e_line}\n  actual   {a_line}"
        for column, (e, a) in enumerate(zip(e_numbers, a_numbers), start=1):
            close, relative = numbers_close(float(e), float(a), rtol, atol)
            if relative > worst.relative:
                worst.relative = relative
                worst.where = f"{name}:{row} number {column}"
            if not close:
                return (f"{name}:{row}: number {column} is {a}, expected {e} "
                        f"(relative difference {relative:.3g} > {rtol:g})")
    return None


def compare(args):
    expected_dir = pathlib.Path(args.expected)
    actual_dir = pathlib.Path(args.actual)
    files = sorted(p.relative_to(expected_dir) for p in expected_dir.rglob("*")
                   if p.is_file() and p.name != "recipe.json"
                   and "runs" not in p.relative_to(expected_dir).parts)
    if not files:
        sys.exit(f"{expected_dir}: no golden outputs")
    identical = 0
    worst = Worst()
    failures = []
    for relative in files:
        actual = actual_dir / relative
        if not actual.exists():
            failures.append(f"{relative}: missing")
            continue
        e_bytes = (expected_dir / relative).read_bytes()
        a_bytes = actual.read_bytes()
        if e_bytes == a_bytes:
            identical += 1
            continue
        failure = compare_text(e_bytes.decode(), a_bytes.decode(), str(relative), args.rtol,
                               args.atol, worst)
        if failure:
            failures.append(failure)
    print(f"{identical} of {len(files)} files bit-identical", end="")
    if worst.where:
        print(f"; largest relative difference {worst.relative:.3g} at {worst.where}", end="")
    print()
    for failure in failures:
        print(f"DIFFERS {failure}")
    return 1 if failures else 0


def check(args):
    golden = pathlib.Path(args.golden)
    recipe = json.loads((golden / "recipe.json").read_text())
    work = pathlib.Path(args.work)
    record(argparse.Namespace(out=str(work), hof=args.hof, python_path=None,
                              only=recipe.get("only"), seconds=recipe.get("seconds"),
                              telemetry_rate=recipe.get("telemetry_rate")))
    args.expected, args.actual = str(golden), str(work)
    return compare(args)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    rec = commands.add_parser("record")
    rec.add_argument("out")
    rec.add_argument("--hof", default=str(SOURCE / "build" / "release" / "bin" / "hof"))
    rec.add_argument("--python-path", help="PYTHONPATH of the hof module: also record the "
                     "Python examples' printed results")
    rec.add_argument("--python", default="/usr/bin/python3", help="the Python that has numpy")
    rec.add_argument("--only", help="only the examples whose file name matches")
    rec.add_argument("--seconds", type=float, help="run each example this long (default: "
                     "its own length)")
    rec.add_argument("--telemetry-rate", type=float, help="telemetry rows per second (default: "
                     "every tick)")
    cmp = commands.add_parser("compare")
    cmp.add_argument("expected")
    cmp.add_argument("actual")
    cmp.add_argument("--rtol", type=float, default=1e-9)
    cmp.add_argument("--atol", type=float, default=1e-12)
    chk = commands.add_parser("check")
    chk.add_argument("golden")
    chk.add_argument("work")
    chk.add_argument("--hof", default=str(SOURCE / "build" / "release" / "bin" / "hof"))
    chk.add_argument("--rtol", type=float, default=1e-9)
    chk.add_argument("--atol", type=float, default=1e-12)
    args = parser.parse_args()
    if args.command == "check":
        return check(args)
    if args.command == "record":
        record(args)
        return 0
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
