// SOFA scenes: the links, files and geometry of the components — `@` links and their paths,
// files found as SOFA finds them (the scene's folder and its parents, SOFA_DATA_PATH, SOFA_ROOT),
// the data a loader, topology or state gives (positions, tetrahedra, triangles) and the
// transforms loaders and states apply. The reader's walk is in sofa_scene.cpp.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include <fmt/format.h>

#include "hof/mesh/mesh_io.h"
#include "hof/scene/sofa_legacy_formats.h"
#include "hof/scene/sofa_scene.h"
#include "hof/scene/sofa_scene_reader.h"

namespace hof::scene::detail {
namespace {

// Rotation of SOFA's MeshLoader `rotation` (degrees, Euler angles about x, then y, then z).
Mat3 euler_xyz_deg(const Vec3& deg) {
  const Vec3 r = deg * (std::numbers::pi / 180.0);
  return (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

}  // namespace

// "@a/b/name.field", "@../name", "@[-1].field", "@/root/a/name", "@name": the component (and
// `field`, if any).
// A single name is looked up in the node, then in its ancestors (SOFA's context lookup).
Expected<Component*> Reader::resolve_link(const Component& from, std::string_view key, std::string_view link,
                                          std::string& field) {
  field.clear();
  const auto unresolved = [&](std::string_view why) {
    return fail(from, fmt::format("attribute {}: link '{}' does not resolve ({})", key, link, why));
  };
  std::string_view path = trim(link);
  if (!path.starts_with('@')) return unresolved("a link starts with '@'");
  path.remove_prefix(1);
  SceneNode* node = from.node;
  // Previous siblings: "[-k]".
  if (path.starts_with('[')) {
    const std::size_t close = path.find(']');
    int k = 0;
    if (close == std::string_view::npos || std::from_chars(path.data() + 1, path.data() + close, k).ec != std::errc{} ||
        k >= 0)
      return unresolved("expected [-k]");
    std::string_view rest = path.substr(close + 1);
    if (rest.starts_with('.')) field = std::string(rest.substr(1));
    const auto target = static_cast<std::int64_t>(from.index) + k;
    if (target < 0) return unresolved("no such previous component");
    return node->components[static_cast<std::size_t>(target)].get();
  }
  // Absolute: "@/Liver/loader" from the root node; "@/root/Liver/loader" names the root too.
  bool absolute = false;
  if (path.starts_with('/')) {
    absolute = true;
    while (node->parent) node = node->parent;
    path.remove_prefix(1);
    const std::size_t slash = path.find('/');
    const std::string_view first = path.substr(0, slash);
    if (slash != std::string_view::npos && first == node->name &&
        std::ranges::none_of(node->children, [&](const auto& n) { return n->name == first; })) {
      path.remove_prefix(slash + 1);
    }
  }
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const std::size_t slash = path.find('/', start);
    parts.push_back(path.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start));
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  std::string_view last = parts.back();
  parts.pop_back();
  if (last != "." && last != "..") {
    if (const std::size_t dot = last.find('.'); dot != std::string_view::npos) {
      field = std::string(last.substr(dot + 1));
      last = last.substr(0, dot);
    }
  }
  for (std::string_view p : parts) {
    if (p.empty() || p == ".") continue;
    if (p == "..") {
      if (!node->parent) return unresolved("'..' above the root node");
      node = node->parent;
      continue;
    }
    const auto it = std::ranges::find_if(node->children, [&](const auto& n) { return n->name == p; });
    if (it == node->children.end()) return unresolved(fmt::format("no node '{}' in '{}'", p, node->path));
    node = it->get();
  }
  for (SceneNode* n = node; n; n = parts.empty() && !absolute ? n->parent : nullptr) {
    for (auto& c : n->components)
      if (c->name == last) return c.get();
  }
  return unresolved(fmt::format("no component '{}' in '{}'{}", last, node->path, parts.empty() ? " or above" : ""));
}

// A relative path is looked up in the scene's folder and its parents, then in SOFA's data
// repository (sofa_data_folders); the error lists every folder tried.
Expected<fs::path> Reader::resolve_file(const Component& c, std::string_view key, const std::string& file) const {
  const fs::path rel(std::string(trim(file)));
  if (rel.empty()) return fail(c, fmt::format("attribute {} is empty", key));
  std::error_code ec;
  if (rel.is_absolute()) {
    if (fs::is_regular_file(rel, ec)) return rel;
    return fail(c, fmt::format("file '{}' not found", rel.string()), ErrorCode::kIo);
  }
  const fs::path scene_folder = fs::absolute(path_, ec).parent_path();
  const std::vector<fs::path> folders = sofa_data_folders(scene_folder);
  for (const fs::path& dir : folders)
    if (fs::is_regular_file(dir / rel, ec)) return dir / rel;
  std::string others;
  for (std::size_t i = 1; i < folders.size(); ++i)
    others += fmt::format("{}{}", others.empty() ? "" : ", ", folders[i].string());
  const bool data_path_set = std::getenv("SOFA_DATA_PATH") || std::getenv("SOFA_ROOT");
  return fail(c,
              fmt::format("{} '{}' not found: looked for {}{}{}", key, rel.string(), (scene_folder / rel).string(),
                          others.empty() ? std::string() : fmt::format(", then under {}", others),
                          data_path_set ? "" : " (set SOFA_DATA_PATH or SOFA_ROOT to add SOFA's data folders)"),
              ErrorCode::kIo);
}

Expected<const MeshData*> Reader::data_of(Component& c) {
  if (const auto it = data_cache_.find(&c); it != data_cache_.end()) return &it->second;
  if (in_progress_.contains(&c)) return fail(c, "links form a cycle");
  in_progress_.insert(&c);
  auto d = compute_data(c);
  in_progress_.erase(&c);
  if (!d) return std::unexpected(d.error());
  c.used = true;
  return &data_cache_.emplace(&c, std::move(*d)).first->second;
}

Expected<const MeshData*> Reader::linked_data_of(Component& c) {
  auto d = data_of(c);
  if (!d || c.type != "MeshOBJLoader" || (*d)->has_positions) return d;
  const char* key = c.attr("filename") ? "filename" : c.attr("fileMesh") ? "fileMesh" : nullptr;
  if (!key) return d;
  MeshData& cached = data_cache_.at(&c);
  if (auto r = read_file_into(c, key, cached); !r) return std::unexpected(r.error());
  if (auto r = transform_loader(c, cached); !r) return std::unexpected(r.error());
  return &cached;
}

Expected<void> Reader::read_file_into(Component& c, std::string_view key, MeshData& d) {
  auto file = resolve_file(c, key, *c.attr(key));
  if (!file) return std::unexpected(file.error());
  d.file = *file;
  const std::string ext = lower(file->extension().string());
  const auto located = [&](Error e) {
    e.message = fmt::format("{}: {}", c.label(), e.message);
    return std::unexpected(std::move(e));
  };
  if (ext == ".xs3") {
    auto x = detail::read_xs3(*file);
    if (!x) return located(x.error());
    d.positions = x->positions;
    d.has_positions = true;
    d.xs3 = std::move(*x);
    return {};
  }
  if (ext == ".mesh") {
    auto m = detail::read_legacy_mesh(*file);
    if (!m) return located(m.error());
    d.tets = std::move(m->tets);
    d.triangles = std::move(m->triangles);
    d.has_tets = !d.tets.empty();
    d.has_triangles = !d.triangles.empty();
    return {};
  }
  // The visual OBJ is only named, never needed as geometry here; every other file is read.
  auto m = mesh::read_mesh(*file);
  if (!m) return located(m.error());
  d.positions = std::move(m->mesh.nodes);
  d.tets = std::move(m->mesh.tets);
  d.triangles = std::move(m->mesh.triangles);
  d.tet_regions = std::move(m->mesh.tet_regions);
  d.triangle_regions = std::move(m->mesh.triangle_regions);
  d.has_positions = true;
  d.has_tets = !d.tets.empty();
  d.has_triangles = !d.triangles.empty();
  return {};
}

// Fills `d` from `key="@comp.field"` or from a literal list.
Expected<void> Reader::read_field(Component& c, std::string_view key, std::string_view field, MeshData& d) {
  const std::string& text = *c.attr(key);
  if (trim(text).starts_with('@')) {
    std::string linked_field;
    auto target = resolve_link(c, key, text, linked_field);
    if (!target) return std::unexpected(target.error());
    auto t = linked_data_of(**target);
    if (!t) return std::unexpected(t.error());
    const std::string f = linked_field.empty() ? std::string(key) : linked_field;
    if (f == "position" || f == "positions" || f == "points" || f == "vertices" || f == "rest_position") {
      if (!(*t)->has_positions) return fail(c, fmt::format("attribute {}: '{}' has no positions", key, text));
      if (field != "position") return fail(c, fmt::format("attribute {}: links positions to {}", key, field));
      d.positions = (*t)->positions;
      d.has_positions = true;
    } else if (f == "tetrahedra" || f == "tetras") {
      if (field != "tetrahedra") return fail(c, fmt::format("attribute {}: links tetrahedra to {}", key, field));
      d.tets = (*t)->tets;
      d.tet_regions = (*t)->tet_regions;
      d.has_tets = true;
    } else if (f == "triangles") {
      if (field != "triangles") return fail(c, fmt::format("attribute {}: links triangles to {}", key, field));
      d.triangles = (*t)->triangles;
      d.triangle_regions = (*t)->triangle_regions;
      d.has_triangles = true;
    } else if (f == "edges" || f == "normals" || f == "texcoords" || f == "quads" || f == "hexahedra") {
      // A loader output HoF does not take from links (edges come from the elements, normals from
      // the surface): linked, not needed.
      return {};
    } else {
      return fail(c, fmt::format("attribute {}: link to data '{}' is not supported", key, f), ErrorCode::kUnsupported);
    }
    return {};
  }
  if (field == "position") {
    auto v = numbers(c, key, text);
    if (!v) return std::unexpected(v.error());
    if (v->size() % 3 != 0)
      return fail(c, fmt::format("attribute {}: {} numbers, not a list of 3D points", key, v->size()));
    d.positions.clear();
    for (std::size_t i = 0; i < v->size(); i += 3) d.positions.emplace_back((*v)[i], (*v)[i + 1], (*v)[i + 2]);
    d.has_positions = true;
    return {};
  }
  auto idx = indices(c, key);
  if (!idx) return std::unexpected(idx.error());
  const std::size_t k = field == "tetrahedra" ? 4 : 3;
  if ((*idx)->size() % k != 0)
    return fail(c, fmt::format("attribute {}: {} indices, not a multiple of {}", key, (*idx)->size(), k));
  const auto& v = **idx;
  if (k == 4) {
    d.tets.clear();
    for (std::size_t i = 0; i < v.size(); i += 4) d.tets.push_back({v[i], v[i + 1], v[i + 2], v[i + 3]});
    d.has_tets = true;
  } else {
    d.triangles.clear();
    for (std::size_t i = 0; i < v.size(); i += 3) d.triangles.push_back({v[i], v[i + 1], v[i + 2]});
    d.has_triangles = true;
  }
  return {};
}

void fill_missing(MeshData& d, const MeshData& from) {
  if (!d.has_positions && from.has_positions) {
    d.positions = from.positions;
    d.has_positions = true;
    if (!d.xs3 && from.xs3) d.xs3 = from.xs3;
  }
  if (!d.has_tets && from.has_tets) {
    d.tets = from.tets;
    d.tet_regions = from.tet_regions;
    d.has_tets = true;
  }
  if (!d.has_triangles && from.has_triangles) {
    d.triangles = from.triangles;
    d.triangle_regions = from.triangle_regions;
    d.has_triangles = true;
  }
  if (!d.file && from.file) d.file = from.file;
}

// Geometry of a loader, topology or MechanicalObject: its own attributes, then `src`, then
// (state and topology only) the topology and loader of its node, as SOFA's init does.
Expected<MeshData> Reader::compute_data(Component& c) {
  MeshData d;
  const std::string* file = c.attr("filename");
  const char* file_key = "filename";
  if (!file && (file = c.attr("fileMesh"))) file_key = "fileMesh";
  // A MeshTopology's older name for its file (SOFA's tutorials still write it).
  if (!file && is_topology(c.type) && (file = c.attr("fileTopology"))) file_key = "fileTopology";
  if (file && (is_loader(c.type) || is_topology(c.type) || c.type == "MechanicalObject" || c.type == "OglModel")) {
    if (c.type == "OglModel" || c.type == "MeshOBJLoader") {
      auto f = resolve_file(c, file_key, *file);  // visual surfaces are only named
      if (!f) return std::unexpected(f.error());
      d.file = *f;
    } else if (auto r = read_file_into(c, file_key, d); !r) {
      return std::unexpected(r.error());
    }
  }
  if (c.attr("position")) {
    if (auto r = read_field(c, "position", "position", d); !r) return std::unexpected(r.error());
  }
  for (const char* key : {"tetrahedra", "tetras"})
    if (c.attr(key))
      if (auto r = read_field(c, key, "tetrahedra", d); !r) return std::unexpected(r.error());
  if (c.attr("triangles"))
    if (auto r = read_field(c, "triangles", "triangles", d); !r) return std::unexpected(r.error());
  if (const std::string* src = c.attr("src")) {
    std::string field;
    auto target = resolve_link(c, "src", *src, field);
    if (!target) return std::unexpected(target.error());
    auto t = linked_data_of(**target);
    if (!t) return std::unexpected(t.error());
    fill_missing(d, **t);
  }
  if (is_loader(c.type) && d.has_positions) {
    if (auto r = transform_loader(c, d); !r) return std::unexpected(r.error());
  }
  // A MechanicalObject whose own position has at most one entry (SOFA's placeholder
  // position="0 0 0") takes its node's topology or loader positions, as SOFA's init resizes the
  // state to the topology; one point stays only when nothing else gives positions.
  std::optional<MeshData> own_placeholder;
  if (c.type == "MechanicalObject" && d.has_positions && d.positions.size() <= 1 && !c.attr("src")) {
    own_placeholder = d;
    d.positions.clear();
    d.has_positions = false;
  }
  if (c.type == "MechanicalObject" || is_topology(c.type)) {
    if (is_topology(c.type)) {
      for (const char* key : {"translation", "rotation", "scale3d", "scale", "dx", "dy", "dz", "rx", "ry", "rz"})
        if (c.attr(key))
          warn(c.line,
               fmt::format("{}: attribute {} ignored (transform the loader or the MechanicalObject)", c.label(), key));
    }
    const bool topo = is_topology(c.type);
    for (auto& other : c.node->components) {
      if (d.has_positions && (d.has_tets || !topo)) break;
      if (other.get() == &c) continue;
      if ((!topo && is_topology(other->type)) || is_loader(other->type)) {
        if (other->type == "MeshOBJLoader" && !topo) continue;  // a surface loader feeds visuals
        auto t = data_of(*other);
        if (!t) return std::unexpected(t.error());
        fill_missing(d, **t);
      }
    }
  }
  if (own_placeholder && !d.has_positions) {
    d.positions = own_placeholder->positions;
    d.has_positions = true;
  }
  if (c.type == "MechanicalObject" && d.has_positions) {
    if (auto r = transform_state(c, d); !r) return std::unexpected(r.error());
  }
  return d;
}

// A loader's or state's transform attributes: translation, rotation (degrees), scale3d × scale;
// a state also reads SOFA's legacy dx dy dz, rx ry rz, sx sy sz.
Expected<Reader::Transform> Reader::read_transform(Component& c, bool legacy) {
  auto t = vec3(c, "translation");
  auto r = vec3(c, "rotation");
  auto s3 = vec3(c, "scale3d");
  auto s = number(c, "scale");
  if (!t) return std::unexpected(t.error());
  if (!r) return std::unexpected(r.error());
  if (!s3) return std::unexpected(s3.error());
  if (!s) return std::unexpected(s.error());
  Transform out{t->value_or(Vec3::Zero()), r->value_or(Vec3::Zero()), s3->value_or(Vec3::Ones())};
  if (*s) out.scale *= **s;
  if (legacy) {
    const char* keys[9] = {"dx", "dy", "dz", "rx", "ry", "rz", "sx", "sy", "sz"};
    for (int k = 0; k < 9; ++k) {
      auto v = number(c, keys[k]);
      if (!v) return std::unexpected(v.error());
      if (*v) (k < 3 ? out.translation : k < 6 ? out.rotation_deg : out.scale)[k % 3] = **v;
    }
  }
  return out;
}

// SOFA's MeshLoader transform: scale, then rotate, then translate.
Expected<void> Reader::transform_loader(Component& c, MeshData& d) {
  auto t = read_transform(c, false);
  if (!t) return std::unexpected(t.error());
  if (t->identity()) return {};
  const Mat3 rot = euler_xyz_deg(t->rotation_deg);
  for (Vec3& p : d.positions) p = rot * p.cwiseProduct(t->scale) + t->translation;
  return {};
}

// SOFA's MechanicalObject transform of its initial positions: rotation (degrees, x then y then
// z), then scale, then translation.
Expected<void> Reader::transform_state(Component& c, MeshData& d) {
  auto t = read_transform(c, true);
  if (!t) return std::unexpected(t.error());
  if (t->identity()) return {};
  const Mat3 rot = euler_xyz_deg(t->rotation_deg);
  for (Vec3& p : d.positions) p = (rot * p).cwiseProduct(t->scale) + t->translation;
  return {};
}

}  // namespace hof::scene::detail
