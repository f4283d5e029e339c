#include "hof/scene/world.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh_io.h"
#include "hof/scene/detail/project_fields.h"
#include "hof/scene/detail/world_parts.h"
#include "hof/scene/model_parameters.h"
#include "hof/scene/sofa_scene.h"

namespace hof::scene {

namespace detail {

// Nodes on the border of an open triangle surface (edges used by one triangle only).
std::vector<std::int32_t> border_nodes(const std::vector<mesh::Tri>& triangles) {
  std::vector<std::array<std::int32_t, 2>> edges;
  for (const mesh::Tri& t : triangles) {
    for (int k = 0; k < 3; ++k) edges.push_back({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::int32_t> held;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) held.insert(held.end(), edges[i].begin(), edges[i].end());
    i = j;
  }
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  return held;
}

// `name`, or `name#2`, `name#3`, ... : names are unique within a world (commands, projects
// and reports address bodies by name; a USE'd shape or two nodes may share one).
std::string unique_name(const std::vector<coupling::SessionBody>& bodies, const std::string& name) {
  std::string candidate = name;
  for (int k = 2; std::any_of(bodies.begin(), bodies.end(), [&](const auto& b) { return b.name == candidate; }); ++k) {
    candidate = fmt::format("{}#{}", name, k);
  }
  return candidate;
}

// A SOFA model as a body: its visual mesh (barycentric) as the touchable surface when it has
// one, else a hexahedral grid's fine surface, else the boundary of its volume elements
// (shared nodes), else (a surface model) itself. On a hexahedral model the mapped surfaces
// follow the grid trilinearly: a coarse mechanical grid under a fine surface.
Expected<coupling::SessionBody> make_deformable(const mechanics::ModelConfig& config,
                                                const std::optional<std::filesystem::path>& visual_mesh,
                                                bool visual_barycentric,
                                                const std::optional<mesh::TriMesh>& fine_surface) {
  auto model = mechanics::build_model(config);
  if (!model) return std::unexpected(model.error());
  coupling::SessionBody body;
  body.name = config.name.empty() ? std::string("model") : config.name;
  body.model.emplace(std::move(*model));
  body.config = config;
  const bool hexahedral = !config.hexahedra.empty();
  const auto mapped = [&](const mesh::TriMesh& surface) -> Expected<void> {
    body.surface = surface;
    // SOFA's BarycentricMapping picks its mapper from the input topology: hexahedra, else
    // tetrahedra, else triangles (a membrane or a surface of springs).
    auto mapping =
        hexahedral ? coupling::SurfaceMapping::trilinear(config.positions, config.hexahedra, body.surface.vertices)
        : !config.tets.empty()
            ? coupling::SurfaceMapping::barycentric(config.positions, config.tets, body.surface.vertices)
            : coupling::SurfaceMapping::onto_triangles(config.positions, config.triangles, body.surface.vertices);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
    return {};
  };
  if (visual_mesh && visual_barycentric) {
    auto visual = mesh::read_mesh(*visual_mesh);
    if (!visual) return std::unexpected(visual.error());
    if (auto ok = mapped(mesh::TriMesh{visual->mesh.nodes, visual->mesh.triangles}); !ok)
      return std::unexpected(ok.error());
  } else if (hexahedral && fine_surface) {
    if (auto ok = mapped(*fine_surface); !ok) return std::unexpected(ok.error());
  } else if (hexahedral) {
    const mesh::BoundarySurface b = mesh::hex_boundary(config.positions, config.hexahedra);
    body.surface = b.surface;
    auto mapping = coupling::SurfaceMapping::by_index(config.positions, b.surface.vertices, b.surface_to_volume);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  } else if (config.tets.empty()) {
    body.surface.vertices = config.positions;
    body.surface.triangles = config.triangles;
    std::vector<mesh::NodeIndex> identity(config.positions.size());
    for (std::size_t i = 0; i < identity.size(); ++i) identity[i] = static_cast<mesh::NodeIndex>(i);
    auto mapping = coupling::SurfaceMapping::by_index(config.positions, body.surface.vertices, identity);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  } else {
    const mesh::BoundarySurface b = mesh::extract_boundary(config.positions, config.tets);
    body.surface = b.surface;
    auto mapping = coupling::SurfaceMapping::by_index(config.positions, b.surface.vertices, b.surface_to_volume);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  }
  if (body.surface.triangles.empty()) {
    return make_error(ErrorCode::kInvalidMesh, fmt::format("model '{}' has no surface to touch", body.name));
  }
  return body;
}

}  // namespace detail

Expected<coupling::SessionBody> deformable_body(const mechanics::ModelConfig& config) {
  return detail::make_deformable(config, std::nullopt, false);
}

namespace {

using detail::add_x3d;
using detail::border_nodes;
using detail::make_deformable;
using detail::unique_name;

// A volume body as a coarse hexahedral grid under its surface (<body model="hexahedra">):
// SOFA's SparseGridTopology over the body's touchable surface, HexahedronFEMForceField with the
// material of its first FEM field, the same mass, solvers and constraints (a held node holds
// the corners of the cell it lies in), and the surface following the grid trilinearly.
Expected<void> fill_with_hexahedra(coupling::SessionBody& body, const BodySetup& setup) {
  const mechanics::ModelConfig& tet = *body.config;
  if (!tet.hexahedra.empty()) return make_error(ErrorCode::kInvalidArgument, "the body is hexahedral already");
  if (tet.tets.empty())
    return make_error(ErrorCode::kInvalidArgument, "the body is a surface (no tetrahedra) with nothing inside to fill");
  std::array<int, 3> n = setup.grid;
  if (n[0] <= 0) {
    // Cells of a tenth of the largest extent.
    Vec3 lo = tet.positions.front(), hi = lo;
    for (const Vec3& p : tet.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double cell = (hi - lo).maxCoeff() / 10.0;
    for (int a = 0; a < 3; ++a)
      n[static_cast<std::size_t>(a)] = std::max(2, static_cast<int>(std::ceil((hi[a] - lo[a]) / cell)) + 1);
  }
  auto grid = mesh::sparse_grid(body.surface, n);
  if (!grid) return std::unexpected(grid.error());
  mechanics::ModelConfig hex = tet;
  hex.positions = grid->nodes;
  hex.tets.clear();
  hex.triangles.clear();
  hex.element_regions.clear();
  hex.hexahedra = grid->hexes;
  hex.mass.element_mass_density_kg_per_m3.clear();
  // The material: the first FEM (or Neo-Hookean, as its small-strain E and ν) field.
  std::optional<mechanics::HexahedronFemConfig> fem;
  for (const mechanics::ForceFieldConfig& f : tet.force_fields) {
    if (fem) break;
    if (f.tetrahedron_fem)
      fem = mechanics::HexahedronFemConfig{
          f.tetrahedron_fem->young_modulus_pa, f.tetrahedron_fem->poisson_ratio, f.tetrahedron_fem->method, {}, {}};
    if (f.neo_hookean)
      fem = mechanics::HexahedronFemConfig{
          f.neo_hookean->young_modulus_pa, f.neo_hookean->poisson_ratio, mechanics::FemMethod::kLarge, {}, {}};
  }
  if (!fem)
    return make_error(ErrorCode::kInvalidArgument,
                      "the body has no FEM or Neo-Hookean force field to take the material from");
  // As SOFA's sparse grid (fillWeighted, its default): a cell the surface passes through is
  // about half full — half the stiffness and half the mass, whatever they are set to later.
  hex.element_fill.assign(grid->hexes.size(), 1.0);
  for (std::size_t h = 0; h < grid->hexes.size(); ++h) {
    if (grid->hex_on_surface[h]) hex.element_fill[h] = 0.5;
  }
  hex.force_fields.clear();
  mechanics::ForceFieldConfig field;
  field.name = "FEM";
  field.hexahedron_fem = *fem;
  hex.force_fields.push_back(std::move(field));
  for (const mechanics::ForceFieldConfig& f : tet.force_fields) {
    if (f.constant_force) {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format("its ConstantForceField '{}' names tetrahedral nodes; remove it to fill the body with hexahedra",
                      f.name));
    }
  }
  // Held nodes: each holds the corners of the grid cell it lies in.
  const Vec3 cell = grid->cell_size();
  std::vector<std::int32_t> hex_of_cell(static_cast<std::size_t>((n[0] - 1) * (n[1] - 1) * (n[2] - 1)), -1);
  for (std::size_t h = 0; h < grid->hex_cells.size(); ++h)
    hex_of_cell[static_cast<std::size_t>(grid->hex_cells[h])] = static_cast<std::int32_t>(h);
  for (mechanics::FixedConstraintConfig& fixed : hex.fixed) {
    if (fixed.box) {
      // A box held the tetrahedral nodes inside it: those nodes, then their cells.
      for (std::size_t i = 0; i < tet.positions.size(); ++i) {
        if ((tet.positions[i].array() >= fixed.box->first.array()).all() &&
            (tet.positions[i].array() <= fixed.box->second.array()).all()) {
          fixed.indices.push_back(static_cast<std::int32_t>(i));
        }
      }
      fixed.box.reset();
    }
    if (fixed.indices.empty()) continue;
    std::vector<std::int32_t> corners;
    for (const std::int32_t i : fixed.indices) {
      const Vec3 p = tet.positions[static_cast<std::size_t>(i)];
      std::array<int, 3> c{};
      for (int a = 0; a < 3; ++a) {
        c[static_cast<std::size_t>(a)] = std::clamp(static_cast<int>(std::floor((p[a] - grid->min[a]) / cell[a])), 0,
                                                    n[static_cast<std::size_t>(a)] - 2);
      }
      const std::int32_t h = hex_of_cell[static_cast<std::size_t>(c[0] + (n[0] - 1) * (c[1] + (n[1] - 1) * c[2]))];
      if (h < 0) continue;  // a node outside every kept cell (cannot happen for a surface node)
      for (const std::int32_t corner : grid->hexes[static_cast<std::size_t>(h)]) corners.push_back(corner);
    }
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    fixed.indices = std::move(corners);
  }
  const mesh::TriMesh surface = body.surface;
  auto rebuilt = make_deformable(hex, std::nullopt, false, surface);
  if (!rebuilt) return std::unexpected(rebuilt.error());
  body.model.emplace(std::move(*rebuilt->model));
  body.config = std::move(hex);
  body.surface = std::move(rebuilt->surface);
  body.mapping = std::move(rebuilt->mapping);
  return {};
}

// A surface body's elasticity as the project chooses it (<body model="springs|membrane">):
// springs on the edges, or a co-rotational membrane of the same in-plane stiffness. A
// triangular spring lattice of stiffness k behaves as a membrane with E·t = 2k/√3 and ν = 1/3
// (equilateral lattice; Ostoja-Starzewski, "Lattice models in micromechanics", Appl. Mech.
// Rev. 55, 2002), so switching keeps the feel; the membrane is 1 mm thick.
Expected<void> apply_body_models(World& w) {
  constexpr double kThickness = 0.001;
  for (const BodySetup& setup : w.project.bodies) {
    if (setup.model.empty()) continue;
    auto it = std::find_if(w.bodies.begin(), w.bodies.end(), [&](const auto& b) { return b.name == setup.name; });
    const std::string who = fmt::format("<body name=\"{}\" model=\"{}\">", setup.name, setup.model);
    if (it == w.bodies.end() || !it->config) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: no deformable body of that name in the scene", who), w.file.string());
    }
    mechanics::ModelConfig config = *it->config;
    if (setup.model == "hexahedra") {
      if (auto ok = fill_with_hexahedra(*it, setup); !ok) {
        return make_error(ok.error().code, fmt::format("{}: {}", who, ok.error().message), w.file.string());
      }
      continue;
    }
    if (!config.tets.empty() || config.triangles.empty()) {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format("{}: the body is a volume ({}); springs and membranes are models of surface bodies (triangles)",
                      who, config.hexahedra.empty() ? "tetrahedra" : "hexahedra"),
          w.file.string());
    }
    double stiffness = 0.0, damping = 0.0, rest_scale = 1.0;
    bool had = false;
    std::vector<mechanics::ForceFieldConfig> kept;
    for (mechanics::ForceFieldConfig& f : config.force_fields) {
      if (f.mesh_springs && !had) {
        stiffness = f.mesh_springs->stiffness_n_per_m;
        damping = f.mesh_springs->damping_n_s_per_m;
        rest_scale = f.mesh_springs->rest_length_scale;
        had = true;
      } else if (f.triangle_fem && !had) {
        stiffness = std::sqrt(3.0) / 2.0 * f.triangle_fem->young_modulus_pa * f.triangle_fem->thickness_m;
        rest_scale = f.triangle_fem->rest_scale;
        had = true;
      }
      if (!f.mesh_springs && !f.triangle_fem) kept.push_back(std::move(f));
    }
    if (!had)
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: the body has no springs or membrane to replace", who), w.file.string());
    mechanics::ForceFieldConfig field;
    field.name = setup.model;
    if (setup.model == "membrane") {
      mechanics::TriangleFemConfig fem;
      fem.young_modulus_pa = 2.0 * stiffness / (std::sqrt(3.0) * kThickness);
      fem.poisson_ratio = 1.0 / 3.0;
      fem.thickness_m = kThickness;
      fem.rest_scale = rest_scale;
      field.triangle_fem = fem;
    } else {
      field.mesh_springs = mechanics::MeshSpringConfig{stiffness, damping, rest_scale};
    }
    kept.insert(kept.begin(), std::move(field));
    config.force_fields = std::move(kept);
    auto rebuilt = make_deformable(config, std::nullopt, false);
    if (!rebuilt) return std::unexpected(rebuilt.error());
    it->model.emplace(std::move(*rebuilt->model));
    it->config = std::move(config);
  }
  return {};
}

// Applies a project's <set> elements to the bodies they name (the same validation as the
// command seam), rebuilding those bodies.
Expected<void> apply_parameters(World& w) {
  for (const ParameterChange& change : w.project.parameters) {
    auto it = std::find_if(w.bodies.begin(), w.bodies.end(), [&](const auto& b) { return b.name == change.body; });
    if (it == w.bodies.end() || !it->config) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("<set body=\"{}\">: no deformable body of that name in the scene", change.body),
                        w.file.string());
    }
    mechanics::ModelConfig config = *it->config;
    if (auto ok = scene::set_parameter(config, change.component, change.parameter, change.value); !ok) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("<set body=\"{}\">: {}", change.body, ok.error().message), w.file.string());
    }
    auto rebuilt = make_deformable(config, std::nullopt, false);
    if (!rebuilt) return std::unexpected(rebuilt.error());
    // Keep the surface and mapping the scene gave it (a visual mesh, say).
    it->model.emplace(std::move(*rebuilt->model));
    it->config = std::move(config);
  }
  return {};
}

