#include "hof/app/bench/recipes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <limits>
#include <utility>

#include "hof/core/assert.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/liver_generator.h"
#include "hof/scene/sofa_scene.h"

namespace hof::app::bench {

using namespace hof::mechanics;
using mesh::LiverResolution;

Expected<const Body*> Bodies::liver(LiverResolution r) {
  const std::string name(mesh::to_string(r));
  if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
  auto m = mesh::generate_liver(r);
  if (!m) return std::unexpected(m.error());
  mesh::TriMesh surface = mesh::extract_boundary(m->nodes, m->tets).surface;
  Body b{name, m->nodes, m->tets, {}, surface.triangles.size(), surface, {}};
  return &bodies_.emplace(name, std::move(b)).first->second;
}

// SOFA's SparseGridTopology over the medium liver's surface, 24×16×10 nodes: cells of about 1 cm.
Expected<const Body*> Bodies::sparse_grid() {
  const std::string name = "sparse-grid";
  if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
  auto medium = liver(LiverResolution::kMedium);
  if (!medium) return std::unexpected(medium.error());
  mesh::TriMesh filled = mesh::extract_boundary((*medium)->nodes, (*medium)->tets).surface;
  auto grid = mesh::sparse_grid(filled, kSparseGridNodes);
  if (!grid) return std::unexpected(grid.error());
  mesh::TriMesh surface = mesh::hex_boundary(grid->nodes, grid->hexes).surface;
  Body b{name, grid->nodes, {}, grid->hexes, surface.triangles.size(), surface, std::move(filled)};
  return &bodies_.emplace(name, std::move(b)).first->second;
}

Expected<const Body*> Bodies::by_name(const std::string& name) {
  if (name == "sparse-grid") return sparse_grid();
  return liver(*mesh::parse_liver_resolution(name));
}

const char* field_name(Field f) {
  switch (f) {
    case Field::kSprings:
      return "springs";
    case Field::kSmall:
      return "linear-fem";
    case Field::kLarge:
      return "corotational-fem";
    case Field::kNeoHookean:
      return "neo-hookean";
    case Field::kHexahedra:
      return "hexahedral-fem";
  }
  return "?";
}

const char* settings_name(Settings s) { return s == Settings::kThesis ? "thesis" : "physiological"; }

const char* solver_name(Solver s) {
  switch (s) {
    case Solver::kExplicitEuler:
      return "explicit-euler";
    case Solver::kSymplecticEuler:
      return "symplectic-euler";
    case Solver::kRungeKutta4:
      return "rk4";
    case Solver::kStatic:
      return "static-cg";
    case Solver::kImplicitCg:
      return "implicit-cg";
    case Solver::kImplicitLdlt:
      return "implicit-ldlt";
  }
  return "?";
}

namespace {

// Numbers as the scene writes them: the shortest text that reads back as the same double.
std::string numbers_text(const std::vector<Vec3>& points) {
  std::string out;
  out.reserve(points.size() * 60);
  for (const Vec3& p : points) fmt::format_to(std::back_inserter(out), "{} {} {} ", p.x(), p.y(), p.z());
  return out;
}

template <typename Elements>
std::string indices_text(const Elements& elements) {
  std::string out;
  out.reserve(elements.size() * 24);
  for (const auto& e : elements)
    for (const auto i : e) fmt::format_to(std::back_inserter(out), "{} ", i);
  return out;
}

// The body's geometry as the scene gives it: a tetrahedral liver's nodes and tetrahedra, or
// the surface the sparse grid fills (the reader makes the grid, as it does for a user's
// SparseGridTopology; fillWeighted off: the bench's grid weighs every cell whole).
std::string geometry_text(const Body& b) {
  if (b.filled_surface) {
    return fmt::format(
        "    <MechanicalObject name=\"state\"/>\n"
        "    <SparseGridTopology name=\"grid\" n=\"{} {} {}\" fillWeighted=\"0\" position=\"{}\" triangles=\"{}\"/>\n",
        kSparseGridNodes[0], kSparseGridNodes[1], kSparseGridNodes[2], numbers_text(b.filled_surface->vertices),
        indices_text(b.filled_surface->triangles));
  }
  return fmt::format(
      "    <MechanicalObject name=\"state\" position=\"{}\"/>\n"
      "    <MeshTopology name=\"mesh\" tetrahedra=\"{}\"/>\n",
      numbers_text(b.nodes), indices_text(b.tets));
}

// The spring cells' stiffness and damping. Springs have no Young's modulus; physiologically, a
// spring over an edge of length l standing for a rod of section l² gives k ≈ E·l (a
// dimensional estimate, not a fitted law), with the thesis' damping ratio to stiffness kept.
std::pair<double, double> spring_values(const Body& b, bool thesis, double young) {
  if (thesis) return {10000.0, 15.0};
  double length = 0.0;
  for (const mesh::Tet& t : b.tets)
    length += (b.nodes[static_cast<std::size_t>(t[0])] - b.nodes[static_cast<std::size_t>(t[1])]).norm();
  const double stiffness = young * length / static_cast<double>(std::max<std::size_t>(b.tets.size(), 1));
  return {stiffness, 15.0 * stiffness / 10000.0};
}

// The force field's component. The springs are HoF's own (the same stiffness for every spring,
// the clamped tangent: the reader's HoF extension), as the thesis' mesh springs were. The
// Neo-Hookean field is written as SOFA's (ParameterSet μ k); body_config sets its E and ν.
std::string force_field_text(const Body& b, Field field, bool thesis, double young, double poisson) {
  const char* name = field_name(field);
  switch (field) {
    case Field::kSprings: {
      const auto [stiffness, damping] = spring_values(b, thesis, young);
      return fmt::format(
          "    <MeshSpringForceField name=\"{}\" stiffness=\"{}\" damping=\"{}\" stiffnessRule=\"sameForEverySpring\" "
          "tangent=\"clampedTransverse\"/>\n",
          name, stiffness, damping);
    }
    case Field::kSmall:
    case Field::kLarge:
      return fmt::format(
          "    <TetrahedronFEMForceField name=\"{}\" youngModulus=\"{}\" poissonRatio=\"{}\" method=\"{}\"/>\n", name,
          young, poisson, field == Field::kSmall ? "small" : "large");
    case Field::kNeoHookean: {
      const double shear = young / (2.0 * (1.0 + poisson)), bulk = young / (3.0 * (1.0 - 2.0 * poisson));
      return fmt::format(
          "    <TetrahedronHyperelasticityFEMForceField name=\"{}\" materialName=\"NeoHookean\" ParameterSet=\"{} "
          "{}\"/>\n",
          name, shear, bulk);
    }
    case Field::kHexahedra:
      return fmt::format(
          "    <HexahedronFEMForceField name=\"{}\" youngModulus=\"{}\" poissonRatio=\"{}\" method=\"large\"/>\n", name,
          young, poisson);
  }
  return {};
}

// The table: the nodes of the lowest 4 mm (a grid's own nodes, for the sparse grid).
std::string table_text(const Body& b) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : b.nodes) lowest = std::min(lowest, p.z());
  std::string indices;
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    if (b.nodes[i].z() < lowest + 0.004) fmt::format_to(std::back_inserter(indices), "{} ", i);
  }
  return fmt::format("    <FixedProjectiveConstraint name=\"table\" indices=\"{}\"/>\n", indices);
}

}  // namespace

