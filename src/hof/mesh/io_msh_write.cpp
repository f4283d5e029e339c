/// @file
/// Gmsh .msh writing: v2.2 ASCII (what most tools read) and v4.1 ASCII (entities, one block
/// per region and element type), node tags 1..N in the mesh's order.

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hof/mesh/detail/text_reader.h"
#include "hof/mesh/mesh_io.h"

namespace hof::mesh {

namespace {

std::int32_t region_of(const std::vector<std::int32_t>& regions, std::size_t i) {
  return regions.empty() ? 0 : regions[i];
}

void append_node_line(std::string& out, std::int64_t tag, const Vec3& p) {
  if (tag >= 0) {
    detail::append_int(out, tag);
    out += ' ';
  }
  detail::append_real(out, p.x());
  out += ' ';
  detail::append_real(out, p.y());
  out += ' ';
  detail::append_real(out, p.z());
  out += '\n';
}

std::string format_v22(const Mesh& mesh) {
  std::string out;
  out.reserve(64 * (mesh.nodes.size() + mesh.tets.size() + mesh.triangles.size()) + 256);
  out += "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n";
  detail::append_int(out, static_cast<std::int64_t>(mesh.nodes.size()));
  out += '\n';
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    append_node_line(out, static_cast<std::int64_t>(i) + 1, mesh.nodes[i]);
  }
  out += "$EndNodes\n$Elements\n";
  detail::append_int(out, static_cast<std::int64_t>(mesh.triangles.size() + mesh.tets.size()));
  out += '\n';
  // "number type 2 physical elementary nodes..." with the region as both tags; triangles
  // first, as Gmsh orders elements by dimension.
  std::int64_t number = 1;
  const auto element = [&](int type, std::int32_t region, const NodeIndex* nodes, int n) {
    detail::append_int(out, number++);
    out += ' ';
    detail::append_int(out, type);
    out += " 2 ";
    detail::append_int(out, region);
    out += ' ';
    detail::append_int(out, region);
    for (int k = 0; k < n; ++k) {
      out += ' ';
      detail::append_int(out, std::int64_t{nodes[k]} + 1);
    }
    out += '\n';
  };
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    element(2, region_of(mesh.triangle_regions, i), mesh.triangles[i].data(), 3);
  }
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    element(4, region_of(mesh.tet_regions, i), mesh.tets[i].data(), 4);
  }
  out += "$EndElements\n";
  return out;
}

/// Axis-aligned bounds of the nodes of one region's elements ($Entities wants them).
struct Bounds {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -Vec3::Constant(std::numeric_limits<double>::infinity());
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
};

template <class Element>
std::map<std::int32_t, Bounds> region_bounds(const Mesh& mesh, const std::vector<Element>& elements,
                                             const std::vector<std::int32_t>& regions) {
  std::map<std::int32_t, Bounds> result;
  for (std::size_t i = 0; i < elements.size(); ++i) {
    Bounds& b = result[region_of(regions, i)];
    for (const NodeIndex v : elements[i]) b.add(mesh.nodes[static_cast<std::size_t>(v)]);
  }
  return result;
}

/// Element blocks of v4.1: one per run of consecutive elements with the same region, so
/// the element order survives a round trip even when regions interleave.
template <class Element>
void append_v41_blocks(std::string& out, std::int64_t& tag, int dim, int type, const std::vector<Element>& elements,
                       const std::vector<std::int32_t>& regions) {
  std::size_t begin = 0;
  while (begin < elements.size()) {
    const std::int32_t region = region_of(regions, begin);
    std::size_t end = begin + 1;
    while (end < elements.size() && region_of(regions, end) == region) ++end;
    detail::append_int(out, dim);
    out += ' ';
    detail::append_int(out, region);
    out += ' ';
    detail::append_int(out, type);
    out += ' ';
    detail::append_int(out, static_cast<std::int64_t>(end - begin));
    out += '\n';
    for (std::size_t i = begin; i < end; ++i) {
      detail::append_int(out, tag++);
      for (const NodeIndex v : elements[i]) {
        out += ' ';
        detail::append_int(out, std::int64_t{v} + 1);
      }
      out += '\n';
    }
    begin = end;
  }
}