Expected<void> apply_regions(World& w) {
  for (const MaterialRegion& region : w.project.regions) {
    auto it = std::find_if(w.bodies.begin(), w.bodies.end(), [&](const auto& b) { return b.name == region.body; });
    const std::string who = fmt::format("<region name=\"{}\" body=\"{}\">", region.name, region.body);
    if (it == w.bodies.end() || !it->config) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("{}: no deformable body of that name in the scene", who), w.file.string());
    }
    mechanics::ModelConfig config = *it->config;
    auto count = apply_material_region(config, region);
    if (!count)
      return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: {}", who, count.error().message),
                        w.file.string());
    if (*count == 0) w.warnings.push_back(fmt::format("{}: no element is inside it; it changes nothing", who));
    auto rebuilt = make_deformable(config, std::nullopt, false);
    if (!rebuilt) return std::unexpected(rebuilt.error());
    it->model.emplace(std::move(*rebuilt->model));
    it->config = std::move(config);
  }
  return {};
}

// The project's per-body settings and obstacles.
Expected<void> apply_bodies(World& w) {
  for (const BodySetup& setup : w.project.bodies) {
    auto it = std::find_if(w.bodies.begin(), w.bodies.end(), [&](const auto& b) { return b.name == setup.name; });
    if (it == w.bodies.end()) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("<body name=\"{}\">: no body of that name in the scene", setup.name),
                        w.file.string(), setup.line);
    }
    if (setup.surface) it->material = setup.surface;
  }
  for (const ObstacleSetup& o : w.project.obstacles) {
    const std::filesystem::path path = o.mesh.is_absolute() ? o.mesh : w.file.parent_path() / o.mesh;
    auto read = mesh::read_mesh(path);
    if (!read) {
      Error e = read.error();
      e.message = fmt::format("obstacle '{}': {} (in project {}:{})", o.name, e.message, w.file.string(), o.line);
      return std::unexpected(e);
    }
    coupling::SessionBody body;
    body.name = unique_name(w.bodies, o.name);
    if (!read->mesh.tets.empty()) {
      body.surface = mesh::extract_boundary(read->mesh.nodes, read->mesh.tets).surface;
    } else {
      body.surface.vertices = read->mesh.nodes;
      body.surface.triangles = read->mesh.triangles;
    }
    if (body.surface.triangles.empty()) {
      // Named by the project's line (the mesh file itself has no line to blame).
      return make_error(ErrorCode::kInvalidMesh,
                        fmt::format("<obstacle name=\"{}\">: its mesh {} has no triangles to touch (a collision "
                                    "model on a body with no surface)",
                                    o.name, path.string()),
                        w.file.string(), o.line);
    }
    for (Vec3& p : body.surface.vertices) p += o.translation;
    body.material = o.surface;
    w.bodies.push_back(std::move(body));
  }
  return {};
}

