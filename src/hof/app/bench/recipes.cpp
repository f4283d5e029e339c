#include "hof/app/bench/recipes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <limits>

#include "hof/mesh/hex_grid.h"
#include "hof/mesh/liver_generator.h"

namespace hof::app::bench {

using namespace hof::mechanics;
using mesh::LiverResolution;

Expected<const Body*> Bodies::liver(LiverResolution r) {
  const std::string name(mesh::to_string(r));
  if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
  auto m = mesh::generate_liver(r);
  if (!m) return std::unexpected(m.error());
  mesh::TriMesh surface = mesh::extract_boundary(m->nodes, m->tets).surface;
  Body b{name, m->nodes, m->tets, {}, surface.triangles.size(), surface};
  return &bodies_.emplace(name, std::move(b)).first->second;
}

// SOFA's SparseGridTopology over the medium liver's surface, 24×16×10 nodes: cells of about 1 cm.
Expected<const Body*> Bodies::sparse_grid() {
  const std::string name = "sparse-grid";
  if (auto it = bodies_.find(name); it != bodies_.end()) return &it->second;
  auto medium = liver(LiverResolution::kMedium);
  if (!medium) return std::unexpected(medium.error());
  auto grid = mesh::sparse_grid(mesh::extract_boundary((*medium)->nodes, (*medium)->tets).surface, {24, 16, 10});
  if (!grid) return std::unexpected(grid.error());
  mesh::TriMesh surface = mesh::hex_boundary(grid->nodes, grid->hexes).surface;
  Body b{name, grid->nodes, {}, grid->hexes, surface.triangles.size(), surface};
  return &bodies_.emplace(name, std::move(b)).first->second;
}

Expected<const Body*> Bodies::by_name(const std::string& name) {
  if (name == "sparse-grid") return sparse_grid();
  return liver(*mesh::parse_liver_resolution(name));
}


const char* field_name(Field f) {
  switch (f) {
    case Field::kSprings: return "springs";
    case Field::kSmall: return "linear-fem";
    case Field::kLarge: return "corotational-fem";
    case Field::kNeoHookean: return "neo-hookean";
    case Field::kHexahedra: return "hexahedral-fem";
  }
  return "?";
}

const char* settings_name(Settings s) { return s == Settings::kThesis ? "thesis" : "physiological"; }


const char* solver_name(Solver s) {
  switch (s) {
    case Solver::kExplicitEuler: return "explicit-euler";
    case Solver::kSymplecticEuler: return "symplectic-euler";
    case Solver::kRungeKutta4: return "rk4";
    case Solver::kStatic: return "static-cg";
    case Solver::kImplicitCg: return "implicit-cg";
    case Solver::kImplicitLdlt: return "implicit-ldlt";
  }
  return "?";
}

// The thesis' settings (l. 1254, 1271): gravity 9.8, total mass 1 kg, mesh springs 10,000 /
// 15, FEM E = 100, ν = 0.4, in SOFA's unit-free scenes. The physiological ones: liver
// E ≈ 5 kPa, ν ≈ 0.45, 1060 kg/m³ (literature.md §6). Our livers are in metres with z up, so
// gravity points along −z (the thesis' liver was y-up). Both rest on their lowest 4 mm (a
// table under the organ), which keeps every model's motion bounded under gravity.
ModelConfig body_config(const Body& b, Field field, Settings s) {
  ModelConfig c;
  c.name = "liver";
  c.positions = b.nodes;
  c.tets = b.tets;
  c.hexahedra = b.hexes;
  const bool thesis = s == Settings::kThesis;
  if (thesis) {
    c.mass.kind = MassKind::kUniform;
    c.mass.total_mass_kg = 1.0;
  } else {
    c.mass.kind = MassKind::kDiagonal;
    c.mass.mass_density_kg_per_m3 = 1060.0;
  }
  c.gravity_m_per_s2 = Vec3(0, 0, thesis ? -9.8 : -9.81);
  const double young = thesis ? 100.0 : 5000.0;
  const double poisson = thesis ? 0.4 : 0.45;
  ForceFieldConfig f;
  f.name = field_name(field);
  switch (field) {
    case Field::kSprings: {
      double stiffness = 10000.0, damping = 15.0;
      if (!thesis) {
        // Springs have no Young's modulus; a spring over an edge of length l standing for a
        // rod of section l² gives k ≈ E·l (a dimensional estimate, not a fitted law), with
        // the thesis' damping ratio to stiffness kept.
        double length = 0.0;
        for (const mesh::Tet& t : b.tets) length += (b.nodes[static_cast<std::size_t>(t[0])] - b.nodes[static_cast<std::size_t>(t[1])]).norm();
        stiffness = young * length / static_cast<double>(std::max<std::size_t>(b.tets.size(), 1));
        damping = 15.0 * stiffness / 10000.0;
      }
      f.mesh_springs = MeshSpringConfig{stiffness, damping, 1.0};
      break;
    }
    case Field::kSmall: f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kSmall, {}, {}}; break;
    case Field::kLarge: f.tetrahedron_fem = TetrahedronFemConfig{young, poisson, FemMethod::kLarge, {}, {}}; break;
    case Field::kNeoHookean: f.neo_hookean = NeoHookeanConfig{young, poisson, {}, {}}; break;
    case Field::kHexahedra: {
      HexahedronFemConfig h;
      h.young_modulus_pa = young;
      h.poisson_ratio = poisson;
      h.method = FemMethod::kLarge;
      f.hexahedron_fem = h;
      break;
    }
  }
  c.force_fields.push_back(f);
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : b.nodes) lowest = std::min(lowest, p.z());
  FixedConstraintConfig fixed;
  fixed.name = "table";
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    if (b.nodes[i].z() < lowest + 0.004) fixed.indices.push_back(static_cast<std::int32_t>(i));
  }
  c.fixed.push_back(fixed);
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.ode.newton_iterations = 1;
  c.linear.iterations = 25;
  // The iteration count is what is measured: no early stop on the residual.
  c.linear.tolerance = c.linear.threshold = 1e-12;
  c.dt_s = 0.02;
  c.threads = 0;
  return c;
}

