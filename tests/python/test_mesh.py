"""Meshes from Python: files, reports, meshing, the standard livers, and refused arrays."""

import numpy as np
import pytest

import hof
import hof.mesh


def test_the_sofa_liver_reads_and_reports_as_hof_mesh_info(anchors):
    liver = hof.mesh.read(anchors / "sofa" / "mesh" / "liver.msh")
    info = liver.info()
    assert info["nodes"] == len(liver.nodes) == 181  # SOFA's liver.msh
    assert info["tets"] == len(liver.tets) > 0
    assert info["quality"]["inverted"] == 0
    assert info["volume_m3"] > 0.0
    assert info["format"].startswith("gmsh")
    np.testing.assert_array_equal(info["bbox_min"], liver.nodes.min(axis=0))
    np.testing.assert_array_equal(info["bbox_max"], liver.nodes.max(axis=0))


@pytest.mark.parametrize("extension", [".msh", ".vtu"])
def test_a_mesh_written_and_read_back_is_the_same(extension, tmp_path):
    liver = hof.mesh.generate_liver("simple")
    liver.write(tmp_path / f"liver{extension}")
    again = hof.mesh.read(tmp_path / f"liver{extension}")
    np.testing.assert_array_equal(again.nodes, liver.nodes)
    np.testing.assert_array_equal(again.tets, liver.tets)
    np.testing.assert_array_equal(again.triangles, liver.triangles)


def test_a_surface_from_arrays_is_tetrahedralized_into_its_volume():
    # A unit cube's surface, triangles counter-clockwise seen from outside.
    nodes = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float) * 0.1
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], dtype=np.int32)
    cube = hof.mesh.Mesh(nodes, triangles=triangles)
    assert cube.info()["closed"]
    solid = hof.mesh.tetrahedralize(cube, max_volume=1e-5)
    info = solid.info()
    assert info["volume_m3"] == pytest.approx(1e-3, rel=1e-9)
    assert info["tets"] >= 100 and info["quality"]["inverted"] == 0
    with pytest.raises(hof.Error, match="open|closed|manifold"):
        hof.mesh.tetrahedralize(hof.mesh.Mesh(nodes, triangles=triangles[:-2]))


def test_the_standard_livers_grow_with_their_resolution():
    simple = hof.mesh.generate_liver("simple")
    coarse = hof.mesh.generate_liver("coarse")
    assert 0 < len(simple.tets) < len(coarse.tets)
    with pytest.raises(ValueError, match="unknown liver 'huge'"):
        hof.mesh.generate_liver("huge")


def test_arrays_of_the_wrong_shape_type_or_range_are_refused():
    nodes = np.zeros((4, 3))
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        hof.mesh.Mesh(np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        hof.mesh.Mesh("nodes")
    with pytest.raises(ValueError, match="not finite"):
        hof.mesh.Mesh(np.array([[0.0, np.nan, 0.0]]))
    with pytest.raises(ValueError, match="integer"):
        hof.mesh.Mesh(nodes, tets=np.zeros((1, 4)))  # float indices
    with pytest.raises(ValueError, match=r"\(m, 4\)"):
        hof.mesh.Mesh(nodes, tets=np.zeros((1, 3), dtype=np.int32))
    with pytest.raises(IndexError, match="names node 4, but there are 4 nodes"):
        hof.mesh.Mesh(nodes, tets=np.array([[0, 1, 2, 4]], dtype=np.int32))
    with pytest.raises(IndexError, match="names node -1"):
        hof.mesh.Mesh(nodes, triangles=np.array([[0, 1, -1]]))
    # Fortran order and other float types are converted, not refused.
    mesh = hof.mesh.Mesh(np.asfortranarray(np.eye(3, dtype=np.float32)))
    np.testing.assert_array_equal(mesh.nodes, np.eye(3))


def test_missing_and_malformed_files_name_themselves(tmp_path):
    with pytest.raises(FileNotFoundError, match="absent.msh"):
        hof.mesh.read(tmp_path / "absent.msh")
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\nmany\n")
    with pytest.raises(hof.Error, match="bad.msh:5"):
        hof.mesh.read(bad)
    with pytest.raises(OSError):
        hof.mesh.generate_liver("simple").write(tmp_path / "no-such-folder" / "x.msh")