/// `text`: the scene held in memory (else it is read from `scene_path`).
Expected<void> add_sofa(World& w, const std::filesystem::path& scene_path, const std::string* text = nullptr) {
  auto sofa = text ? read_sofa_scene_text(*text, scene_path) : read_sofa_scene(scene_path);
  if (!sofa) return std::unexpected(sofa.error());
  w.skipped = sofa->skipped;
  w.ignored = sofa->ignored;
  w.warnings = sofa->warnings;
  if (sofa->models.empty() && sofa->obstacles.empty()) {
    std::string why =
        "the scene has no simulated body (a node with an ODE solver and a MechanicalObject) and no "
        "obstacle (a TriangleCollisionModel on a state no solver moves)";
    if (!sofa->skipped.empty()) why += fmt::format("; not simulated: {}", fmt::join(sofa->skipped, ", "));
    return make_error(ErrorCode::kInvalidArgument, why, scene_path.string());
  }
  for (const SofaSceneModel& m : sofa->models) {
    auto body = make_deformable(m.config, m.visual_mesh, m.visual_barycentric, m.fine_surface);
    if (!body) {
      Error e = body.error();
      if (e.file.empty()) e.file = scene_path.string();
      e.message = fmt::format("body '{}': {}", m.node_path, e.message);
      return std::unexpected(e);
    }
    const std::string name = unique_name(w.bodies, body->name);
    body->name = name;
    if (body->config) body->config->name = name;
    body->collision = m.collision;
    w.bodies.push_back(std::move(*body));
  }
  for (const SofaSceneObstacle& o : sofa->obstacles) {
    coupling::SessionBody body;
    body.name = unique_name(w.bodies, o.name);
    body.surface = o.surface;
    body.collision = o.collision;
    w.bodies.push_back(std::move(body));
  }
  // Kept through finish_world(), which makes the rest of the configuration from the project.
  w.config.contacts = sofa->contacts;
  return {};
}

