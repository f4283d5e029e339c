"""HoF (Haptics Open Framework) for Python: deformable worlds, haptic sessions, meshes.

    import hof
    world = hof.load("examples/liver-palpation-medium.hof")
    report, telemetry = world.run(2.0)          # virtual time: deterministic
    print(report["max_force_n"], telemetry["force_y"].min())

Units are SI everywhere (m, kg, s, N). docs/python.md is the guide.
"""

from __future__ import annotations

import os as _os
import sys as _sys
import tempfile as _tempfile
from xml.sax.saxutils import quoteattr as _quoteattr

import numpy as _np

from ._hof import Error, World, mesh

__all__ = ["Body", "Error", "World", "build", "load", "mesh", "telemetry_frame"]

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


# Force fields a Body can have: SOFA's component and its `method`.
_MODELS = {
    "corotational": ("TetrahedronFEMForceField", "large"),
    "linear": ("TetrahedronFEMForceField", "small"),
    "polar": ("TetrahedronFEMForceField", "polar"),
    "neohookean": ("TetrahedronHyperelasticityFEMForceField", None),
}
_MATERIAL_KEYS = {"young_modulus", "poisson_ratio", "density", "model"}


class Body:
    """A deformable body from arrays: a tetrahedral mesh, a material, the nodes it is held by.

    `hof.build([body, ...])` makes a world of such bodies (the builder reads them as a SOFA
    scene it writes: the same path as a file's bodies, the same checks and defaults).
    """

    def __init__(self, name: str, mesh_: "mesh.Mesh", material: dict | None = None, fixed=None):
        material = dict(material or {})
        unknown = set(material) - _MATERIAL_KEYS
        if unknown:
            raise ValueError(f"body '{name}': unknown material key(s) {sorted(unknown)} (known: {sorted(_MATERIAL_KEYS)})")
        self.name = str(name)
        if not self.name or any(c in self.name for c in "/@ "):
            raise ValueError(f"a body's name must be non-empty without '/', '@' or spaces, got {name!r}")
        self.mesh = mesh_
        if len(mesh_.tets) == 0:
            raise ValueError(f"body '{name}': the mesh has no tetrahedra (tetrahedralize a surface with hof.mesh.tetrahedralize)")
        self.young_modulus = float(material.get("young_modulus", 5000.0))  # Pa, liver (literature.md)
        self.poisson_ratio = float(material.get("poisson_ratio", 0.45))
        self.density = float(material.get("density", 1060.0))  # kg/m^3
        self.model = material.get("model", "corotational")
        if self.model not in _MODELS:
            raise ValueError(f"body '{name}': unknown model {self.model!r} (known: {sorted(_MODELS)})")
        self.fixed = self._fixed_nodes(fixed, len(mesh_.nodes))

    @classmethod
    def from_arrays(cls, nodes, tets, material: dict | None = None, fixed=None, name: str = "Body") -> "Body":
        """A body of `nodes` ((n, 3) float64, m) and `tets` ((m, 4) int32 node indices).

        `material`: young_modulus (Pa, 5000), poisson_ratio (0.45), density (kg/m^3, 1060),
        model ("corotational", "linear", "polar" or "neohookean"). `fixed`: the nodes held,
        as indices or an (n,) boolean mask. Arrays are converted when no value is lost (float32
        nodes, Fortran order); float indices, a wrong shape or an index out of range raise.
        """
        return cls(name, mesh.Mesh(nodes, tets=tets), material, fixed)

    @classmethod
    def from_mesh(cls, mesh_: "mesh.Mesh", material: dict | None = None, fixed=None, name: str = "Body") -> "Body":
        """A body of a mesh (hof.mesh.read, hof.mesh.generate_liver, hof.mesh.tetrahedralize)."""
        return cls(name, mesh_, material, fixed)

    @staticmethod
    def _fixed_nodes(fixed, count: int) -> _np.ndarray:
        if fixed is None:
            return _np.zeros(0, dtype=_np.int64)
        array = _np.asarray(fixed)
        if array.dtype == bool:
            if array.shape != (count,):
                raise ValueError(f"fixed: a boolean mask must have one entry per node ({count}), got shape {array.shape}")
            return _np.flatnonzero(array)
        if array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
            raise ValueError("fixed: node indices (a 1-D integer array) or an (n,) boolean mask")
        if array.size and (array.min() < 0 or array.max() >= count):
            raise IndexError(f"fixed: node {int(array.min() if array.min() < 0 else array.max())} is out of range "
                             f"(the mesh has {count} nodes)")
        return _np.unique(array.astype(_np.int64))

    def _scene_node(self, mesh_file: str) -> str:
        component, method = _MODELS[self.model]
        if method:
            fem = (f'<{component} name="FEM" youngModulus="{self.young_modulus!r}" poissonRatio="{self.poisson_ratio!r}" '
                   f'method="{method}"/>')
        else:
            # SOFA's NeoHookean takes the shear and bulk moduli: mu = E / 2(1 + nu), k = E / 3(1 - 2 nu).
            mu = self.young_modulus / (2.0 * (1.0 + self.poisson_ratio))
            bulk = self.young_modulus / (3.0 * (1.0 - 2.0 * self.poisson_ratio))
            fem = f'<{component} name="FEM" materialName="NeoHookean" ParameterSet="{mu!r} {bulk!r}"/>'

        lines = [f"  <Node name={_quoteattr(self.name)}>",
                 '    <EulerImplicitSolver name="solver" rayleighStiffness="0.1" rayleighMass="0.1"/>',
                 '    <CGLinearSolver name="cg" iterations="25" tolerance="1e-9" threshold="1e-9"/>',
                 f"    <MeshGmshLoader name=\"loader\" filename={_quoteattr(mesh_file)}/>",
                 '    <MeshTopology name="topology" src="@loader"/>',
                 '    <MechanicalObject name="dofs" src="@loader"/>',
                 f'    <DiagonalMass name="mass" massDensity="{self.density!r}"/>',
                 "    " + fem]
        if len(self.fixed):
            lines.append('    <FixedProjectiveConstraint name="fixed" indices="' + " ".join(map(str, self.fixed)) + '"/>')
        lines.append("  </Node>")
        return "\n".join(lines)