void set_solver(ModelConfig& c, Solver s, double dt_s) {
  c.dt_s = dt_s;
  switch (s) {
    case Solver::kExplicitEuler: c.ode.kind = OdeSolverKind::kEulerExplicit; c.ode.symplectic = false; break;
    case Solver::kSymplecticEuler: c.ode.kind = OdeSolverKind::kEulerExplicit; c.ode.symplectic = true; break;
    case Solver::kRungeKutta4: c.ode.kind = OdeSolverKind::kRungeKutta4; break;
    case Solver::kStatic:
      // Every step makes its Newton iteration, as SOFA's StaticSolver with a fixed count
      // does: a step skipped because the residual is already small would time nothing.
      c.ode.kind = OdeSolverKind::kStatic;
      c.ode.newton_residual_tolerance_n = 0.0;
      break;
    case Solver::kImplicitCg: c.ode.kind = OdeSolverKind::kEulerImplicit; break;
    case Solver::kImplicitLdlt:
      c.ode.kind = OdeSolverKind::kEulerImplicit;
      c.linear.kind = LinearSolverKind::kSparseLdlt;
      break;
  }
}

void use_haptic_rate_cg(ModelConfig& c) { use_haptic_rate_solver(c.linear, c.ode, c.positions.size()); }

ModelConfig corotational_config(const Body& b, const CorotationalSetup& s) {
  ModelConfig config = body_config(b, Field::kLarge, Settings::kPhysiological);
  set_solver(config, Solver::kImplicitCg, s.dt_s);
  config.linear.iterations = s.iterations;
  if (s.haptic_rate_cg) use_haptic_rate_cg(config);
  if (!s.gravity) config.gravity_m_per_s2 = Vec3::Zero();
  return config;
}

std::string dt_label(double dt) { return fmt::format("dt{:g}", dt); }

ModelConfig coupling_press_config(const Body& b) {
  ModelConfig c = body_config(b, Field::kLarge, Settings::kPhysiological);
  c.gravity_m_per_s2 = Vec3::Zero();
  c.ode.rayleigh_mass = 1.0;  // strongly damped: the press is quasi-static
  c.ode.rayleigh_stiffness = 0.1;
  c.linear.iterations = 100;
  c.linear.tolerance = c.linear.threshold = 1e-9;
  return c;
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