bool identity(const std::array<double, 16>& m) {
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (m[static_cast<std::size_t>(4 * r + c)] != (r == c ? 1.0 : 0.0)) return false;
    }
  }
  return true;
}

}  // namespace

void record_parameters(HofProject& project, const std::vector<ParameterChange>& changes) {
  for (const ParameterChange& change : changes) {
    auto same = std::find_if(project.parameters.begin(), project.parameters.end(), [&](const auto& p) {
      return p.body == change.body && p.component == change.component && p.parameter == change.parameter;
    });
    if (same != project.parameters.end()) {
      same->value = change.value;
    } else {
      project.parameters.push_back(change);
    }
  }
}

void record_changes(HofProject& project, const coupling::Session& session) {
  record_parameters(project, parameter_changes(session));
  for (const auto& [id, material] : session.material_changes()) {
    const std::string& name = session.body(static_cast<std::size_t>(id)).name;
    auto obstacle =
        std::find_if(project.obstacles.begin(), project.obstacles.end(), [&](const auto& o) { return o.name == name; });
    if (obstacle != project.obstacles.end()) {
      obstacle->surface = material;
      continue;
    }
    auto body =
        std::find_if(project.bodies.begin(), project.bodies.end(), [&](const auto& b) { return b.name == name; });
    if (body == project.bodies.end()) {
      project.bodies.push_back(BodySetup{name, material, {}, {}, {}, 0});
    } else {
      body->surface = material;
    }
  }
}