// The thesis' settings (l. 1254, 1271): gravity 9.8, total mass 1 kg, mesh springs 10,000 /
// 15, FEM E = 100, ν = 0.4, in SOFA's unit-free scenes. The physiological ones: liver
// E ≈ 5 kPa, ν ≈ 0.45, 1060 kg/m³ (literature.md §6). Our livers are in metres with z up, so
// gravity points along −z (the thesis' liver was y-up). Both rest on their lowest 4 mm (a
// table under the organ), which keeps every model's motion bounded under gravity.
// The CG's iteration count is what is measured: no early stop on the residual (1e-12).
std::string body_scene(const Body& b, Field field, Settings s, const ImplicitCgScene& solver) {
  const bool thesis = s == Settings::kThesis;
  const double young = thesis ? 100.0 : 5000.0;
  const double poisson = thesis ? 0.4 : 0.45;
  std::string text =
      fmt::format("<Node name=\"root\" dt=\"{}\" gravity=\"0 0 {}\">\n  <Node name=\"liver\">\n", solver.dt_s,
                  !solver.gravity ? 0.0
                  : thesis        ? -9.8
                                  : -9.81);
  text += fmt::format("    <EulerImplicitSolver name=\"odesolver\" rayleighMass=\"{}\" rayleighStiffness=\"0.1\"/>\n",
                      solver.rayleigh_mass);
  text +=
      fmt::format("    <CGLinearSolver name=\"linearsolver\" iterations=\"{}\" tolerance=\"{}\" threshold=\"{}\"/>\n",
                  solver.iterations, solver.tolerance, solver.tolerance);
  text += geometry_text(b);
  text += thesis ? "    <UniformMass name=\"mass\" totalMass=\"1\"/>\n"
                 : "    <DiagonalMass name=\"mass\" massDensity=\"1060\"/>\n";
  text += force_field_text(b, field, thesis, young, poisson);
  text += table_text(b);
  text += "  </Node>\n</Node>\n";
  return text;
}

