#!/usr/bin/env python3
"""Force against indentation on the medium liver for several Young's moduli.

The standard probe (the world's default: a scripted press along the organ's outward normal)
presses the co-rotational FEM liver once per modulus; each run's loading curve, the force at
the probe against how far the tissue surface moved in, is plotted. A stiffer liver gives a
steeper curve: what a clinician's palpation feels.

    PYTHONPATH=build/release/python python3 examples/python/force_indentation_sweep.py [--out DIR]

Writes DIR/force_indentation_sweep.png (and .csv) and prints the peak force per modulus.
"""

import argparse
import pathlib

import numpy as np

import hof

EXAMPLES = pathlib.Path(__file__).resolve().parents[1]
PROJECT = EXAMPLES / "liver-palpation-medium-fem.hof"


BIN_M = 2.5e-4  # the curve is drawn as the mean force over each quarter millimetre


def loading_curve(young_modulus: float, seconds: float = 1.6):
    """(indentation m, force N) while the probe goes in, for one modulus (Pa).

    The force felt at 1 kHz ripples with each 10 ms simulation step (the surface moves in
    steps); the curve is its mean over each quarter millimetre of indentation."""
    world = hof.load(PROJECT)
    world.set("Liver/FEM", "youngModulus", young_modulus)
    report, telemetry = world.run(seconds)
    force = np.sqrt(telemetry["force_x"] ** 2 + telemetry["force_y"] ** 2 + telemetry["force_z"] ** 2)
    device = np.column_stack([telemetry["device_x"], telemetry["device_y"], telemetry["device_z"]])
    first = int(np.argmax(telemetry["contact"]))
    # While the probe goes deeper: from the first contact to its deepest point.
    travel = np.linalg.norm(device - device[first], axis=1)
    deepest = first + int(np.argmax(travel[first:]))
    indentation = telemetry["indentation"][first:deepest + 1]
    force = force[first:deepest + 1]
    bins = np.floor(indentation / BIN_M).astype(int)
    centres, means = [], []
    for b in np.unique(bins):
        centres.append((b + 0.5) * BIN_M)
        means.append(force[bins == b].mean())
    return np.array(centres), np.array(means), report


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("sweep-out"))
    parser.add_argument("--moduli", type=float, nargs="+", default=[2000, 3500, 5400, 8000, 12000])
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    rows = ["young_modulus_pa,indentation_m,force_n"]
    print(f"{'E (Pa)':>8}  {'peak force (N)':>14}  {'max indentation (mm)':>20}")
    for young in args.moduli:
        indentation, force, report = loading_curve(young)
        ax.plot(1e3 * indentation, force, "-o", ms=3, label=f"E = {young / 1000:g} kPa")
        rows += [f"{young:g},{i:.9g},{f:.9g}" for i, f in zip(indentation, force)]
        print(f"{young:8.0f}  {report['max_force_n']:14.3f}  {1e3 * indentation.max():20.2f}")
    ax.set_xlabel("tissue indentation at the probe (mm)")
    ax.set_ylabel("force at the probe (N)")
    ax.set_title("Medium liver, co-rotational FEM (nu = 0.45): a press at 2 cm/s")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out / "force_indentation_sweep.png", dpi=120)
    (args.out / "force_indentation_sweep.csv").write_text("\n".join(rows) + "\n")
    print(f"plot: {args.out / 'force_indentation_sweep.png'}")


if __name__ == "__main__":
    main()
