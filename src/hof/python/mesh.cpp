// hof.mesh: mesh files, reports, meshing and the standard livers.

#include <filesystem>

#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/mesh_report.h"
#include "hof/mesh/tetrahedralize.h"
#include "hof/python/bindings.h"
#include "hof/python/common.h"

namespace hof::python {
namespace {

struct PyMesh {
  mesh::Mesh mesh;
  std::vector<std::string> warnings;
  std::string format;
};

PyMesh mesh_from_arrays(const py::object& nodes, const py::object& tets, const py::object& triangles) {
  PyMesh m;
  m.mesh.nodes = points_from(nodes, "nodes");
  if (!tets.is_none()) m.mesh.tets = indices_from<4>(tets, "tets", m.mesh.nodes.size());
  if (!triangles.is_none()) m.mesh.triangles = indices_from<3>(triangles, "triangles", m.mesh.nodes.size());
  return m;
}

py::dict mesh_info(const PyMesh& m) {
  const mesh::MeshReport r = mesh::make_mesh_report(m.mesh);
  py::dict d;
  d["nodes"] = r.nodes;
  d["tets"] = r.tets;
  d["file_triangles"] = r.file_triangles;
  d["edges"] = r.edges;
  d["surface_triangles"] = r.surface_triangles;
  d["surface_vertices"] = r.surface_vertices;
  d["unused_nodes"] = r.unused_nodes;
  d["bbox_min"] = vec3_array(r.bbox_min);
  d["bbox_max"] = vec3_array(r.bbox_max);
  d["volume_m3"] = r.volume_m3;
  if (r.tets > 0) {
    py::dict q;
    q["min_dihedral_deg"] = r.quality.min_dihedral_deg;
    q["max_dihedral_deg"] = r.quality.max_dihedral_deg;
    q["mean_min_dihedral_deg"] = r.quality.mean_min_dihedral_deg;
    q["min_radius_ratio"] = r.quality.min_radius_ratio;
    q["mean_radius_ratio"] = r.quality.mean_radius_ratio;
    q["min_volume_m3"] = r.quality.min_volume_m3;
    q["max_volume_m3"] = r.quality.max_volume_m3;
    q["inverted"] = r.quality.inverted;
    q["degenerate"] = r.quality.degenerate;
    d["quality"] = q;
  }
  d["closed"] = r.surface.closed_manifold();
  d["problems"] = r.problems;
  if (!m.format.empty()) d["format"] = m.format;
  d["warnings"] = m.warnings;
  return d;
}

}  // namespace

void bind_mesh(py::module_& module) {
  py::module_ mesh_module = module.def_submodule("mesh", "Mesh files, reports, meshing and the standard livers.");
  py::class_<PyMesh>(mesh_module, "Mesh", "A mesh: nodes (n, 3) m, tets (m, 4) and triangles (f, 3) int32 (copies).")
      .def(py::init(&mesh_from_arrays), py::arg("nodes"), py::arg("tets") = py::none(),
           py::arg("triangles") = py::none())
      .def_property_readonly("nodes", [](const PyMesh& m) { return points_array(m.mesh.nodes); })
      .def_property_readonly("tets", [](const PyMesh& m) { return index_array(m.mesh.tets); })
      .def_property_readonly("triangles", [](const PyMesh& m) { return index_array(m.mesh.triangles); })
      .def_property_readonly("warnings", [](const PyMesh& m) { return m.warnings; })
      .def("info", &mesh_info, "The report `hof mesh info` prints, as a dict.")
      .def(
          "write",
          [](const PyMesh& m, const std::filesystem::path& path) {
            Expected<void> ok = [&] {
              py::gil_scoped_release release;
              return mesh::write_mesh(m.mesh, path);
            }();
            ok_or_raise(ok);
          },
          py::arg("path"), "Writes by extension: .msh (Gmsh 4.1), .vtu, .obj, .off.")
      .def("__repr__", [](const PyMesh& m) {
        return fmt::format("<hof.mesh.Mesh: {} nodes, {} tets, {} triangles>", m.mesh.nodes.size(), m.mesh.tets.size(),
                           m.mesh.triangles.size());
      });
  mesh_module.def(
      "read",
      [](const std::filesystem::path& path) {
        Expected<mesh::ReadResult> read = [&] {
          py::gil_scoped_release release;
          return mesh::read_mesh(path);
        }();
        mesh::ReadResult r = value_or_raise(std::move(read));
        return PyMesh{std::move(r.mesh), std::move(r.report.warnings), r.report.format};
      },
      py::arg("path"), "Reads a mesh: Gmsh .msh (v1, v2, v4), .vtu, .obj, .stl, .off.");
  mesh_module.def(
      "generate_liver",
      [](const std::string& resolution) {
        const auto r = mesh::parse_liver_resolution(resolution);
        if (!r) throw py::value_error(fmt::format("unknown liver '{}': simple, coarse, medium or fine", resolution));
        Expected<mesh::Mesh> made = [&] {
          py::gil_scoped_release release;
          return mesh::generate_liver(*r);
        }();
        return PyMesh{value_or_raise(std::move(made)), {}, {}};
      },
      py::arg("resolution") = "medium", "The standard tetrahedral liver: 'simple', 'coarse', 'medium' or 'fine'.");
  mesh_module.def(
      "tetrahedralize",
      [](const PyMesh& surface, double max_volume, double radius_edge_ratio) {
        if (surface.mesh.triangles.empty())
          throw py::value_error("tetrahedralize needs a closed triangle surface (the mesh has no triangles)");
        mesh::TetrahedralizeOptions options;
        options.max_volume_m3 = max_volume;
        options.radius_edge_ratio = radius_edge_ratio;
        Expected<mesh::Mesh> made = [&] {
          py::gil_scoped_release release;
          return mesh::tetrahedralize(mesh::TriMesh{surface.mesh.nodes, surface.mesh.triangles}, options);
        }();
        return PyMesh{value_or_raise(std::move(made)), {}, {}};
      },
      py::arg("surface"), py::arg("max_volume") = 0.0, py::arg("radius_edge_ratio") = 1.414,
      "Fills a closed surface with tetrahedra (TetGen): max_volume m^3 (0: unbounded), the radius-edge quality bound.");
}

}  // namespace hof::python