def build(bodies, folder=None, dt: float = 0.01, gravity=(0.0, 0.0, 0.0), device: str = "") -> World:
    """A world of Body objects. Their meshes (Gmsh) and a SOFA scene (world.scn) are written
    into `folder` (default: a new folder under the system's temporary one, kept, so that the
    world can be saved as a project that refers to them), and the world is built from it as
    `hof.load` builds any scene: with the default probe, unless `device` names another.
    """
    bodies = list(bodies)
    if not bodies or not all(isinstance(b, Body) for b in bodies):
        raise TypeError("build() takes a list of hof.Body")
    names = [b.name for b in bodies]
    if len(set(names)) != len(names):
        raise ValueError(f"two bodies have the same name: {names}")
    folder = _tempfile.mkdtemp(prefix="hof-world-") if folder is None else _os.fspath(folder)
    _os.makedirs(folder, exist_ok=True)
    nodes = []
    for body in bodies:
        mesh_file = f"{body.name}.msh"
        body.mesh.write(_os.path.join(folder, mesh_file))
        nodes.append(body._scene_node(mesh_file))
    g = " ".join(repr(float(v)) for v in gravity)
    scene = (f'<?xml version="1.0"?>\n<!-- Written by hof.build() (Python). SI units. -->\n'
             f'<Node name="root" dt="{float(dt)!r}" gravity="{g}">\n' + "\n".join(nodes) + "\n</Node>\n")
    path = _os.path.join(folder, "world.scn")
    with open(path, "w", encoding="utf-8") as f:
        f.write(scene)
    return load(path, device)