namespace {

/// The project's scene (its errors: the project first, then the scene resolved, then what is
/// wrong there).
Expected<void> add_project_scene(World& w, const std::filesystem::path& file) {
  w.scene_path = scene_file(w.project, file);
  // An inline scene is read from the file when the file holds this very scene (errors then
  // give the file's line numbers), else from memory (the window edited it).
  const std::string* text = nullptr;
  if (!w.project.mechanics_inline.empty()) {
    const auto on_disk = read_project(file);
    if (!on_disk || on_disk->mechanics_inline != w.project.mechanics_inline) text = &w.project.mechanics_inline;
  }
  // Lines of a scene held in memory are its own, not the file's: its messages say so (the
  // folder still anchors its files).
  const std::filesystem::path named =
      text ? file.parent_path() / (file.filename().string() + " (edited scene)") : w.scene_path;
  if (!text && w.scene_path.extension() == ".x3d") {
    // An X3D scene under a project: its shapes are the bodies; the project's settings (device,
    // renderer, calibration, graphics) stay the project's, the scene's force effects are used
    // when the project has none.
    const HofProject kept = w.project;
    if (auto ok = add_x3d(w, w.scene_path); !ok) {
      Error e = ok.error();
      e.message = fmt::format("its scene {}: {}", w.scene_path.string(), e.message);
      return std::unexpected(e);
    }
    const haptics::ForceEffects effects = w.project.effects;
    const bool two_sided = w.project.touchable_face == collision::TouchableFace::kFrontAndBack;
    const Vec3 scene_viewpoint = w.project.graphics.viewpoint_m;
    w.project = kept;
    // A project that keeps the default view looks from the scene's Viewpoint.
    if (kept.graphics.viewpoint_m == GraphicsSetup{}.viewpoint_m &&
        kept.graphics.look_at_m == GraphicsSetup{}.look_at_m) {
      w.project.graphics.viewpoint_m = scene_viewpoint;
    }
    if (two_sided) w.project.touchable_face = collision::TouchableFace::kFrontAndBack;  // solid='false' shapes
    if (kept.effects.empty()) w.project.effects = effects;
    return {};
  }
  if (auto ok = add_sofa(w, named, text); !ok) {
    Error inner = ok.error();
    if (w.scene_path == file) return std::unexpected(inner);
    std::error_code canonical_error;
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(w.scene_path, canonical_error);
    if (!canonical_error && (inner.file.empty() || inner.file == w.scene_path.string())) inner.file = resolved.string();
    Error e;
    e.code = inner.code;
    e.file = file.string();
    e.message = "its scene " + inner.to_string();
    return std::unexpected(e);
  }
  return {};
}

/// What every input shares once its bodies are read: the project's settings, the unit, the
/// device (the default probe when the world is bare).
// The shaped tool (<tool>): the tool in the haptic loop and its reaction in the tissue of the
// body it touches most. Its dimensions are SI; the scene's length unit converts them.
struct MadeTool {
  std::shared_ptr<procedures::ShapedTool> tool;
  std::shared_ptr<procedures::ShapedTissueCoupling> coupling;
};
Expected<MadeTool> make_shaped_tool(const World& w, const procedures::ShapedToolConfig& config) {
  double metres_per_unit = 1.0;
  if (w.length_unit == "mm") metres_per_unit = 1e-3;
  if (w.length_unit == "cm") metres_per_unit = 1e-2;
  if (w.length_unit == "dm") metres_per_unit = 1e-1;
  std::optional<mesh::TriMesh> surface;
  if (config.shape == procedures::ToolShape::kMesh) {
    const std::filesystem::path path = std::filesystem::path(config.mesh).is_relative()
                                           ? w.file.parent_path() / config.mesh
                                           : std::filesystem::path(config.mesh);
    auto read = procedures::read_tool_mesh(path);
    if (!read) return std::unexpected(read.error());
    surface = std::move(*read);
  }
  auto tool = procedures::ShapedTool::make(config, surface ? &*surface : nullptr, metres_per_unit);
  if (!tool) {
    Error e = tool.error();
    e.file = w.file.string();
    return std::unexpected(e);
  }
  std::vector<procedures::ToolBodySurface> bodies;
  for (const coupling::SessionBody& b : w.bodies) {
    procedures::ToolBodySurface s;
    if (b.deformable()) {
      s.triangles = b.surface.triangles;
      s.vertex_count = b.surface.vertices.size();
      s.mapping = b.mapping;
    }
    bodies.push_back(std::move(s));
  }
  return MadeTool{*tool, std::make_shared<procedures::ShapedTissueCoupling>(*tool, std::move(bodies))};
}

Expected<void> add_shaped_tool(World& w) {
  auto made = make_shaped_tool(w, *w.project.tool);
  if (!made) return std::unexpected(made.error());
  w.config.tool = made->tool;
  w.config.tool_coupling = made->coupling;
  return {};
}

// The hands beyond the first (project.hands): each its device spec, its tool, its own force
// limit, and the calibration the file gave (the default probe's fitted one is the first hand's).
Expected<void> add_hands(World& w) {
  for (const HandSetup& setup : w.project.hands) {
    coupling::HandConfig hand;
    hand.device = setup.tool.device;
    // A recording the hand replays is found beside the project, as the project's own.
    if (const std::string_view replay = "replay:"; hand.device.starts_with(replay)) {
      const std::filesystem::path recording = hand.device.substr(replay.size());
      if (recording.is_relative() && !w.file.parent_path().empty())
        hand.device = std::string(replay) + (w.file.parent_path() / recording).string();
    }
    if (hand.device == w.device) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("<tool> device=\"{}\": the first hand's device too (each device carries one tool)",
                                    setup.tool.device),
                        w.file.string(), setup.line);
    }
    for (const coupling::HandConfig& other : w.config.more_hands) {
      if (other.device == hand.device)
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("<tool> device=\"{}\": a second tool on that device", setup.tool.device),
                          w.file.string(), setup.line);
    }
    hand.haptics = w.config.haptics;
    if (setup.max_force_n > 0.0) hand.haptics.safety.max_force_n = setup.max_force_n;
    for (int r = 0; r < 4; ++r) {
      for (int k = 0; k < 4; ++k)
        hand.haptics.calibration.position(r, k) = w.file_calibration[static_cast<std::size_t>(4 * r + k)];
    }
    auto made = make_shaped_tool(w, setup.tool);
    if (!made) {
      Error e = made.error();
      e.line = setup.line;
      return std::unexpected(e);
    }
    hand.tool = made->tool;
    hand.tool_coupling = made->coupling;
    w.config.more_hands.push_back(std::move(hand));
  }
  return {};
}

