"""The Python examples (examples/python/) run and do what they say."""

import csv
import importlib
import subprocess
import sys

import numpy as np
import pytest


def example(examples, name):
    """An example as a module (importable by name: worker processes pickle its functions)."""
    folder = str(examples / "python")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module(name)


def test_the_fit_recovers_a_known_youngs_modulus_within_one_percent(examples):
    fit = example(examples, "fit_young_modulus")
    true_modulus = 7300.0
    forces = fit.indentation_forces(true_modulus)
    assert np.all(np.diff(forces) > 0)  # deeper is harder
    found, result = fit.fit(fit.DEPTHS_M, forces)
    assert found == pytest.approx(true_modulus, rel=0.01)
    # And a curve from a softer tissue gives a softer modulus.
    softer, _ = fit.fit(fit.DEPTHS_M, fit.indentation_forces(4000.0))
    assert softer == pytest.approx(4000.0, rel=0.01)


def test_the_fit_runs_from_the_command_line_on_a_measured_curve(examples, tmp_path):
    fit = example(examples, "fit_young_modulus")
    curve = tmp_path / "measured.csv"
    rows = zip(fit.DEPTHS_M, fit.indentation_forces(5000.0))
    curve.write_text("depth_m,force_n\n" + "".join(f"{d},{f}\n" for d, f in rows))
    done = subprocess.run([sys.executable, str(examples / "python" / "fit_young_modulus.py"), "--curve", str(curve),
                           "--out", str(tmp_path)], check=True, capture_output=True, text=True)
    found = float(done.stdout.split("fitted Young's modulus: ")[1].split()[0])
    assert found == pytest.approx(5000.0, rel=0.01)
    assert (tmp_path / "fit_young_modulus.png").stat().st_size > 10000


def test_the_sweep_draws_steeper_curves_for_stiffer_livers(examples, tmp_path):
    subprocess.run([sys.executable, str(examples / "python" / "force_indentation_sweep.py"), "--out", str(tmp_path),
                    "--moduli", "3000", "9000"], check=True, capture_output=True)
    assert (tmp_path / "force_indentation_sweep.png").stat().st_size > 10000
    with open(tmp_path / "force_indentation_sweep.csv") as f:
        rows = list(csv.DictReader(f))
    at_2mm = {}
    for young in ("3000", "9000"):
        curve = sorted((float(r["indentation_m"]), float(r["force_n"])) for r in rows if r["young_modulus_pa"] == young)
        depths, forces = np.array(curve).T
        at_2mm[young] = np.interp(0.002, depths, forces)
    assert at_2mm["9000"] > 1.8 * at_2mm["3000"]


def test_the_parallel_sweep_gives_what_one_process_gives(examples):
    sweep = example(examples, "parallel_sweep")
    parallel = sweep.sweep([4000.0, 8000.0], [0.45], workers=2)
    serial = [sweep.press(e, 0.45) for e in (4000.0, 8000.0)]
    assert parallel == serial  # virtual time is deterministic, in any process
    assert parallel[1]["max_force_n"] > parallel[0]["max_force_n"]
