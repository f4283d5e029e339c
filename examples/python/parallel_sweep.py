#!/usr/bin/env python3
"""A parameter sweep in parallel processes: one world per process.

Each (Young's modulus, Poisson ratio) pair runs the standard press on the medium FEM liver
in its own process (concurrent.futures): a world is not shared between threads or processes,
and virtual-time runs are deterministic, so the table is the same whatever the number of
workers.

    PYTHONPATH=build/release/python python3 examples/python/parallel_sweep.py [--workers N] [--out DIR]
"""

import argparse
import concurrent.futures
import itertools
import os
import pathlib

import hof

EXAMPLES = pathlib.Path(__file__).resolve().parents[1]
PROJECT = EXAMPLES / "liver-palpation-medium-fem.hof"


def press(young_modulus: float, poisson_ratio: float, seconds: float = 1.6) -> dict:
    """The standard press for one material: peak force, peak displacement, contact time."""
    world = hof.load(PROJECT)
    world.set("Liver/FEM", "youngModulus", young_modulus)
    world.set("Liver/FEM", "poissonRatio", poisson_ratio)
    report, _ = world.run(seconds)
    return {"young_modulus_pa": young_modulus, "poisson_ratio": poisson_ratio,
            "max_force_n": report["max_force_n"], "max_displacement_m": report["bodies"][0]["max_displacement"],
            "contact_time_s": report["contact_time_s"]}


def sweep(moduli, ratios, workers):
    with concurrent.futures.ProcessPoolExecutor(max_workers=workers) as pool:
        jobs = [pool.submit(press, e, nu) for e, nu in itertools.product(moduli, ratios)]
        return [job.result() for job in jobs]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--moduli", type=float, nargs="+", default=[3000, 5400, 9000])
    parser.add_argument("--ratios", type=float, nargs="+", default=[0.3, 0.45, 0.49])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("sweep-out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    results = sweep(args.moduli, args.ratios, args.workers)
    keys = list(results[0])
    lines = [",".join(keys)] + [",".join(f"{r[k]:.9g}" for k in keys) for r in results]
    (args.out / "parallel_sweep.csv").write_text("\n".join(lines) + "\n")
    print(f"{'E (Pa)':>8} {'nu':>5} {'peak force (N)':>15} {'max displacement (mm)':>22}")
    for r in results:
        print(f"{r['young_modulus_pa']:8.0f} {r['poisson_ratio']:5.2f} {r['max_force_n']:15.3f} {1e3 * r['max_displacement_m']:22.2f}")
    print(f"table: {args.out / 'parallel_sweep.csv'} ({len(results)} runs on {args.workers} processes)")


if __name__ == "__main__":
    main()
