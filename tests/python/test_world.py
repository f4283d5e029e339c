"""Worlds from Python: the same runs as `hof run`, state as arrays, settings, errors."""

import csv
import gc
import json
import math
import os
import signal
import subprocess
import threading

import numpy as np
import pytest

import hof

# summary.json's entries that measure the machine, not the run.
MACHINE_KEYS = {"wall_s", "peak_rss_bytes", "graphics_equivalent_fps", "host_cpu_steal_s", "file", "scene"}


def csv_number(value: float) -> str:
    """A number as telemetry.csv writes it (9 significant digits)."""
    return format(value, ".9g")


def without_machine(summary: dict) -> dict:
    out = {k: v for k, v in summary.items() if k not in MACHINE_KEYS}
    out["simulation"] = {k: v for k, v in summary["simulation"].items() if k != "steps_per_s"}
    return out


@pytest.mark.parametrize("example", ["liver-palpation-simple.hof", "needle-cube.hof"])
def test_a_run_from_python_gives_the_telemetry_and_summary_of_hof_run(example, examples, hof_executable, tmp_path):
    project = examples / example
    subprocess.run([str(hof_executable), "run", str(project), "--deterministic", "--quiet", "--out", str(tmp_path / "cli")],
                   check=True)
    with open(tmp_path / "cli" / "telemetry.csv", newline="") as f:
        cli_rows = list(csv.reader(f))
    header, cli_rows = cli_rows[0], cli_rows[1:]

    world = hof.load(project)
    report, telemetry = world.run()
    assert list(telemetry) == header
    assert len(telemetry["t"]) == len(cli_rows) > 100
    for i, cli in enumerate(cli_rows):
        mine = []
        for name in header:
            value = telemetry[name][i]
            if name == "contact":
                mine.append("1" if value else "0")
            elif isinstance(value, (np.floating, float)):
                mine.append(csv_number(float(value)))
            else:
                mine.append(str(value))
        assert mine == cli, f"row {i + 1} differs"
    with open(tmp_path / "cli" / "summary.json") as f:
        cli_summary = json.load(f)
    assert without_machine(report) == without_machine(cli_summary)
    assert report["max_force_n"] > 0.1  # a run that touched something


def test_the_report_folder_from_python_holds_what_hof_run_writes(examples, tmp_path):
    world = hof.load(examples / "liver-palpation-simple.hof")
    report, _ = world.run(1.0, out=tmp_path / "report")
    written = {p.name for p in (tmp_path / "report").iterdir()}
    assert {"telemetry.csv", "summary.json", "Liver.vtu"} <= written
    with open(tmp_path / "report" / "summary.json") as f:
        assert json.load(f)["haptic"]["ticks"] == report["haptic"]["ticks"] == 1000