template <class Element>
std::int64_t count_runs(const std::vector<Element>& elements, const std::vector<std::int32_t>& regions) {
  std::int64_t runs = 0;
  for (std::size_t i = 0; i < elements.size(); ++i) {
    if (i == 0 || region_of(regions, i) != region_of(regions, i - 1)) ++runs;
  }
  return runs;
}

std::string format_v41(const Mesh& mesh) {
  std::string out;
  out.reserve(64 * (mesh.nodes.size() + mesh.tets.size() + mesh.triangles.size()) + 512);
  out += "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";

  // $Entities: one surface per triangle region, one volume per tet region, each carrying
  // the region as its physical group too, so Gmsh shows the regions as physical groups.
  // A mesh without elements puts its nodes in volume 1.
  auto surfaces = region_bounds(mesh, mesh.triangles, mesh.triangle_regions);
  auto volumes = region_bounds(mesh, mesh.tets, mesh.tet_regions);
  if (surfaces.empty() && volumes.empty()) {
    Bounds& b = volumes[1];
    for (const Vec3& p : mesh.nodes) b.add(p);
  }
  out += "$Entities\n0 0 ";
  detail::append_int(out, static_cast<std::int64_t>(surfaces.size()));
  out += ' ';
  detail::append_int(out, static_cast<std::int64_t>(volumes.size()));
  out += '\n';
  for (const auto* entities : {&surfaces, &volumes}) {
    for (const auto& [tag, b] : *entities) {
      detail::append_int(out, tag);
      for (const double v : {b.lo.x(), b.lo.y(), b.lo.z(), b.hi.x(), b.hi.y(), b.hi.z()}) {
        out += ' ';
        detail::append_real(out, v);
      }
      out += tag > 0 ? " 1 " + std::to_string(tag) + " 0\n" : std::string(" 0 0\n");
    }
  }
  out += "$EndEntities\n";

  // All nodes in one block, on the entity of the first element (or volume 1).
  int node_dim = 3;
  std::int32_t node_entity = 1;
  if (!mesh.tets.empty()) {
    node_entity = region_of(mesh.tet_regions, 0);
  } else if (!mesh.triangles.empty()) {
    node_dim = 2;
    node_entity = region_of(mesh.triangle_regions, 0);
  }
  const auto n = static_cast<std::int64_t>(mesh.nodes.size());
  out += "$Nodes\n1 ";
  detail::append_int(out, n);
  out += " 1 ";
  detail::append_int(out, n);
  out += '\n';
  detail::append_int(out, node_dim);
  out += ' ';
  detail::append_int(out, node_entity);
  out += " 0 ";
  detail::append_int(out, n);
  out += '\n';
  for (std::int64_t i = 1; i <= n; ++i) {
    detail::append_int(out, i);
    out += '\n';
  }
  for (const Vec3& p : mesh.nodes) append_node_line(out, -1, p);
  out += "$EndNodes\n";

  const auto elements = static_cast<std::int64_t>(mesh.triangles.size() + mesh.tets.size());
  out += "$Elements\n";
  detail::append_int(out, count_runs(mesh.triangles, mesh.triangle_regions) + count_runs(mesh.tets, mesh.tet_regions));
  out += ' ';
  detail::append_int(out, elements);
  out += elements > 0 ? " 1 " : " 0 ";
  detail::append_int(out, elements);
  out += '\n';
  std::int64_t tag = 1;
  append_v41_blocks(out, tag, 2, 2, mesh.triangles, mesh.triangle_regions);
  append_v41_blocks(out, tag, 3, 4, mesh.tets, mesh.tet_regions);
  out += "$EndElements\n";
  return out;
}

}  // namespace

Expected<void> write_msh(const Mesh& mesh, const std::filesystem::path& path, MshVersion version) {
  if (auto ok = detail::check_mesh_for_write(mesh, path); !ok) return ok;
  return detail::write_whole_file(path, version == MshVersion::k2_2 ? format_v22(mesh) : format_v41(mesh));
}

}  // namespace hof::mesh