ModelConfig body_config(const Body& b, Field field, Settings s, const ImplicitCgScene& solver) {
  // Built as `hof run` builds a scene's body: the SOFA reader makes the ModelConfig.
  auto scene = scene::read_sofa_scene_text(body_scene(b, field, s, solver),
                                           std::filesystem::path("hof-bench") / (b.name + ".scn"));
  HOF_CHECK(scene && scene->models.size() == 1, "the bench's own scene reads as one body");
  ModelConfig c = std::move(scene->models.front().config);
  // What the scene cannot say. Neo-Hookean: SOFA's component takes (μ, k), which the reader
  // turns into E and ν by a formula that rounds (5 kPa, 0.45 read back as E =
  // 5000.0000000000009 Pa); HoF's field is defined by E and ν, which the cells state exactly.
  // Newton iterations: only SOFA's StaticSolver has them (the static cells' count, which
  // set_solver keeps). Threads: a scene has none; 0 (all cores) is the reader's as the bench's.
  if (field == Field::kNeoHookean) {
    auto& neo = *c.force_fields.front().neo_hookean;
    neo.young_modulus_pa = s == Settings::kThesis ? 100.0 : 5000.0;
    neo.poisson_ratio = s == Settings::kThesis ? 0.4 : 0.45;
  }
  c.ode.newton_iterations = 1;
  return c;
}

void set_solver(ModelConfig& c, Solver s, double dt_s) {
  c.dt_s = dt_s;
  switch (s) {
    case Solver::kExplicitEuler:
      c.ode.kind = OdeSolverKind::kEulerExplicit;
      c.ode.symplectic = false;
      break;
    case Solver::kSymplecticEuler:
      c.ode.kind = OdeSolverKind::kEulerExplicit;
      c.ode.symplectic = true;
      break;
    case Solver::kRungeKutta4:
      c.ode.kind = OdeSolverKind::kRungeKutta4;
      break;
    case Solver::kStatic:
      // Every step makes its Newton iteration, as SOFA's StaticSolver with a fixed count
      // does: a step skipped because the residual is already small would time nothing.
      c.ode.kind = OdeSolverKind::kStatic;
      c.ode.newton_residual_tolerance_n = 0.0;
      break;
    case Solver::kImplicitCg:
      c.ode.kind = OdeSolverKind::kEulerImplicit;
      break;
    case Solver::kImplicitLdlt:
      c.ode.kind = OdeSolverKind::kEulerImplicit;
      c.linear.kind = LinearSolverKind::kSparseLdlt;
      break;
  }
}

void use_haptic_rate_cg(ModelConfig& c) { use_haptic_rate_solver(c.linear, c.ode, c.positions.size()); }

// The haptic-rate CG stays mechanics' own typed mode (use_haptic_rate_solver), as `hof run`
// applies it: its iterations follow the body's size.
ModelConfig corotational_config(const Body& b, const CorotationalSetup& s) {
  ModelConfig config = body_config(b, Field::kLarge, Settings::kPhysiological,
                                   {.dt_s = s.dt_s, .iterations = s.iterations, .gravity = s.gravity});
  if (s.haptic_rate_cg) use_haptic_rate_cg(config);
  return config;
}

std::string dt_label(double dt) { return fmt::format("dt{:g}", dt); }

// Strongly damped (Rayleigh mass 1): the press is quasi-static.
ModelConfig coupling_press_config(const Body& b) {
  return body_config(b, Field::kLarge, Settings::kPhysiological,
                     {.iterations = 100, .tolerance = 1e-9, .rayleigh_mass = 1.0, .gravity = false});
}

std::size_t pressed_vertex(const Body& b, const mesh::BoundarySurface& boundary) {
  Vec3 lo = b.nodes.front(), hi = lo;
  for (const Vec3& p : b.nodes) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d middle = 0.5 * (lo + hi).head<2>();
  std::size_t top = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < boundary.surface.vertices.size(); ++i) {
    const Vec3& v = boundary.surface.vertices[i];
    const double score = (v.head<2>() - middle).norm() - 0.5 * (v.z() - lo.z());
    if (score < best) {
      best = score;
      top = i;
    }
  }
  return top;
}

haptics::MotionConfig framework_press(const Vec3& top) {
  return haptics::MotionConfig::poke(top + Vec3(0, 0, 0.01), Vec3(0, 0, -1), 0.01, 0.008, 0.02, 10.0);
}

coupling::SessionConfig framework_session_config(coupling::ContactCoupling mode) {
  coupling::SessionConfig config;
  config.coupling = mode;
  config.haptics.rate_hz = 1000.0;
  config.haptics.renderer.kind = haptics::RendererKind::kRuspini;
  config.haptics.material.stiffness = 0.2;
  return config;
}

}  // namespace hof::app::bench
