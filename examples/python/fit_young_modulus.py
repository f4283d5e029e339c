#!/usr/bin/env python3
"""Identifies a liver's Young's modulus from a measured indentation curve.

An indentation test presses a probe into the tissue in steps and, once the tissue has
settled at each depth, records the force: a CSV of `depth_m,force_n` (or, without one, a
curve HoF makes itself for a known modulus, so that the fit can be checked). The modulus is
the one whose simulated test, the same probe pressing the same depths into the medium liver,
best reproduces the forces (least squares, a bounded scalar search with scipy). The probe is
a Python function of time: a device in the world frame.

    PYTHONPATH=build/release/python python3 examples/python/fit_young_modulus.py [--curve CSV] [--out DIR]
"""

import argparse
import pathlib

import numpy as np
from scipy.optimize import minimize_scalar

import hof

EXAMPLES = pathlib.Path(__file__).resolve().parents[1]
PROJECT = EXAMPLES / "liver-palpation-medium-fem.hof"
DEPTHS_M = np.array([0.002, 0.004, 0.006, 0.008])  # the test's depths below the resting surface
APPROACH_S = 1.0   # from 2 cm above the surface down to it
RAMP_S = 0.1       # to the next depth
STEP_S = 0.5       # ramp and hold, per depth
AVERAGE_S = 0.1    # the force is the mean over the end of each hold


def staircase(top: np.ndarray, depths: np.ndarray):
    """The probe's position (world frame, m) at time t: down onto `top`, then step by step."""
    def position(t: float) -> np.ndarray:
        if t < APPROACH_S:
            return top + np.array([0.0, 0.0, 0.02 * (1.0 - t / APPROACH_S)])
        k = min(int((t - APPROACH_S) // STEP_S), len(depths) - 1)
        before = depths[k - 1] if k > 0 else 0.0
        u = min(1.0, (t - APPROACH_S - STEP_S * k) / RAMP_S)
        return top - np.array([0.0, 0.0, before + (depths[k] - before) * u])
    return position


def indentation_forces(young_modulus: float, depths: np.ndarray = DEPTHS_M) -> np.ndarray:
    """The settled force (N) at each depth for one modulus (Pa), pressed on the liver's top."""
    world = hof.load(PROJECT)
    world.set("Liver/FEM", "youngModulus", young_modulus)
    vertices, _ = world.surface()
    top = vertices[np.argmax(vertices[:, 2])]  # the liver's highest point (z is up)
    _, t = world.run(APPROACH_S + STEP_S * len(depths), device=staircase(top, depths))
    force = np.sqrt(t["force_x"] ** 2 + t["force_y"] ** 2 + t["force_z"] ** 2)
    ends = APPROACH_S + STEP_S * (np.arange(len(depths)) + 1)
    return np.array([force[(t["t"] > end - AVERAGE_S) & (t["t"] <= end)].mean() for end in ends])


def fit(depths: np.ndarray, forces: np.ndarray, bounds=(500.0, 50000.0)):
    """The modulus (Pa) whose test best reproduces `forces` at `depths`, and the search's result."""
    def misfit(log_modulus: float) -> float:
        return float(np.mean((indentation_forces(np.exp(log_modulus), depths) - forces) ** 2))
    result = minimize_scalar(misfit, bounds=np.log(bounds), method="bounded", options={"xatol": 1e-4})
    return float(np.exp(result.x)), result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curve", type=pathlib.Path, help="CSV of depth_m,force_n (default: made by HoF for --true-modulus)")
    parser.add_argument("--true-modulus", type=float, default=6500.0, help="Pa, for the curve HoF makes")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("fit-out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.curve:
        data = np.loadtxt(args.curve, delimiter=",", comments="#", skiprows=1, ndmin=2)
        depths, forces = data[:, 0], data[:, 1]
        source = str(args.curve)
    else:
        depths, forces = DEPTHS_M, indentation_forces(args.true_modulus)
        source = f"made by HoF with E = {args.true_modulus:g} Pa"
    young, result = fit(depths, forces)
    print(f"curve: {source} ({len(depths)} depths)")
    print(f"fitted Young's modulus: {young:.1f} Pa after {result.nfev} simulated tests")
    if not args.curve:
        print(f"error against the true modulus: {100 * (young / args.true_modulus - 1):+.3f} %")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fine = np.linspace(depths.min(), depths.max(), 8)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(1e3 * depths, forces, "o", ms=7, label=f"measured ({source})")
    ax.plot(1e3 * fine, indentation_forces(young, fine), "-", label=f"simulated, fitted E = {young:.0f} Pa")
    for factor in (0.8, 1.25):
        ax.plot(1e3 * fine, indentation_forces(factor * young, fine), ":", color="gray",
                label=f"simulated, E = {factor * young:.0f} Pa")
    ax.set_xlabel("indentation depth (mm)")
    ax.set_ylabel("settled force at the probe (N)")
    ax.set_title("Young's modulus identified from an indentation test (medium liver, FEM)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out / "fit_young_modulus.png", dpi=120)
    print(f"plot: {args.out / 'fit_young_modulus.png'}")


if __name__ == "__main__":
    main()
