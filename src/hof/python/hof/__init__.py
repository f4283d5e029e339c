"""HoF (Haptics Open Framework) for Python: deformable worlds, haptic sessions, meshes.

    import hof
    world = hof.load("examples/liver-palpation-medium.hof")
    report, telemetry = world.run(2.0)          # virtual time: deterministic
    print(report["max_force_n"], telemetry["force_y"].min())

Units are SI everywhere (m, kg, s, N). docs/python.md is the guide.
"""

from __future__ import annotations

import sys as _sys

from ._hof import Error, World, mesh

__all__ = ["Error", "World", "load", "mesh", "telemetry_frame"]

# `import hof.mesh` as well as `hof.mesh`.
_sys.modules[__name__ + ".mesh"] = mesh


def load(path, device: str = "") -> World:
    """The world of a .hof project, a SOFA .scn or an X3D scene, built as `hof run` builds it.

    `device` replaces the file's device (a spec string, as `hof run --device`). Errors are
    FileNotFoundError (no such file), ValueError (a value out of range) or hof.Error (a file
    that does not parse), with the message the command line prints.
    """
    return World.load(path, device)


def telemetry_frame(telemetry: dict):
    """The telemetry of World.run() as a pandas DataFrame (pandas must be installed)."""
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the machine
        raise ImportError("telemetry_frame needs pandas (Debian: apt install python3-pandas)") from e
    return pandas.DataFrame(telemetry)