def test_state_arrays_have_their_shapes_and_are_copies(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    x = world.positions()
    rest = world.rest_positions()
    assert x.shape == rest.shape == world.velocities().shape == world.forces().shape
    assert x.dtype == np.float64 and x.shape[1] == 3
    np.testing.assert_array_equal(x, rest)  # nothing has moved yet
    tets = world.tets()
    assert tets.dtype == np.int32 and tets.shape[1] == 4 and tets.max() < len(x)
    assert world.masses().shape == (len(x),) and world.masses().min() > 0
    x[:] = 0.0  # a copy: the world is untouched
    np.testing.assert_array_equal(world.positions(), rest)
    world.run(2.0)
    moved = np.linalg.norm(world.positions() - rest, axis=1)
    assert moved.max() > 1e-4  # the probe pressed it
    fixed = world.fixed_nodes()
    assert len(fixed) > 0 and moved[fixed].max() == 0.0  # held nodes stay put


def test_the_surface_and_its_normals_follow_the_body_and_point_outward(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    vertices, triangles = world.surface()
    assert triangles.dtype == np.int32 and triangles.max() < len(vertices)
    normals = world.normals()
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
    outward = np.einsum("ij,ij->i", normals, vertices - vertices.mean(axis=0))
    assert (outward > 0).mean() > 0.9  # a liver is not convex everywhere, but nearly
    world.run(1.5)
    after, _ = world.surface()
    assert np.abs(after - vertices).max() > 1e-4


def test_arrays_outlive_their_world():
    world = hof.load(os.path.join(os.environ["HOF_SOURCE_DIR"], "examples", "liver-palpation-simple.hof"))
    x = world.positions()
    surface, triangles = world.surface()
    del world
    gc.collect()
    assert np.isfinite(x).all() and x.sum() != 0.0 and len(surface) > 0 and len(triangles) > 0


def test_step_advances_the_simulated_time(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    world.step(5)
    assert world.time == pytest.approx(5 * world.dt)
    world.step()
    assert world.time == pytest.approx(6 * world.dt)
    with pytest.raises(ValueError, match="steps must be >= 0"):
        world.step(-1)


def test_parameters_go_through_the_command_seam_with_its_checks(examples, tmp_path):
    world = hof.load(examples / "liver-palpation-medium-fem.hof")
    assert world.get("Liver/FEM", "youngModulus") == 5400.0
    world.set("Liver/FEM", "youngModulus", 8000)
    assert world.get("Liver/FEM", "youngModulus") == 8000.0
    assert "Liver/FEM/youngModulus" in world.parameters()
    with pytest.raises(ValueError, match="youngModulus"):
        world.set("Liver/FEM", "youngModulus", -5)
    with pytest.raises(ValueError, match="no component 'nope'"):
        world.set("Liver/nope", "youngModulus", 1)
    with pytest.raises(ValueError, match="no body 'Spleen'"):
        world.get("Spleen/FEM", "youngModulus")
    assert world.get("Liver/FEM", "youngModulus") == 8000.0  # refused commands change nothing
    # Saved, the change is in the project; loaded again, the world has it.
    world.save(tmp_path / "stiffer.hof")
    again = hof.load(tmp_path / "stiffer.hof")
    assert again.get("Liver/FEM", "youngModulus") == 8000.0


def test_a_stiffer_liver_pushes_back_harder(examples):
    peaks = []
    for young in (3000.0, 12000.0):
        world = hof.load(examples / "liver-palpation-medium-fem.hof")
        world.set("Liver/FEM", "youngModulus", young)
        report, telemetry = world.run(3.0)
        assert report["fall_through_events"] == 0
        peaks.append(report["max_force_n"])
    assert peaks[1] > 1.2 * peaks[0]


def test_a_python_function_is_a_device_in_the_world_frame(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    vertices, _ = world.surface()
    top = vertices[np.argmax(vertices[:, 2])]
    # Down onto the highest point of the liver, 5 mm into it, then hold.
    press = lambda t: top + np.array([0.0, 0.0, 0.02 - 0.025 * min(t, 1.0)])
    report, telemetry = world.run(1.5, device=press)
    assert report["contact_time_s"] > 0.2
    np.testing.assert_allclose(telemetry["device_z"][-1], top[2] - 0.005, atol=1e-9)
    assert telemetry["force_z"][-1] > 0.05  # pushed back up
    assert world.contact()["body"] == "Liver"


@pytest.mark.parametrize("bad, error", [(lambda t: 1 / 0, ZeroDivisionError),
                                        (lambda t: (0.0, float("nan"), 0.0), ValueError),
                                        (lambda t: (1.0, 2.0), ValueError),
                                        (lambda t: "up", ValueError)])
def test_a_failing_device_function_ends_the_run_with_its_error(bad, error, examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    with pytest.raises(error):
        world.run(1.0, device=bad)
    world.step(3)  # the world is still usable


def test_a_device_function_is_refused_in_real_time(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    with pytest.raises(ValueError, match="virtual time only"):
        world.run(0.1, device=lambda t: (0, 0, 0), deterministic=False)


def test_ctrl_c_stops_a_run_after_its_step_and_leaves_the_world_usable(examples):
    world = hof.load(examples / "liver-palpation-medium-fem.hof")
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            world.run(600.0)
    finally:
        timer.cancel()
    assert 0.0 < world.time < 600.0
    world.step(2)


def test_a_real_time_run_reports_its_rates(examples):
    world = hof.load(examples / "liver-palpation-simple.hof")
    report, telemetry = world.run(0.5, deterministic=False)
    assert report["mode"] == "real-time"
    assert report["haptic"]["ticks"] > 100 and len(telemetry["t"]) > 100


def test_bad_inputs_are_python_exceptions_with_the_command_lines_messages(examples, tmp_path, anchors):
    with pytest.raises(FileNotFoundError, match="nowhere.hof"):
        hof.load(tmp_path / "nowhere.hof")
    with pytest.raises(OSError, match="folder"):
        hof.load(tmp_path)
    broken = tmp_path / "broken.hof"
    broken.write_text("<hof version='1'><mechanics scene='liver.scn'>")
    with pytest.raises(hof.Error, match="broken.hof"):
        hof.load(broken)
    with pytest.raises(ValueError, match="spec"):
        hof.load(examples / "liver-palpation-simple.hof", device="warp-drive")
    world = hof.load(examples / "liver-palpation-simple.hof")
    with pytest.raises(IndexError, match="out of range"):
        world.positions(3)
    with pytest.raises(KeyError, match="no body 'Heart'"):
        world.positions("Heart")
    with pytest.raises(TypeError):
        world.positions(1.5)
    with pytest.raises(ValueError, match="seconds"):
        world.run(-1.0)
    with pytest.raises(TypeError, match="device"):
        world.run(0.1, device=42)


def test_a_sofa_scene_from_the_sofa_project_loads_and_runs(anchors):
    world = hof.load(anchors / "sofa" / "liver.scn")
    assert world.length_unit == "scene units"
    report, telemetry = world.run()
    assert report["default_probe"] and report["contact_time_s"] > 0.5
    assert math.isfinite(telemetry["force_x"].sum())


def test_the_windows_settings_go_through_the_same_seam_and_are_saved(examples, tmp_path):
    world = hof.load(examples / "liver-palpation-simple.hof")
    world.set("haptics/surface", "stiffness", 0.4)
    world.set("haptics", "renderer", "GodObjectRenderer")
    world.set("haptics/safety", "maxForce", 1.5)
    report, telemetry = world.run(2.0)
    assert report["commands"] == ["step 0: surface of Liver", "step 0: renderer", "step 0: force limit 1.5 N"]
    force = np.sqrt(telemetry["force_x"] ** 2 + telemetry["force_y"] ** 2 + telemetry["force_z"] ** 2)
    assert force.max() <= 1.5 + 1e-12 and report["max_force_n"] == pytest.approx(1.5)
    with pytest.raises(ValueError, match="stiffness=\"soft\" is not a number"):
        world.set("haptics/surface", "stiffness", "soft")
    with pytest.raises(ValueError, match="has no attribute 'nope'"):
        world.set("haptics/surface", "nope", 1)
    with pytest.raises(TypeError, match="a mechanics parameter is a number"):
        world.set("Liver/springs", "stiffness", "stiff")
    with pytest.warns(UserWarning, match="takes effect when the project is loaded again"):
        world.set("haptics", "hapticRate", 2000)
    world.save(tmp_path / "tuned.hof")
    text = (tmp_path / "tuned.hof").read_text()
    assert 'renderer="GodObjectRenderer"' in text and 'hapticRate="2000"' in text and 'maxForce="1.5"' in text
    assert 'stiffness="0.4"' in text
    again = hof.load(tmp_path / "tuned.hof")  # its scene found from the new folder
    assert again.bodies == ["Liver"]


def cube_mesh(size=0.04, cells=3):
    """A cube of tetrahedra (six per cell), nodes on a grid, z up."""
    n = cells + 1
    grid = np.array([[i, j, k] for k in range(n) for j in range(n) for i in range(n)], dtype=float) * size / cells
    index = lambda i, j, k: i + n * (j + n * k)
    tets = []
    for i in range(cells):
        for j in range(cells):
            for k in range(cells):
                c = [index(i + a, j + b, k + d) for d in (0, 1) for b in (0, 1) for a in (0, 1)]
                # Six tetrahedra around the cell's diagonal 0-7 (Kuhn triangulation), positively oriented.
                for p in ((0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)):
                    tets.append([c[q] for q in p])
    return grid, np.array(tets, dtype=np.int32)


def test_a_world_from_arrays_is_built_like_a_files_world_and_can_be_saved(tmp_path):
    nodes, tets = cube_mesh()
    held = nodes[:, 2] == 0.0
    body = hof.Body.from_arrays(nodes, tets, material={"young_modulus": 3000.0, "density": 1000.0}, fixed=held, name="Cube")
    world = hof.build([body], folder=tmp_path / "cube")
    assert world.bodies == ["Cube"] and world.get("Cube/FEM", "youngModulus") == 3000.0
    np.testing.assert_array_equal(world.rest_positions(), nodes)
    np.testing.assert_array_equal(world.tets(), tets)
    assert world.masses().sum() == pytest.approx(1000.0 * 0.04 ** 3, rel=1e-9)
    np.testing.assert_array_equal(world.fixed_nodes(), np.flatnonzero(held))
    report, telemetry = world.run(1.6)  # the default probe presses the cube, and holds
    assert report["contact_time_s"] > 0.3 and report["fall_through_events"] == 0
    moved = np.linalg.norm(world.positions() - nodes, axis=1)
    assert moved.max() > 1e-4 and moved[held].max() == 0.0
    world.save(tmp_path / "cube.hof")
    assert hof.load(tmp_path / "cube.hof").bodies == ["Cube"]


def test_a_liver_mesh_becomes_a_body_of_the_world():
    liver = hof.mesh.generate_liver("simple")
    base = liver.nodes[:, 2] < liver.nodes[:, 2].min() + 0.01
    world = hof.build([hof.Body.from_mesh(liver, {"model": "neohookean"}, fixed=base, name="Liver")])
    report, _ = world.run(2.0)
    assert report["bodies"][0]["nodes"] == len(liver.nodes) and report["max_force_n"] > 0.0


def test_bodies_from_bad_arrays_or_settings_are_refused_by_name():
    nodes, tets = cube_mesh(cells=1)
    with pytest.raises(ValueError, match="integer node indices"):
        hof.Body.from_arrays(nodes, tets.astype(float))
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        hof.Body.from_arrays(nodes[:, :2], tets)
    with pytest.raises(IndexError, match="names node 99"):
        hof.Body.from_arrays(nodes, np.array([[0, 1, 2, 99]], dtype=np.int32))
    with pytest.raises(ValueError, match="unknown material key"):
        hof.Body.from_arrays(nodes, tets, material={"stiffness": 1})
    with pytest.raises(ValueError, match="unknown model"):
        hof.Body.from_arrays(nodes, tets, material={"model": "jelly"})
    with pytest.raises(IndexError, match="out of range"):
        hof.Body.from_arrays(nodes, tets, fixed=[0, 8])
    with pytest.raises(ValueError, match="one entry per node"):
        hof.Body.from_arrays(nodes, tets, fixed=np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="no tetrahedra"):
        hof.Body.from_arrays(nodes, np.zeros((0, 4), dtype=np.int32))
    with pytest.raises(ValueError, match="youngModulus"):
        hof.build([hof.Body.from_arrays(nodes, tets, material={"young_modulus": -1.0})])
    with pytest.raises(ValueError, match="same name"):
        body = hof.Body.from_arrays(nodes, tets)
        hof.build([body, body])


def test_a_recorded_trajectory_replays_as_the_device(examples, tmp_path):
    world = hof.load(examples / "liver-palpation-simple.hof")  # its calibration is the identity
    _, recorded = world.run(1.5)
    trajectory = tmp_path / "hand.csv"
    rows = zip(recorded["t"], recorded["device_x"], recorded["device_y"], recorded["device_z"])
    trajectory.write_text("t,x,y,z\n" + "".join(f"{t!r},{x!r},{y!r},{z!r}\n" for t, x, y, z in rows))
    again = hof.load(examples / "liver-palpation-simple.hof", device=f"replay:{trajectory}")
    report, replayed = again.run(1.5)
    assert again.device.startswith("replay:")
    for axis in "xyz":
        np.testing.assert_allclose(replayed[f"device_{axis}"], recorded[f"device_{axis}"], atol=1e-12)
    assert report["contact_time_s"] > 0.2


def test_the_telemetry_becomes_a_pandas_frame_where_pandas_is_installed(examples):
    pandas = pytest.importorskip("pandas")
    _, telemetry = hof.load(examples / "liver-palpation-simple.hof").run(0.5)
    frame = hof.telemetry_frame(telemetry)
    assert isinstance(frame, pandas.DataFrame) and list(frame.columns) == list(telemetry)
    assert len(frame) == len(telemetry["t"])