Expected<World> finish_world(World w, bool sofa_scene, bool bare, const std::string& device_override) {
  if (auto ok = apply_body_models(w); !ok) return std::unexpected(ok.error());
  if (auto ok = apply_parameters(w); !ok) return std::unexpected(ok.error());
  if (auto ok = apply_regions(w); !ok) return std::unexpected(ok.error());
  if (auto ok = apply_bodies(w); !ok) return std::unexpected(ok.error());
  w.name = w.project.name;
  // A project states its scene's unit (<mechanics unit="m">); unstated, X3D is in metres (the
  // X3D standard's unit) and a SOFA scene — bare or under a project — carries none: its lengths
  // are reported in "scene units", never presumed metres (SOFA's liver is 6 units across).
  const bool sofa_mechanics = sofa_scene || !w.project.mechanics_inline.empty() || w.scene_path.extension() == ".scn";
  w.length_unit = !w.project.scene_unit.empty() ? w.project.scene_unit : sofa_mechanics ? "scene units" : "m";

  w.file_calibration = w.project.position_calibration;
  std::string device = device_override.empty() ? (bare ? std::string("auto") : w.project.device) : device_override;
  if (device == "auto") {
    const haptics::DeviceSpec spec = haptics::device_spec_for_model(haptics::DeviceModel::kVirtual);
    const double k = w.project.surface.stiffness_n_per_m(spec.max_stiffness_n_per_m);
    // A calibration the file gives is kept; a bare scene gets the fitted one.
    const bool given = !identity(w.project.position_calibration);
    const Vec3 effects_centre = default_probe_effects_centre(w.project.effects);
    const double radius = w.project.renderer == haptics::RendererKind::kRuspini ? w.project.proxy_radius_m : 0.0;
    // A shaped tool presses a deforming surface along its whole shape, and its contact still
    // chatters as the surface moves at the simulation's rate (issue 37, left): the probe aims
    // at a quarter of the force it would press a point with, to stay off the device's limit.
    const double probe_force_limit_n = w.project.tool ? 0.25 * spec.max_force_n : spec.max_force_n;
    DefaultProbe probe = default_probe(w.bodies, spec.workspace_radius_m, k, probe_force_limit_n,
                                       given ? &w.project.position_calibration : nullptr, spec.max_stiffness_n_per_m,
                                       effects_centre, radius);
    device = probe.device;
    w.default_probe = true;
    w.probe_arrival_s = probe.arrival_s;
    w.probe_press_s = probe.press_s;
    w.project.position_calibration = probe.calibration;
    w.defaults.push_back("device = " + device + " (the default probe: " + probe.description + ")");
  }
  w.device = device;
  const coupling::ContactSettings scene_contacts = w.config.contacts;
  w.config = session_config(w.project);
  w.config.contacts = scene_contacts;
  if (auto ok = detail::apply_contact(w); !ok) return std::unexpected(ok.error());
  if (w.project.needle) {
    // The needle stylus: the tool in the haptic loop and its reaction in the tissue.
    std::vector<std::string> names;
    std::vector<bool> deformable;
    for (const coupling::SessionBody& b : w.bodies) {
      names.push_back(b.name);
      deformable.push_back(b.deformable());
    }
    // The needle's parameters are SI: lengths in the scene's unit are converted.
    double metres_per_unit = 1.0;
    if (w.length_unit == "mm")
      metres_per_unit = 1e-3;
    else if (w.length_unit == "cm")
      metres_per_unit = 1e-2;
    else if (w.length_unit == "dm")
      metres_per_unit = 1e-1;
    else if (w.length_unit != "m") {
      w.warnings.push_back(
          fmt::format("the needle's parameters are in SI units; the scene's lengths ({}) are taken as metres "
                      "(set mechanics@unit to m, cm or mm)",
                      w.length_unit));
    }
    auto tool = procedures::NeedleTool::make(*w.project.needle, names, deformable, metres_per_unit);
    if (!tool) {
      Error e = tool.error();
      e.file = w.file.string();
      return std::unexpected(e);
    }
    w.config.tool = *tool;
    w.config.tool_coupling = std::make_shared<procedures::NeedleTissueCoupling>(*tool);
  }
  if (w.project.tool && !w.project.needle) {
    if (auto ok = add_shaped_tool(w); !ok) return std::unexpected(ok.error());
  }
  w.config.device = w.device;
  if (auto ok = add_hands(w); !ok) return std::unexpected(ok.error());
  return w;
}

}  // namespace

