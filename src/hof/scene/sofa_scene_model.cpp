#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh_io.h"
#include "hof/scene/sofa_scene_reader.h"

// Maps the components of a model node to mechanics configs (SOFA names and defaults from
// sofa-components.md).

namespace hof::scene::detail {

Expected<SofaSceneModel> Reader::make_model(SceneNode& node, Component* state) {
  SofaSceneModel out;
  out.node_path = node.path;
  ModelConfig& m = out.config;
  m.name = node.name;
  m.dt_s = node.dt_s;
  m.gravity_m_per_s2 = node.gravity;

  if (auto r = read_geometry(node, state, out); !r) return std::unexpected(r.error());
  if (auto r = apply_solvers(node, m); !r) return std::unexpected(r.error());
  if (auto r = apply_components(node, m); !r) return std::unexpected(r.error());
  if (auto r = apply_visual(node, out); !r) return std::unexpected(r.error());
  const bool has_surface =
      !m.tets.empty() || !m.triangles.empty() || !m.hexahedra.empty() || out.fine_surface || out.visual_mesh;
  auto collision = body_collision(node, has_surface, false);
  if (!collision) return std::unexpected(collision.error());
  out.collision = std::move(*collision);
  return out;
}

// The model's nodes and elements: the state (with its fallbacks), or the node's topology or
// loader; a grid topology makes a hexahedral model.
Expected<void> Reader::read_geometry(SceneNode& node, Component* state, SofaSceneModel& out) {
  ModelConfig& m = out.config;
  const MeshData* geo = nullptr;
  Component* source = state;
  if (!source)
    for (auto& c : node.components)
      if (is_topology(c->type) || (is_loader(c->type) && c->type != "MeshOBJLoader")) {
        source = c.get();
        break;
      }
  auto d = data_of(*source);
  if (!d) return std::unexpected(d.error());
  geo = *d;
  // Tetrahedra of the node's topology take precedence over the state's.
  MeshData topo_data;
  fill_missing(topo_data, *geo);
  for (auto& c : node.components)
    if (is_topology(c->type) && c.get() != source) {
      auto t = data_of(*c);
      if (!t) return std::unexpected(t.error());
      if ((*t)->has_tets) {
        topo_data.tets = (*t)->tets;
        topo_data.tet_regions = (*t)->tet_regions;
        topo_data.has_tets = true;
      }
      break;
    }
  // What HoF does not simulate yet, named rather than reported as its consequence.
  const auto not_yet = [&](std::initializer_list<std::string_view> types) -> const Component* {
    for (auto& c : node.components)
      if (std::ranges::find(types, std::string_view(c->type)) != types.end()) return c.get();
    return nullptr;
  };
  Component* grid = nullptr;
  for (auto& c : node.components)
    if (c->type == "SparseGridTopology" || c->type == "RegularGridTopology") grid = c.get();
  if (const Component* hex = not_yet({"HexahedronSetTopologyContainer"}); hex && !grid) {
    return fail(*hex,
                fmt::format("node '{}': a HexahedronSetTopologyContainer is not read by HoF yet; a "
                            "RegularGridTopology or SparseGridTopology (hexahedral FEM) or a tetrahedral mesh is",
                            node.path),
                ErrorCode::kUnsupported);
  }
  if (grid) {
    // A hexahedral model: the grid's nodes are the state (a MechanicalObject's own positions,
    // if any, are SOFA's placeholder and give way to the topology's).
    if (auto r = apply_grid(*grid, out); !r) return std::unexpected(r.error());
    if (state) {
      // The state's translation/rotation/scale moves the grid's nodes, and the fine surface
      // with them (it rests where the grid rests).
      state->used = true;
      MeshData moved;
      moved.positions = m.positions;
      if (auto r = transform_state(*state, moved); !r) return std::unexpected(r.error());
      m.positions = std::move(moved.positions);
      if (out.fine_surface) {
        moved.positions = out.fine_surface->vertices;
        if (auto r = transform_state(*state, moved); !r) return std::unexpected(r.error());
        out.fine_surface->vertices = std::move(moved.positions);
      }
    }
  } else if (const Component* hex = not_yet({"HexahedronFEMForceField", "HexahedralFEMForceField"})) {
    return fail(*hex,
                fmt::format("node '{}': {} needs a hexahedral topology (RegularGridTopology or SparseGridTopology) "
                            "in the node",
                            node.path, hex->type),
                ErrorCode::kUnsupported);
  }
  if (!grid && (!geo->has_positions || geo->positions.empty()))
    return fail(*source, fmt::format("the model in node '{}' has no positions (no position, src or filename, and "
                                     "no topology or loader with positions in the node)",
                                     node.path));
  if (!grid) m.positions = geo->positions;
  if (geo->xs3 && std::ranges::any_of(geo->xs3->fixed, [](bool f) { return f; }))
    warn(source->line,
         fmt::format("{}: 'fixed' flags of the Xsp file ignored (use a FixedProjectiveConstraint)", source->label()));
  if (!grid) m.tets = topo_data.tets;
  if (!grid && m.tets.empty()) m.triangles = topo_data.triangles;
  // Gmsh physical groups, for tissue regions that select by them.
  const auto& regions = m.tets.empty() ? topo_data.triangle_regions : topo_data.tet_regions;
  if (!grid && regions.size() == (m.tets.empty() ? m.triangles.size() : m.tets.size())) m.element_regions = regions;
  const auto n = static_cast<std::int64_t>(m.positions.size());
  for (std::size_t t = 0; t < m.tets.size(); ++t)
    for (std::int32_t i : m.tets[t])
      if (i >= n)
        return fail(*source, fmt::format("tetrahedron {} uses node {} but the model has {} nodes", t, i, n),
                    ErrorCode::kInvalidMesh);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (std::int32_t i : m.triangles[t])
      if (i >= n)
        return fail(*source, fmt::format("triangle {} uses node {} but the model has {} nodes", t, i, n),
                    ErrorCode::kInvalidMesh);
  if (state) state->used = true;
  return {};
}

// The nearest ODE solver (this node or above) and the linear solver beside it.
Expected<void> Reader::apply_solvers(SceneNode& node, ModelConfig& m) {
  bool have_ode = false;
  bool have_linear = false;
  bool cg_embedded = false;
  for (SceneNode* s = &node; s && !(have_ode && have_linear); s = s->parent) {
    for (auto& c : s->components) {
      if (!have_ode && is_ode_solver(c->type)) {
        if (auto r = apply_ode(*c, m, cg_embedded); !r) return std::unexpected(r.error());
        have_ode = true;
        have_linear = have_linear || cg_embedded;
      } else if (!have_linear && is_linear_solver(c->type)) {
        if (auto r = apply_linear(*c, m); !r) return std::unexpected(r.error());
        have_linear = true;
      }
    }
  }
  if (!have_linear && m.ode.kind != mechanics::OdeSolverKind::kEulerExplicit &&
      m.ode.kind != mechanics::OdeSolverKind::kRungeKutta4)
    warn(node.line, fmt::format("node '{}': no linear solver; CGLinearSolver defaults assumed", node.path));
  return {};
}

// The mass, force fields and constraints of the node.
Expected<void> Reader::apply_components(SceneNode& node, ModelConfig& m) {
  bool have_mass = false;
  for (auto& c : node.components) {
    const std::string& t = c->type;
    if (t == "UniformMass" || t == "DiagonalMass" || t == "MeshMatrixMass") {
      if (have_mass) {
        warn(c->line, fmt::format("{}: a second mass in the node is ignored", c->label()));
        continue;
      }
      if (auto r = apply_mass(*c, m, m.positions.size()); !r) return std::unexpected(r.error());
      have_mass = true;
    } else if (t == "TetrahedronFEMForceField" || t == "FastTetrahedralCorotationalForceField" ||
               t == "TetrahedronHyperelasticityFEMForceField" || t == "MeshSpringForceField" ||
               t == "ConstantForceField" || t == "TriangleFEMForceField" || t == "TriangularFEMForceField" ||
               t == "HexahedronFEMForceField" || t == "HexahedralFEMForceField") {
      if (auto r = apply_force_field(*c, m); !r) return std::unexpected(r.error());
    } else if (t == "FixedProjectiveConstraint" || t == "PartialFixedProjectiveConstraint") {
      if (auto r = apply_fixed(*c, m); !r) return std::unexpected(r.error());
    } else if (t == "TetrahedronSetGeometryAlgorithms" || t == "TriangleSetGeometryAlgorithms") {
      c->used = true;  // geometry helpers: HoF computes volumes itself
    }
  }
  if (!have_mass) warn(node.line, fmt::format("node '{}': no mass; DiagonalMass massDensity=1 assumed", node.path));
  if (m.force_fields.empty()) {
    // A body with no elasticity HoF simulates would only fall: refused, naming what it has.
    for (auto& c : node.components) {
      if (c->used || c->type.find("ForceField") == std::string::npos) continue;
      return fail(*c,
                  fmt::format("node '{}': {} is not simulated by HoF yet, and the body has no other force field",
                              node.path, c->type),
                  ErrorCode::kUnsupported);
    }
  }
  return {};
}

Expected<std::optional<SofaSceneObstacle>> Reader::make_obstacle(SceneNode& node, Component* state) {
  Component* collision = nullptr;
  for (auto& c : node.components) {
    const std::string& t = c->type;
    if (t == "TriangleCollisionModel" || t == "TriangleModel" || t == "Triangle" || t == "TTriangleModel") {
      collision = c.get();
      break;
    }
  }
  if (!collision) return std::optional<SofaSceneObstacle>{};
  // Its geometry: the state (with its fallbacks), else the node's topology or loader.
  Component* source = state;
  if (!source) {
    for (auto& c : node.components) {
      if (is_topology(c->type) || is_loader(c->type)) {
        source = c.get();
        break;
      }
    }
  }
  if (!source) {
    warn(collision->line, fmt::format("{}: no state, topology or loader with positions in node '{}'; not touchable",
                                      collision->label(), node.path));
    return std::optional<SofaSceneObstacle>{};
  }
  auto d = data_of(*source);
  if (!d) return std::unexpected(d.error());
  MeshData data;
  fill_missing(data, **d);
  for (auto& c : node.components) {
    if (c.get() == source || !(is_topology(c->type) || is_loader(c->type))) continue;
    auto more = data_of(*c);
    if (!more) return std::unexpected(more.error());
    fill_missing(data, **more);
  }
  if ((!data.has_positions || data.triangles.empty()) && data.file) {
    // A surface loader HoF only names for visual models (MeshOBJLoader): read it here.
    auto surface = mesh::read_mesh(*data.file);
    if (!surface) return std::unexpected(surface.error());
    data.positions = surface->mesh.nodes;
    data.triangles = surface->mesh.triangles;
    data.has_positions = data.has_triangles = true;
  }
  if (!data.has_positions || data.positions.empty() || data.triangles.empty()) {
    models_without_surface_.push_back(collision);
    warn(collision->line,
         fmt::format("{}: node '{}' has no triangles to touch; skipped", collision->label(), node.path));
    return std::optional<SofaSceneObstacle>{};
  }
  const auto n = static_cast<std::int64_t>(data.positions.size());
  for (std::size_t t = 0; t < data.triangles.size(); ++t)
    for (std::int32_t i : data.triangles[t])
      if (i < 0 || i >= n)
        return fail(*source, fmt::format("triangle {} uses node {} but the obstacle has {} nodes", t, i, n),
                    ErrorCode::kInvalidMesh);
  collision->used = true;
  if (state) state->used = true;
  source->used = true;
  SofaSceneObstacle o;
  o.node_path = node.path;
  o.name = node.name;
  o.surface.vertices = data.positions;
  o.surface.triangles = data.triangles;
  auto models = body_collision(node, true, true);
  if (!models) return std::unexpected(models.error());
  o.collision = std::move(*models);
  return std::optional<SofaSceneObstacle>{std::move(o)};
}

Expected<void> Reader::apply_ode(Component& c, ModelConfig& m, bool& cg_embedded) {
  using mechanics::OdeSolverKind;
  c.used = true;
  m.ode.name = c.name;
  const std::string& t = c.type;
  if (t == "EulerImplicitSolver" || t == "CGImplicitSolver") {
    m.ode.kind = OdeSolverKind::kEulerImplicit;
    // Before 2009 both Rayleigh coefficients defaulted to 0.1; today they default to 0.
    const double def = (legacy_ || t == "CGImplicitSolver") ? 0.1 : 0.0;
    auto rs = number(c, "rayleighStiffness");
    auto rm = number(c, "rayleighMass");
    if (!rs) return std::unexpected(rs.error());
    if (!rm) return std::unexpected(rm.error());
    m.ode.rayleigh_stiffness = rs->value_or(def);
    m.ode.rayleigh_mass = rm->value_or(def);
    if (def != 0.0 && (!*rs || !*rm))
      warn(c.line, fmt::format("{}: 2008 syntax, Rayleigh defaults of the time assumed (rayleighStiffness={}, "
                               "rayleighMass={})",
                               c.label(), m.ode.rayleigh_stiffness, m.ode.rayleigh_mass));
    if (c.written != c.type) warn(c.line, fmt::format("{}: read as {}", c.label(), c.type));
    if (t == "CGImplicitSolver") {
      // The 2008 solver embedded its conjugate gradient.
      cg_embedded = true;
      m.linear.kind = mechanics::LinearSolverKind::kConjugateGradient;
      m.linear.name = c.name;
      auto it = number(c, "iterations");
      auto tol = number(c, "tolerance");
      auto th = number(c, "threshold");
      if (!it) return std::unexpected(it.error());
      if (!tol) return std::unexpected(tol.error());
      if (!th) return std::unexpected(th.error());
      m.linear.iterations = static_cast<int>(it->value_or(25.0));
      m.linear.tolerance = tol->value_or(1e-5);
      m.linear.threshold = th->value_or(1e-5);
    }
  } else if (t == "EulerExplicitSolver") {
    m.ode.kind = OdeSolverKind::kEulerExplicit;
    auto s = boolean(c, "symplectic");
    if (!s) return std::unexpected(s.error());
    m.ode.symplectic = s->value_or(true);
  } else if (t == "RungeKutta4Solver") {
    m.ode.kind = OdeSolverKind::kRungeKutta4;
  } else {  // StaticSolver
    m.ode.kind = OdeSolverKind::kStatic;
    auto it = number(c, "newton_iterations");
    auto res = number(c, "absolute_residual_tolerance_threshold");
    auto cor = number(c, "relative_correction_tolerance_threshold");
    if (!it) return std::unexpected(it.error());
    if (!res) return std::unexpected(res.error());
    if (!cor) return std::unexpected(cor.error());
    if (*it) m.ode.newton_iterations = static_cast<int>(**it);
    if (*res) m.ode.newton_residual_tolerance_n = **res;
    if (*cor) m.ode.newton_correction_tolerance = **cor;
  }
  return {};
}

Expected<void> Reader::apply_linear(Component& c, ModelConfig& m) {
  c.used = true;
  m.linear.name = c.name;
  if (c.type != "CGLinearSolver") {
    m.linear.kind = mechanics::LinearSolverKind::kSparseLdlt;
    return {};
  }
  m.linear.kind = mechanics::LinearSolverKind::kConjugateGradient;
  auto it = number(c, "iterations");
  auto tol = number(c, "tolerance");
  auto th = number(c, "threshold");
  if (!it) return std::unexpected(it.error());
  if (!tol) return std::unexpected(tol.error());
  if (!th) return std::unexpected(th.error());
  if (*it && (**it < 1 || **it != std::floor(**it)))
    return fail(c, fmt::format("attribute iterations: {} is not a positive integer", **it),
                ErrorCode::kInvalidArgument);
  m.linear.iterations = static_cast<int>(it->value_or(25.0));
  m.linear.tolerance = tol->value_or(1e-5);
  m.linear.threshold = th->value_or(1e-5);
  auto warm = boolean(c, "warmStart");
  if (!warm) return std::unexpected(warm.error());
  m.linear.warm_start = warm->value_or(false);
  // HoF extensions: the two-level preconditioner (mechanics/coarse_correction.h).
  auto coarse = boolean(c, "coarseCorrection");
  if (!coarse) return std::unexpected(coarse.error());
  m.linear.coarse_correction = coarse->value_or(false);
  auto refresh = number(c, "coarseRefreshSteps");
  if (!refresh) return std::unexpected(refresh.error());
  if (*refresh && (**refresh < 1 || **refresh != std::floor(**refresh)))
    return fail(c, fmt::format("attribute coarseRefreshSteps: {} is not a positive integer", **refresh),
                ErrorCode::kInvalidArgument);
  m.linear.coarse_refresh_steps = static_cast<int>(refresh->value_or(100.0));
  return {};
}

Expected<void> Reader::apply_mass(Component& c, ModelConfig& m, std::size_t n) {
  using mechanics::MassKind;
  c.used = true;
  m.mass.name = c.name;
  auto vertex = number(c, "vertexMass");
  auto total = number(c, "totalMass");
  auto density = number(c, "massDensity");
  if (!vertex) return std::unexpected(vertex.error());
  if (!total) return std::unexpected(total.error());
  if (!density) return std::unexpected(density.error());
  if (c.type == "UniformMass") {
    m.mass.kind = MassKind::kUniform;
    m.mass.total_mass_kg = total->value_or(1.0);
    if (*vertex) m.mass.vertex_mass_kg = **vertex;
    return {};
  }
  if (c.type == "MeshMatrixMass") warn(c.line, fmt::format("{}: simulated as a lumped DiagonalMass", c.label()));
  // DiagonalMass: masses from an Xsp file, else vertexMass > massDensity > totalMass.
  const std::string* file = c.attr("filename");
  if (!file) file = c.attr("fileMass");
  if (file) {
    auto path = resolve_file(c, c.attr("filename") ? "filename" : "fileMass", *file);
    if (!path) return std::unexpected(path.error());
    auto x = detail::read_xs3(*path);
    if (!x) {
      Error e = x.error();
      e.message = fmt::format("{}: {}", c.label(), e.message);
      return std::unexpected(std::move(e));
    }
    if (x->masses.size() != n)
      return fail(c, fmt::format("'{}' has {} masses but the model has {} nodes", path->string(), x->masses.size(), n),
                  ErrorCode::kInvalidMesh);
    m.mass.kind = MassKind::kUniform;
    const double first = x->masses.empty() ? 0.0 : x->masses.front();
    if (std::ranges::all_of(x->masses, [&](double v) { return v == first; })) {
      m.mass.vertex_mass_kg = first;
    } else {
      double sum = 0.0;
      for (double v : x->masses) sum += v;
      m.mass.total_mass_kg = sum;
      warn(c.line, fmt::format("{}: per-node masses of '{}' differ; their total {} is spread uniformly", c.label(),
                               path->filename().string(), sum));
    }
    return {};
  }
  if (*vertex) {
    m.mass.kind = MassKind::kUniform;
    m.mass.vertex_mass_kg = **vertex;
    return {};
  }
  m.mass.kind = MassKind::kDiagonal;
  if (*density) {
    m.mass.mass_density_kg_per_m3 = **density;
    if (*total) warn(c.line, fmt::format("{}: massDensity and totalMass both set; massDensity used", c.label()));
  } else if (*total) {
    m.mass.diagonal_total_mass_kg = **total;
  }
  return {};
}

Expected<void> Reader::apply_grid(Component& c, SofaSceneModel& out) {
  c.used = true;
  ModelConfig& m = out.config;
  // n: nodes per axis (SOFA's `n`, or the old nx ny nz).
  std::array<int, 3> n{2, 2, 2};
  if (const std::string* text = c.attr("n")) {
    auto v = numbers(c, "n", *text);
    if (!v) return std::unexpected(v.error());
    if (v->size() != 3) return fail(c, fmt::format("attribute n: expected 3 node counts, got {} values", v->size()));
    for (std::size_t a = 0; a < 3; ++a) {
      const double count = (*v)[a];
      if (!(count >= 2.0 && count <= 512.0) || count != std::floor(count)) {
        return fail(c, fmt::format("attribute n: {} is not a whole number of nodes from 2 to 512", count),
                    ErrorCode::kInvalidArgument);
      }
      n[a] = static_cast<int>(count);
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    static constexpr std::array<const char*, 3> kKeys{"nx", "ny", "nz"};
    auto v = number(c, kKeys[a]);
    if (!v) return std::unexpected(v.error());
    if (*v) {
      if (!(**v >= 2.0 && **v <= 512.0) || **v != std::floor(**v)) {
        return fail(c, fmt::format("attribute {}: {} is not a whole number of nodes from 2 to 512", kKeys[a], **v),
                    ErrorCode::kInvalidArgument);
      }
      n[a] = static_cast<int>(**v);
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (n[a] < 2 || n[a] > 512) {
      return fail(c,
                  fmt::format("attribute n: {} {} {}: each axis needs 2 to 512 nodes (n - 1 cells)", n[0], n[1], n[2]),
                  ErrorCode::kInvalidArgument);
    }
  }
  // The box: min/max, or the old xmin xmax ymin ymax zmin zmax.
  auto lo = vec3(c, "min");
  auto hi = vec3(c, "max");
  if (!lo) return std::unexpected(lo.error());
  if (!hi) return std::unexpected(hi.error());
  std::optional<std::pair<Vec3, Vec3>> box;
  if (*lo && *hi) box = std::make_pair(**lo, **hi);
  if (!box && c.attr("xmin")) {
    Vec3 a = Vec3::Zero(), b = Vec3::Zero();
    static constexpr std::array<std::pair<const char*, const char*>, 3> kBounds{
        {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}}};
    for (std::size_t k = 0; k < 3; ++k) {
      auto x0 = number(c, kBounds[k].first);
      auto x1 = number(c, kBounds[k].second);
      if (!x0) return std::unexpected(x0.error());
      if (!x1) return std::unexpected(x1.error());
      a[static_cast<Eigen::Index>(k)] = x0->value_or(0.0);
      b[static_cast<Eigen::Index>(k)] = x1->value_or(0.0);
    }
    box = std::make_pair(a, b);
  }
  Expected<mesh::HexGrid> grid = make_error(ErrorCode::kInvalidArgument, "no grid");
  if (c.type == "RegularGridTopology") {
    if (!box) return fail(c, "a RegularGridTopology needs its box: min=\"x y z\" max=\"x y z\"");
    grid = mesh::regular_grid(n, box->first, box->second);
  } else {
    // SparseGridTopology: the closed surface to fill, from fileTopology (or filename), or
    // linked positions and triangles.
    mesh::TriMesh surface;
    const char* key = c.attr("fileTopology") ? "fileTopology" : c.attr("filename") ? "filename" : nullptr;
    if (key) {
      auto file = resolve_file(c, key, *c.attr(key));
      if (!file) return std::unexpected(file.error());
      auto read = mesh::read_mesh(*file);
      if (!read) {
        Error e = read.error();
        e.message = fmt::format("{}: {}", c.label(), e.message);
        return std::unexpected(std::move(e));
      }
      if (!read->mesh.tets.empty())
        surface = mesh::extract_boundary(read->mesh.nodes, read->mesh.tets).surface;
      else
        surface = mesh::TriMesh{read->mesh.nodes, read->mesh.triangles};
    } else if (c.attr("position") && c.attr("triangles")) {
      MeshData d;
      if (auto r = read_field(c, "position", "position", d); !r) return std::unexpected(r.error());
      if (auto r = read_field(c, "triangles", "triangles", d); !r) return std::unexpected(r.error());
      surface = mesh::TriMesh{d.positions, d.triangles};
    } else {
      return fail(c,
                  "a SparseGridTopology needs the closed surface it fills: fileTopology=\"FILE\" (or position and "
                  "triangles)");
    }
    grid = mesh::sparse_grid(surface, n, box);
    if (grid) out.fine_surface = std::move(surface);
  }
  if (!grid) {
    Error e = grid.error();
    e.message = fmt::format("{}: {}", c.label(), e.message);
    e.line = c.line;
    if (e.file.empty()) e.file = path_.string();
    return std::unexpected(std::move(e));
  }
  m.positions = std::move(grid->nodes);
  m.hexahedra = std::move(grid->hexes);
  // fillWeighted (SOFA's default): a cell the surface passes through is about half full —
  // half the stiffness (SparseGridTopology's stiffness coefficient, which HexahedronFEMForceField
  // applies), whatever the modulus becomes; DiagonalMass lumps the whole cell.
  auto weighted = boolean(c, "fillWeighted");
  if (!weighted) return std::unexpected(weighted.error());
  if (c.type == "SparseGridTopology" && weighted->value_or(true)) {
    m.element_fill.assign(grid->hex_on_surface.size(), 1.0);
    m.fill_scales_mass = false;  // SOFA's DiagonalMass lumps each whole cell
    for (std::size_t h = 0; h < grid->hex_on_surface.size(); ++h) {
      if (grid->hex_on_surface[h]) m.element_fill[h] = 0.5;
    }
  }
  return {};
}

Expected<void> Reader::apply_fixed(Component& c, ModelConfig& m) {
  c.used = true;
  mechanics::FixedConstraintConfig f;
  f.name = c.name;
  auto all = boolean(c, "fixAll");
  if (!all) return std::unexpected(all.error());
  f.fix_all = all->value_or(false);
  if (c.type == "PartialFixedProjectiveConstraint") {
    if (const std::string* text = c.attr("fixedDirections")) {
      auto v = numbers(c, "fixedDirections", *text);
      if (!v) return std::unexpected(v.error());
      if (v->size() != 3) return fail(c, "attribute fixedDirections: expected 3 flags");
      for (std::size_t k = 0; k < 3; ++k) f.directions[k] = (*v)[k] != 0.0;
    }
  }
  if (c.written != c.type) warn(c.line, fmt::format("{}: read as {}", c.label(), c.type));
  // indices="@roi.indices": the nodes inside a BoxROI's boxes (SOFA's usual way to hold a
  // grid), taken as indices now, as SOFA computes them at init.
  if (const std::string* text = c.attr("indices"); text && trim(*text).starts_with('@')) {
    std::string field;
    auto target = resolve_link(c, "indices", *text, field);
    if (!target) return std::unexpected(target.error());
    Component& roi = **target;
    if (roi.type != "BoxROI")
      return fail(c, fmt::format("attribute indices: links to {}, expected a BoxROI's indices", roi.label()));
    roi.used = true;
    const std::string* box_text = roi.attr("box");
    if (!box_text) return fail(roi, "a BoxROI needs box=\"xmin ymin zmin xmax ymax zmax\"");
    auto v = numbers(roi, "box", *box_text);
    if (!v) return std::unexpected(v.error());
    if (v->empty() || v->size() % 6 != 0)
      return fail(roi, fmt::format("attribute box: {} numbers, expected 6 per box", v->size()));
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
      for (std::size_t b = 0; b < v->size(); b += 6) {
        const Vec3 lo((*v)[b], (*v)[b + 1], (*v)[b + 2]), hi((*v)[b + 3], (*v)[b + 4], (*v)[b + 5]);
        if ((m.positions[i].array() >= lo.array()).all() && (m.positions[i].array() <= hi.array()).all()) {
          f.indices.push_back(static_cast<std::int32_t>(i));
          break;
        }
      }
    }
    // SOFA accepts a box that holds nothing; it is worth a word, since the body may fly off.
    if (f.indices.empty()) {
      warn(roi.line,
           fmt::format("{}: no node of '{}' lies in its box; {} holds nothing", roi.label(), m.name, c.label()));
      return {};
    }
    m.fixed.push_back(std::move(f));
    return {};
  }
  auto idx = indices(c, "indices");
  if (!idx) return std::unexpected(idx.error());
  if (*idx) f.indices = **idx;
  for (std::int32_t i : f.indices)
    if (i >= static_cast<std::int32_t>(m.positions.size()))
      return fail(
          c, fmt::format("attribute indices: node {} out of range (the model has {} nodes)", i, m.positions.size()),
          ErrorCode::kInvalidArgument);
  m.fixed.push_back(std::move(f));
  return {};
}

// A child node with an OglModel (file, or src to an OBJ loader) and a BarycentricMapping.
Expected<void> Reader::apply_visual(SceneNode& node, SofaSceneModel& model) {
  for (auto& child : node.children) {
    Component* ogl = nullptr;
    Component* mapping = nullptr;
    for (auto& c : child->components) {
      if (c->type == "OglModel" && !ogl) ogl = c.get();
      if (c->type == "BarycentricMapping" && !mapping) mapping = c.get();
    }
    if (!ogl) continue;
    if (model.visual_mesh) {
      warn(ogl->line, fmt::format("{}: one visual model per body; this one is skipped", ogl->label()));
      continue;
    }
    auto d = data_of(*ogl);
    if (!d) return std::unexpected(d.error());
    if (!(*d)->file) {
      warn(ogl->line, fmt::format("{}: no file (filename, fileMesh or src to a loader); skipped", ogl->label()));
      ogl->used = false;
      continue;
    }
    model.visual_mesh = *(*d)->file;
    if (mapping) {
      mapping->used = true;
      model.visual_barycentric = true;
    }
  }
  return {};
}

}  // namespace hof::scene::detail
