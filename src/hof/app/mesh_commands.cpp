#include "hof/app/mesh_commands.h"

#include <algorithm>

#include <fmt/format.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "hof/app/detail/cli_failure.h"
#include "hof/core/progress.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/mesh_report.h"
#include "hof/mesh/tetrahedralize.h"

namespace hof::app {

namespace {

using detail::fail;

Expected<mesh::MshVersion> msh_version(int v) {
  if (v == 2) return mesh::MshVersion::k2_2;
  if (v == 4) return mesh::MshVersion::k4_1;
  return make_error(ErrorCode::kInvalidArgument, fmt::format("--msh-version must be 2 (v2.2) or 4 (v4.1), got {}", v));
}

// A mesh file's numbers carry no unit (Gmsh, OBJ, STL, OFF, VTU alike): lengths are reported
// as the file's numbers unless the user states the unit, and then in metres.
struct LengthUnit {
  bool stated{false};
  double to_m{1.0};
  std::string label{"file units"};
  [[nodiscard]] double volume_to_m3() const { return to_m * to_m * to_m; }
  [[nodiscard]] std::string volume_label() const { return stated ? label + "^3" : "(" + label + ")^3"; }
};

Expected<LengthUnit> length_unit(const std::string& name) {
  if (name.empty()) return LengthUnit{};
  if (name == "m") return LengthUnit{true, 1.0, "m"};
  if (name == "cm") return LengthUnit{true, 1e-2, "m"};
  if (name == "mm") return LengthUnit{true, 1e-3, "m"};
  return make_error(ErrorCode::kInvalidArgument, fmt::format("--unit must be m, cm or mm, got '{}'", name));
}

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json report_json(const std::filesystem::path& file, const mesh::ReadReport& read, const mesh::MeshReport& r,
                           const LengthUnit& unit) {
  nlohmann::json j;
  j["file"] = file.string();
  j["format"] = read.format;
  j["nodes"] = r.nodes;
  j["tetrahedra"] = r.tets;
  j["file_triangles"] = r.file_triangles;
  j["edges"] = r.edges;
  j["surface"] = {{"triangles", r.surface_triangles},
                  {"vertices", r.surface_vertices},
                  {"closed_manifold", r.surface.closed_manifold()},
                  {"outward", r.surface.closed_outward()},
                  {"boundary_edges", r.surface.boundary_edges},
                  {"non_manifold_edges", r.surface.non_manifold_edges},
                  {"non_manifold_vertices", r.surface.non_manifold_vertices},
                  {"misoriented_edges", r.surface.misoriented_edges},
                  {"components", r.surface.components},
                  {"area", r.surface.area_m2 * unit.to_m * unit.to_m}};
  // Lengths in metres when the user stated the file's unit, else in the file's own numbers.
  j["length_unit"] = unit.label;
  j["bounding_box"] = {{"min", vec_json(r.bbox_min * unit.to_m)},
                       {"max", vec_json(r.bbox_max * unit.to_m)},
                       {"size", vec_json((r.bbox_max - r.bbox_min) * unit.to_m)}};
  j["volume"] = r.volume_m3 * unit.volume_to_m3();
  if (r.tets > 0) {
    j["quality"] = {{"min_dihedral_deg", r.quality.min_dihedral_deg},
                    {"max_dihedral_deg", r.quality.max_dihedral_deg},
                    {"mean_min_dihedral_deg", r.quality.mean_min_dihedral_deg},
                    {"min_radius_ratio", r.quality.min_radius_ratio},
                    {"mean_radius_ratio", r.quality.mean_radius_ratio},
                    {"min_tet_volume", r.quality.min_volume_m3 * unit.volume_to_m3()},
                    {"max_tet_volume", r.quality.max_volume_m3 * unit.volume_to_m3()},
                    {"inverted", r.quality.inverted},
                    {"degenerate", r.quality.degenerate}};
  }
  j["ignored"] = {{"points", read.ignored_points}, {"lines", read.ignored_lines}, {"other", read.ignored_other}};
  j["warnings"] = read.warnings;
  j["problems"] = r.problems;
  return j;
}

void print_report(const std::filesystem::path& file, const mesh::ReadReport& read, const mesh::MeshReport& r,
                  const LengthUnit& unit) {
  const Vec3 lo = r.bbox_min * unit.to_m;
  const Vec3 hi = r.bbox_max * unit.to_m;
  const Vec3 size = hi - lo;
  const std::string& u = unit.label;
  fmt::print("{} ({})\n", file.string(), read.format);
  fmt::print("  nodes              {}\n", r.nodes);
  fmt::print("  tetrahedra         {}\n", r.tets);
  fmt::print("  triangles in file  {}\n", r.file_triangles);
  fmt::print("  edges              {}\n", r.edges);
  fmt::print("  surface            {} triangles on {} vertices, {}\n", r.surface_triangles, r.surface_vertices,
             r.surface.closed_outward()    ? "closed, outward"
             : r.surface.closed_manifold() ? "closed, inward"
                                           : "not closed");
  fmt::print("  bounding box       [{:.4g}, {:.4g}, {:.4g}] to [{:.4g}, {:.4g}, {:.4g}] {}\n", lo.x(), lo.y(), lo.z(),
             hi.x(), hi.y(), hi.z(), u);
  fmt::print("  size               {:.4g} x {:.4g} x {:.4g} {}\n", size.x(), size.y(), size.z(), u);
  fmt::print("  volume             {:.6g} {}{}\n", r.volume_m3 * unit.volume_to_m3(), unit.volume_label(),
             r.tets > 0 ? "" : " (enclosed by the triangles)");
  if (r.tets > 0) {
    const auto& q = r.quality;
    fmt::print("  dihedral angles    min {:.2f} deg, max {:.2f} deg, mean of per-tet min {:.2f} deg\n",
               q.min_dihedral_deg, q.max_dihedral_deg, q.mean_min_dihedral_deg);
    fmt::print("  radius ratio       min {:.3f}, mean {:.3f} (1 = regular)\n", q.min_radius_ratio, q.mean_radius_ratio);
    fmt::print("  tet volume         min {:.4g} {}, max {:.4g} {}\n", q.min_volume_m3 * unit.volume_to_m3(),
               unit.volume_label(), q.max_volume_m3 * unit.volume_to_m3(), unit.volume_label());
    fmt::print("  inverted           {}\n", q.inverted);
  }
  if (read.ignored_points + read.ignored_lines + read.ignored_other > 0) {
    fmt::print("  ignored elements   {} points, {} lines, {} other\n", read.ignored_points, read.ignored_lines,
               read.ignored_other);
  }
  for (const std::string& w : read.warnings) fmt::print("  warning: {}\n", w);
  if (!unit.stated) {
    fmt::print("  length unit        not stated by the file (lengths as its numbers); --unit m|cm|mm states it\n");
  }
  if (r.problems.empty()) {
    fmt::print("  problems           none\n");
  } else {
    fmt::print("  problems           {}\n", r.problems.size());
    for (const std::string& p : r.problems) fmt::print("    - {}\n", p);
  }
}

Expected<void> write_with_surface(const mesh::Mesh& m, const std::filesystem::path& output, mesh::MshVersion version) {
  if (output.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(output.parent_path(), ec);
    if (ec) {
      return make_error(ErrorCode::kIo, fmt::format("cannot create folder: {}", ec.message()),
                        output.parent_path().string());
    }
  }
  if (auto ok = mesh::write_mesh(m, output, version); !ok) return ok;
  // The surface beside the volume, for viewers and for the haptic/visual model.
  if (output.extension() == ".msh" && !m.tets.empty()) {
    const mesh::BoundarySurface boundary = mesh::extract_boundary(m.nodes, m.tets);
    mesh::Mesh surface;
    surface.nodes = boundary.surface.vertices;
    surface.triangles = boundary.surface.triangles;
    std::filesystem::path obj = output;
    obj.replace_extension(".obj");
    if (auto ok = mesh::write_obj(surface, obj); !ok) return ok;
  }
  return {};
}

}  // namespace

int run_mesh_info(const MeshInfoOptions& options) {
  const auto unit = length_unit(options.unit);
  if (!unit) return fail(unit.error());
  auto read = mesh::read_mesh(options.file, make_terminal_progress(options.quiet || options.json));
  if (!read) return fail(read.error());
  const mesh::MeshReport report = mesh::make_mesh_report(read->mesh);
  if (options.json) {
    fmt::print("{}\n", report_json(options.file, read->report, report, *unit).dump(2));
  } else {
    print_report(options.file, read->report, report, *unit);
  }
  return 0;
}

int run_mesh_generate(const MeshGenerateOptions& options) {
  if (options.shape != "liver") {
    return fail(fmt::format("unknown shape '{}': the generator makes 'liver'", options.shape));
  }
  const auto resolution = mesh::parse_liver_resolution(options.resolution);
  if (!resolution) {
    return fail(fmt::format("unknown resolution '{}': use simple, coarse, medium or fine", options.resolution));
  }
  const auto version = msh_version(options.msh_version);
  if (!version) return fail(version.error());
  auto liver = mesh::generate_liver(*resolution, make_terminal_progress(options.quiet));
  if (!liver) return fail(liver.error());
  if (auto ok = write_with_surface(*liver, options.output, *version); !ok) return fail(ok.error());
  if (!options.quiet) {
    fmt::print(stderr, "wrote {} ({} nodes, {} tetrahedra, {} surface triangles)\n", options.output.string(),
               liver->nodes.size(), liver->tets.size(), liver->triangles.size());
  }
  return 0;
}

int run_mesh_tetrahedralize(const MeshTetrahedralizeOptions& options) {
  const auto version = msh_version(options.msh_version);
  if (!version) return fail(version.error());
  auto progress = make_terminal_progress(options.quiet);
  auto read = mesh::read_mesh(options.surface, progress);
  if (!read) return fail(read.error());
  if (read->mesh.triangles.empty()) {
    return fail(fmt::format("{}: has no triangles to mesh", options.surface.string()));
  }
  mesh::TriMesh surface{read->mesh.nodes, read->mesh.triangles};
  mesh::TetrahedralizeOptions tet_options;
  tet_options.max_volume_m3 = options.max_volume_m3;
  tet_options.radius_edge_ratio = options.quality;
  tet_options.min_dihedral_deg = options.min_dihedral_deg;
  tet_options.preserve_surface = options.preserve_surface;
  progress("tetrahedralizing", -1.0);
  auto volume = mesh::tetrahedralize(surface, tet_options, options.surface.string());
  progress("tetrahedralizing", 1.0);
  if (!volume) return fail(volume.error());
  if (auto ok = write_with_surface(*volume, options.output, *version); !ok) return fail(ok.error());
  if (!options.quiet) {
    fmt::print(stderr, "wrote {} ({} nodes, {} tetrahedra)\n", options.output.string(), volume->nodes.size(),
               volume->tets.size());
  }
  return 0;
}

int run_mesh_convert(const MeshConvertOptions& options) {
  const auto version = msh_version(options.msh_version);
  if (!version) return fail(version.error());
  auto read = mesh::read_mesh(options.input, make_terminal_progress(options.quiet));
  if (!read) return fail(read.error());
  mesh::Mesh out = std::move(read->mesh);
  std::string ext = options.output.extension().string();
  std::ranges::transform(ext, ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // Surface formats hold triangles only: the file's own triangles (a Gmsh file's boundary), else
  // the boundary of its tetrahedra, on just the nodes they use — a volume's interior nodes in
  // an OBJ would be vertices of no face.
  if (ext == ".obj" || ext == ".off" || ext == ".stl") {
    std::vector<mesh::Tri> triangles = out.triangles;
    if (triangles.empty() && !out.tets.empty())
      triangles = mesh::extract_boundary(out.nodes, out.tets).volume_triangles;
    std::vector<std::int32_t> new_index(out.nodes.size(), -1);
    mesh::Mesh surface;
    for (mesh::Tri& t : triangles) {
      for (mesh::NodeIndex& i : t) {
        const auto old_index = static_cast<std::size_t>(i);
        if (new_index[old_index] < 0) {
          new_index[old_index] = static_cast<std::int32_t>(surface.nodes.size());
          surface.nodes.push_back(out.nodes[old_index]);
        }
        i = new_index[old_index];
      }
    }
    surface.triangles = std::move(triangles);
    out = std::move(surface);
  }
  if (auto ok = mesh::write_mesh(out, options.output, *version); !ok) return fail(ok.error());
  if (!options.quiet) {
    fmt::print(stderr, "wrote {} ({} nodes, {} tetrahedra, {} triangles)\n", options.output.string(), out.nodes.size(),
               out.tets.size(), out.triangles.size());
  }
  return 0;
}

}  // namespace hof::app