std::optional<std::vector<coupling::Command>> live_commands(const HofProject& next, const ProjectEdit& edit,
                                                            const std::vector<std::string>& bodies) {
  const coupling::SessionConfig config = session_config(next);
  std::vector<coupling::Command> commands;
  if (std::holds_alternative<project_edit::Surface>(edit)) {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const std::string& body = bodies[i];
      const bool own = std::any_of(next.bodies.begin(), next.bodies.end(),
                                   [&](const auto& b) { return b.name == body && b.surface; }) ||
                       std::any_of(next.obstacles.begin(), next.obstacles.end(),
                                   [&](const auto& o) { return o.name == body && o.surface; });
      if (!own) commands.emplace_back(coupling::command::SetMaterial{static_cast<coupling::BodyId>(i), next.surface});
    }
  } else if (std::holds_alternative<project_edit::Rendering>(edit)) {
    commands.emplace_back(coupling::command::SetRenderer{config.haptics.renderer});
  } else if (std::holds_alternative<project_edit::Effects>(edit)) {
    commands.emplace_back(coupling::command::SetEffects{config.effects});
  } else if (std::holds_alternative<project_edit::Calibration>(edit)) {
    commands.emplace_back(coupling::command::SetCalibration{config.haptics.calibration});
  } else if (std::holds_alternative<project_edit::ForceLimit>(edit)) {
    commands.emplace_back(coupling::command::SetForceLimit{next.safety.max_force_n});
  } else if (std::holds_alternative<project_edit::Graphics>(edit) ||
             std::holds_alternative<project_edit::Stylus>(edit)) {
    // Drawn by the window only.
  } else {
    return std::nullopt;
  }
  return commands;
}

Expected<procedures::ShapedToolConfig> parse_tool_spec(std::string_view spec) {
  procedures::ShapedToolConfig tool;
  std::vector<std::pair<std::string, std::string>> pairs;
  std::size_t start = 0;
  bool first = true;
  while (start <= spec.size()) {
    const std::size_t end = std::min(spec.find(',', start), spec.size());
    const std::string item(spec.substr(start, end - start));
    if (first && item.find('=') == std::string::npos) {
      pairs.emplace_back("shape", item);
    } else if (const std::size_t eq = item.find('='); eq != std::string::npos) {
      pairs.emplace_back(item.substr(0, eq), item.substr(eq + 1));
    } else {
      return make_error(
          ErrorCode::kInvalidArgument,
          fmt::format("tool \"{}\": \"{}\" is not ATTRIBUTE=VALUE (e.g. capsule,radius=0.004,length=0.05)", spec,
                      item));
    }
    first = false;
    start = end + 1;
  }
  for (const auto& [name, value] : pairs) {
    const auto& fields = detail::tool_fields();
    if (std::none_of(fields.begin(), fields.end(), [&](const auto& f) { return f.name == name; })) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("tool \"{}\": unknown attribute \"{}\" (shape, radius, length, mesh, "
                                    "orientation, stiffness, damping)",
                                    spec, name));
    }
  }
  const auto attribute = [&](std::string_view name) -> std::optional<std::string_view> {
    for (const auto& [n, v] : pairs) {
      if (n == name) return std::string_view(v);
    }
    return std::nullopt;
  };
  if (auto problem = detail::read_fields(detail::tool_fields(), "tool", attribute, tool))
    return make_error(ErrorCode::kInvalidArgument, fmt::format("tool \"{}\": {}", spec, *problem));
  if (auto problem = detail::check_tool(tool))
    return make_error(ErrorCode::kInvalidArgument, fmt::format("tool \"{}\": {}", spec, *problem));
  return tool;
}

Expected<void> mount_tool(World& w, const procedures::ShapedToolConfig& tool) {
  if (auto problem = detail::check_tool(tool)) return make_error(ErrorCode::kInvalidArgument, *problem);
  w.project.tool = tool;
  w.project.needle.reset();
  w.config.tool.reset();
  w.config.tool_coupling.reset();
  return add_shaped_tool(w);
}

Expected<World> build_world(const std::filesystem::path& file, const std::string& device_override) {
  World w;
  w.file = file;
  w.scene_path = file;
  const std::string ext = file.extension().string();
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    return make_error(ErrorCode::kIo, "is a folder, not a scene or project file", file.string());
  if (!std::filesystem::exists(file, ec)) return make_error(ErrorCode::kIo, "no such file", file.string());
  if (ext == ".hof") {
    auto project = read_project(file);
    if (!project) return std::unexpected(project.error());
    return build_world(*project, file, device_override);
  }
  if (ext == ".scn") {
    w.project.name = file.stem().string();
    w.project.mechanics_scene = file.filename();
    if (auto ok = add_sofa(w, file); !ok) return std::unexpected(ok.error());
    return finish_world(std::move(w), true, true, device_override);
  }
  if (ext == ".x3d") {
    w.project.name = file.stem().string();
    if (auto ok = add_x3d(w, file); !ok) return std::unexpected(ok.error());
    return finish_world(std::move(w), false, true, device_override);
  }
  return make_error(ErrorCode::kUnsupported, "expected a .hof project, a .scn SOFA scene or an .x3d scene",
                    file.string());
}

Expected<World> build_world(const HofProject& project, const std::filesystem::path& file,
                            const std::string& device_override) {
  World w;
  w.file = file;
  w.project = project;
  // A recording the project replays is found beside it, as its scene is.
  if (const std::string_view replay = "replay:"; w.project.device.starts_with(replay)) {
    const std::string rest = w.project.device.substr(replay.size());
    const std::filesystem::path recording = rest.substr(0, rest.find(','));
    if (recording.is_relative() && !file.parent_path().empty())
      w.project.device = std::string(replay) + (file.parent_path() / rest).string();
  }
  if (auto ok = add_project_scene(w, file); !ok) return std::unexpected(ok.error());
  return finish_world(std::move(w), false, project.device == "auto", device_override);
}

Expected<std::size_t> apply_material_region(mechanics::ModelConfig& config, const MaterialRegion& region) {
  const auto positive = [](const std::optional<double>& v) { return !v || (*v > 0.0 && std::isfinite(*v)); };
  if (!positive(region.young_modulus_pa)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("youngModulus must be > 0 Pa, got {}", *region.young_modulus_pa));
  }
  if (region.poisson_ratio && !(*region.poisson_ratio > -1.0 && *region.poisson_ratio < 0.5)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("poissonRatio must be in (-1, 0.5), got {}", *region.poisson_ratio));
  }
  if (!positive(region.mass_density_kg_per_m3)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("massDensity must be > 0, got {}", *region.mass_density_kg_per_m3));
  }
  if (!region.young_modulus_pa && !region.poisson_ratio && !region.mass_density_kg_per_m3) {
    return make_error(ErrorCode::kInvalidArgument, "sets nothing: give youngModulus, poissonRatio or massDensity");
  }
  // The elements a region selects: the body's volume elements (tetrahedra or hexahedra), else
  // its triangles (a membrane).
  const bool on_hexahedra = config.tets.empty() && !config.hexahedra.empty();
  const bool on_triangles = config.tets.empty() && !on_hexahedra;
  const std::size_t element_count = on_hexahedra   ? config.hexahedra.size()
                                    : on_triangles ? config.triangles.size()
                                                   : config.tets.size();
  struct Target {
    std::vector<double>* young;
    std::vector<double>* poisson;
  };
  std::vector<Target> targets;
  std::string names;
  for (mechanics::ForceFieldConfig& f : config.force_fields) {
    Target t{nullptr, nullptr};
    if (f.tetrahedron_fem)
      t = {&f.tetrahedron_fem->element_young_modulus_pa, &f.tetrahedron_fem->element_poisson_ratio};
    if (f.neo_hookean) t = {&f.neo_hookean->element_young_modulus_pa, &f.neo_hookean->element_poisson_ratio};
    if (f.triangle_fem) t = {&f.triangle_fem->element_young_modulus_pa, &f.triangle_fem->element_poisson_ratio};
    if (f.hexahedron_fem) t = {&f.hexahedron_fem->element_young_modulus_pa, &f.hexahedron_fem->element_poisson_ratio};
    if (!t.young) continue;
    names += (names.empty() ? "" : ", ") + f.name;
    if (!region.force_field.empty() && f.name != region.force_field) continue;
    targets.push_back(t);
  }
  const bool elastic = region.young_modulus_pa || region.poisson_ratio;
  if (elastic && targets.empty()) {
    return make_error(
        ErrorCode::kInvalidArgument,
        region.force_field.empty()
            ? std::string(
                  "the body has no FEM force field (TetrahedronFEMForceField, Neo-Hookean, "
                  "HexahedronFEMForceField or a membrane TriangleFEMForceField) whose material a region could set")
            : fmt::format("no FEM force field '{}' (the body has: {})", region.force_field,
                          names.empty() ? std::string("none") : names));
  }
  if (region.mass_density_kg_per_m3 && config.mass.kind != mechanics::MassKind::kDiagonal) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("massDensity needs the body's mass to be a DiagonalMass (its '{}' is a UniformMass)",
                                  config.mass.name));
  }
  if (region.shape == MaterialRegion::Shape::kGroup && config.element_regions.size() != element_count) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("physicalGroup=\"{}\": the body's mesh has no physical groups (a Gmsh file with tagged {})",
                    region.physical_group,
                    on_hexahedra   ? "elements; a grid has none"
                    : on_triangles ? "triangles"
                                   : "tetrahedra"));
  }
  std::size_t count = 0;
  for (const Target& t : targets) {
    if (region.young_modulus_pa) t.young->resize(element_count, 0.0);
    if (region.poisson_ratio) t.poisson->resize(element_count, 0.0);
  }
  if (region.mass_density_kg_per_m3) config.mass.element_mass_density_kg_per_m3.resize(element_count, 0.0);
  for (std::size_t e = 0; e < element_count; ++e) {
    bool inside = false;
    if (region.shape == MaterialRegion::Shape::kGroup) {
      inside = config.element_regions[e] == region.physical_group;
    } else {
      Vec3 centroid = Vec3::Zero();
      const std::span<const std::int32_t> nodes = on_hexahedra   ? std::span<const std::int32_t>(config.hexahedra[e])
                                                  : on_triangles ? std::span<const std::int32_t>(config.triangles[e])
                                                                 : std::span<const std::int32_t>(config.tets[e]);
      for (const std::int32_t n : nodes) {
        if (n < 0 || static_cast<std::size_t>(n) >= config.positions.size()) {
          return make_error(ErrorCode::kInvalidMesh, fmt::format("element {} refers to a missing node {}", e, n));
        }
        centroid += config.positions[static_cast<std::size_t>(n)] / static_cast<double>(nodes.size());
      }
      inside = region.shape == MaterialRegion::Shape::kSphere ? (centroid - region.center).norm() <= region.radius
                                                              : (centroid.array() >= region.box_min.array()).all() &&
                                                                    (centroid.array() <= region.box_max.array()).all();
    }
    if (!inside) continue;
    ++count;
    for (const Target& t : targets) {
      if (region.young_modulus_pa) (*t.young)[e] = *region.young_modulus_pa;
      if (region.poisson_ratio) (*t.poisson)[e] = *region.poisson_ratio;
    }
    if (region.mass_density_kg_per_m3) config.mass.element_mass_density_kg_per_m3[e] = *region.mass_density_kg_per_m3;
  }
  return count;
}

}  // namespace hof::scene
