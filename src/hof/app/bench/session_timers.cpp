#include "hof/app/bench/timers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

#include "hof/app/gui/gui_app.h"
#include "hof/core/file_write.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/mesh_io.h"
#include "hof/scene/world.h"

namespace hof::app::bench {

using namespace hof::mechanics;

namespace {

void fill_framework_cell(const coupling::SessionReport& report, Cell& cell) {
  cell.stable = !report.diverged;
  cell.failure = report.divergence;
  cell.steps = report.simulation_steps;
  cell.median = cell.min = cell.max = report.simulation_steps_per_s;
  cell.simulated_s = report.simulated_s;
  cell.wall_s = report.wall_s;
  cell.rate_untouched = report.rate_untouched > 0.0 ? report.rate_untouched : kNaN;
  cell.rate_deforming = report.rate_deforming > 0.0 ? report.rate_deforming : kNaN;
  cell.rate_contact = report.rate_in_contact > 0.0 ? report.rate_in_contact : kNaN;
  cell.tick_p50_us = 1e6 * report.haptic_periods.quantile_s(0.5);
  cell.tick_p99_us = 1e6 * report.haptic_periods.quantile_s(0.99);
  cell.tick_max_us = 1e6 * report.haptic_periods.max_s();
  cell.contact_fraction = report.contact_time_s / std::max(report.wall_s, 1e-9);  // haptic ticks keep wall time
  cell.measured = report.simulation_steps > 0;
}

// The figures of a run in virtual time, whose rate is the machine's: steps per wall second.
void fill_virtual_cell(const coupling::SessionReport& report, double wall_s, Cell& cell) {
  cell.stable = !report.diverged;
  cell.failure = report.divergence;
  cell.steps = report.simulation_steps;
  cell.simulated_s = report.simulated_s;
  cell.wall_s = wall_s;
  cell.median = cell.min = cell.max = static_cast<double>(report.simulation_steps) / std::max(wall_s, 1e-9);
  cell.measured = report.simulation_steps > 0;
}

// A cell that could not be set up: unstable, with the reason.
void fail_cell(const Error& error, Cell& cell) {
  cell.stable = false;
  cell.failure = error.to_string();
}

// A session of `bodies` pressed by a scripted hand moving as `motion`, or null (the cell
// failed) when it cannot be made.
std::unique_ptr<coupling::Session> pressed_session(std::vector<coupling::SessionBody> bodies,
                                                   const haptics::MotionConfig& motion,
                                                   const std::optional<haptics::DeviceSpec>& spec,
                                                   const coupling::SessionConfig& config, Cell& cell) {
  auto scripted = haptics::ScriptedMotion::make(motion);
  if (!scripted) {
    fail_cell(scripted.error(), cell);
    return nullptr;
  }
  auto device = spec ? std::make_unique<haptics::ScriptedDevice>(*scripted, *spec)
                     : std::make_unique<haptics::ScriptedDevice>(*scripted);
  auto session = coupling::Session::make(std::move(bodies), std::move(device), config);
  if (!session) {
    fail_cell(session.error(), cell);
    return nullptr;
  }
  return std::move(*session);
}

// The press of the framework cells on the liver `b`: onto the top of its surface.
haptics::MotionConfig framework_press_on(const Body& b) {
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  return framework_press(boundary.surface.vertices[pressed_vertex(b, boundary)]);
}

}  // namespace

// The whole framework (thesis Figure 34): a real-time session, the haptic loop and the
// simulation each on its own thread, a scripted hand pressing the liver's top from 1 cm above
// (contact after about 0.5 s, then held). Its rates, and the haptic period's p50/p99/max.
void time_framework(const Body& b, const ModelConfig& config, coupling::ContactCoupling mode, double seconds,
                    Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  auto body = scene::deformable_body(config);
  if (!body) return fail_cell(body.error(), cell);
  std::vector<coupling::SessionBody> bodies;
  bodies.push_back(std::move(*body));
  auto session =
      pressed_session(std::move(bodies), framework_press_on(b), std::nullopt, framework_session_config(mode), cell);
  if (session) fill_framework_cell(session->run_realtime(seconds, {}), cell);
}

// The framework with the window open (thesis Figure 34 was a window): the haptic-rate press
// of time_framework, written out as a project (the liver as Gmsh, a SOFA scene, a `.hof`
// naming the scripted hand as its device) into DIR/window and opened by `hof gui` in this
// process, which draws it for `seconds` and stops. Needs a display (Xvfb will do).
void time_framework_window(const Body& b, const ModelConfig& config, const std::filesystem::path& dir, double seconds,
                           Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display) {
    cell.failure = "no display: run `xvfb-run -a hof bench` (or from a desktop) to measure the window";
    return;
  }
  const std::filesystem::path at = dir / "window";
  std::error_code ec;
  std::filesystem::create_directories(at, ec);
  mesh::Mesh liver;
  liver.nodes = b.nodes;
  liver.tets = b.tets;
  if (auto w = mesh::write_msh(liver, at / "liver.msh", mesh::MshVersion::k2_2); !w) {
    cell.stable = false;
    cell.failure = w.error().to_string();
    return;
  }
  const TetrahedronFemConfig& fem = *config.force_fields.front().tetrahedron_fem;
  std::string fixed;
  for (const std::int32_t i : config.fixed.front().indices) fixed += fmt::format("{}{}", fixed.empty() ? "" : " ", i);
  const std::string scene = fmt::format(
      "<?xml version=\"1.0\"?>\n<!-- Written by hof bench: the framework cell with the window open. -->\n"
      "<Node name=\"root\" dt=\"{}\" gravity=\"0 0 0\">\n  <Node name=\"Liver\">\n"
      "    <EulerImplicitSolver name=\"solver\" rayleighStiffness=\"{}\" rayleighMass=\"{}\"/>\n"
      "    <CGLinearSolver name=\"cg\" iterations=\"{}\" tolerance=\"1e-12\" threshold=\"1e-12\" warmStart=\"{}\" "
      "coarseCorrection=\"{}\"/>\n"
      "    <MeshGmshLoader name=\"loader\" filename=\"liver.msh\"/>\n    <MeshTopology name=\"topology\" "
      "src=\"@loader\"/>\n"
      "    <MechanicalObject name=\"dofs\" src=\"@loader\"/>\n    <DiagonalMass name=\"mass\" massDensity=\"{}\"/>\n"
      "    <TetrahedronFEMForceField name=\"FEM\" youngModulus=\"{}\" poissonRatio=\"{}\" method=\"large\"/>\n"
      "    <FixedProjectiveConstraint name=\"base\" indices=\"{}\"/>\n  </Node>\n</Node>\n",
      config.dt_s, config.ode.rayleigh_stiffness, config.ode.rayleigh_mass, config.linear.iterations,
      config.linear.warm_start ? "true" : "false", config.linear.coarse_correction ? "true" : "false",
      config.mass.mass_density_kg_per_m3, fem.young_modulus_pa, fem.poisson_ratio, fixed);
  const haptics::MotionConfig press = framework_press_on(b);
  const std::string device = fmt::format(
      "scripted:poke,start={};{};{},direction=0;0;-1,approach={},depth={},speed={},hold={}", press.start_m.x(),
      press.start_m.y(), press.start_m.z(), press.approach_m, press.depth_m, press.speed_m_per_s, press.hold_s);
  const std::string project = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<hof version=\"1\" name=\"hof bench: the framework with the window "
      "open\">\n"
      "  <mechanics scene=\"liver.scn\">\n"
      "    <set body=\"Liver\" component=\"solver\" parameter=\"matrixReuseSteps\" value=\"{}\"/>\n  </mechanics>\n"
      "  <haptics device=\"{}\" hapticRate=\"1000\" renderer=\"RuspiniRenderer\" coupling=\"fem-reaction\">\n"
      "    <surface type=\"SmoothSurface\" stiffness=\"0.2\" damping=\"0\" useRelativeValues=\"true\"/>\n  "
      "</haptics>\n</hof>\n",
      config.ode.matrix_reuse_steps, device);
  const std::string script = fmt::format("wait {}\nquit\n", seconds);
  for (const auto& [file, text] :
       {std::pair{"liver.scn", scene}, std::pair{"liver.hof", project}, std::pair{"script.txt", script}}) {
    if (auto w = write_file_atomically(at / file, text); !w) {
      cell.stable = false;
      cell.failure = w.error().to_string();
      return;
    }
  }
  GuiRunResult result;
  GuiOptions options;
  options.file = at / "liver.hof";
  options.script = at / "script.txt";
  options.quiet = true;
  options.result = &result;
  if (run_gui(options) != 0 || !result.session) {
    cell.stable = false;
    cell.failure =
        fmt::format("the window did not run the project {} (see the messages above)", options.file->string());
    return;
  }
  fill_framework_cell(*result.session, cell);
  cell.frames_per_s = static_cast<double>(result.frames) / std::max(result.wall_s, 1e-9);
}

// Several bodies (the world of issue 12): one liver against two side by side, 25 cm apart,
// the first pressed, in virtual time so that the rate is the machine's, not the clock's. The
// bodies of a world step in parallel, each with its own threads.
void time_bodies(const Body& b, const ModelConfig& config, int count, double seconds, Cell& cell) {
  cell.matrix_reuse = config.ode.matrix_reuse_steps;  // as the model runs (it depends on the mesh)
  std::vector<coupling::SessionBody> bodies;
  for (int i = 0; i < count; ++i) {
    const Vec3 offset(0.25 * i, 0.0, 0.0);
    ModelConfig c = config;
    for (Vec3& p : c.positions) p += offset;
    auto body = scene::deformable_body(c);
    if (!body) return fail_cell(body.error(), cell);
    body->name = fmt::format("liver{}", i + 1);
    bodies.push_back(std::move(*body));
  }
  coupling::SessionConfig session_config = framework_session_config(coupling::ContactCoupling::kBarycentric);
  session_config.haptics.realtime_priority = false;
  auto session = pressed_session(std::move(bodies), framework_press_on(b), std::nullopt, session_config, cell);
  if (!session) return;
  const auto t0 = Clock::now();
  const coupling::SessionReport report = session->run_virtual(seconds, {});
  fill_virtual_cell(report, seconds_since(t0), cell);
  cell.contact_fraction = report.contact_time_s / std::max(report.simulated_s, 1e-9);
}

// The coupling schemes against the static FEM reaction (the set-up of
// tests/coupling/compliance_test.cpp): a slow press (4 mm at 4 mm/s, then held) straight down
// onto the top's surface node, in virtual time, strongly damped so that the tissue follows
// quasi-statically. At 1, 2, 3 and 4 mm below the rest surface the felt force is compared
// with the static FEM reaction of the node held at that depth (Newton with an exact LDLT
// solve); the cell's error is the largest |felt − reaction| / |reaction|. The contact
// schemes render the proxy's spring (stiffness × penetration of the displaced surface); the
// compliance and fem-reaction schemes render the FEM's own response.
Expected<CouplingReference> coupling_reference(const Body& b) {
  CouplingReference ref;
  const mesh::BoundarySurface boundary = mesh::extract_boundary(b.nodes, b.tets);
  const std::size_t vertex = pressed_vertex(b, boundary);
  ref.node = boundary.surface_to_volume[vertex];
  ref.top = b.nodes[static_cast<std::size_t>(ref.node)];
  for (const double depth : {0.001, 0.002, 0.003, 0.004}) {
    ModelConfig c = coupling_press_config(b);
    c.fixed.push_back(FixedConstraintConfig{"probe", {ref.node}, std::nullopt, false, {true, true, true}});
    c.ode.kind = OdeSolverKind::kStatic;
    c.ode.newton_iterations = 30;
    c.ode.newton_residual_tolerance_n = 1e-9;
    c.linear.kind = LinearSolverKind::kSparseLdlt;
    auto model = build_model(c);
    if (!model) return std::unexpected(model.error());
    MechanicalState state = make_state(*model);
    state.x.segment<3>(3 * static_cast<Eigen::Index>(ref.node)) = ref.top - Vec3(0, 0, depth);
    if (!step(*model, state))
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("the static reference at {} mm did not converge", 1e3 * depth));
    Eigen::VectorXd internal = Eigen::VectorXd::Zero(state.x.size());
    model->force_fields[0]->add_force(state.x, state.v, state.field_states[0], internal);
    ref.depths.push_back(depth);
    ref.reactions.push_back(internal.segment<3>(3 * static_cast<Eigen::Index>(ref.node)));
  }
  return ref;
}

void time_coupling(const Body& b, const CouplingReference& ref, coupling::ContactCoupling mode, Cell& cell) {
  ModelConfig config = coupling_press_config(b);
  if (mode == coupling::ContactCoupling::kFemReaction) {
    config.dt_s = 0.001;
    use_haptic_rate_cg(config);
  }
  cell.matrix_reuse = config.ode.matrix_reuse_steps;
  auto body = scene::deformable_body(config);
  if (!body) return fail_cell(body.error(), cell);
  std::vector<coupling::SessionBody> bodies;
  bodies.push_back(std::move(*body));
  // Held 1 s: the run ends 0.6 s into the hold.
  const haptics::MotionConfig motion =
      haptics::MotionConfig::poke(ref.top + Vec3(0, 0, 0.004), Vec3(0, 0, -1), 0.004, 0.004, 0.004, 1.0);
  haptics::DeviceSpec spec;
  spec.max_force_n = 50.0;
  spec.max_stiffness_n_per_m = 2000.0;
  coupling::SessionConfig session_config;
  session_config.coupling = mode;
  session_config.haptics.renderer.kind = haptics::RendererKind::kGodObject;
  session_config.haptics.material.stiffness = 1.0;  // the device's stiffest: 2,000 N/m
  session_config.haptics.safety.fade_in_s = 0.0;
  session_config.haptics.realtime_priority = false;
  auto session = pressed_session(std::move(bodies), motion, spec, session_config, cell);
  if (!session) return;
  // The samples nearest each reference depth, in contact, after the approach.
  std::vector<haptics::HapticSample> nearest(ref.depths.size());
  std::vector<double> distance(ref.depths.size(), std::numeric_limits<double>::infinity());
  const auto t0 = Clock::now();
  haptics::HapticSample settled;
  bool have_settled = false;
  const coupling::SessionReport report = session->run_virtual(2.6, [&](const haptics::HapticSample& s) {
    if (!s.contact || s.time_s < 0.5) return;
    settled = s;  // the last in contact: 0.6 s into the hold at 4 mm
    have_settled = true;
    for (std::size_t k = 0; k < ref.depths.size(); ++k) {
      const double d = std::abs(ref.top.z() - s.device.z() - ref.depths[k]);
      if (d < distance[k]) {
        distance[k] = d;
        nearest[k] = s;
      }
    }
  });
  fill_virtual_cell(report, seconds_since(t0), cell);
  double worst = 0.0;
  for (std::size_t k = 0; k < ref.depths.size(); ++k) {
    if (!std::isfinite(distance[k])) {
      cell.failure = fmt::format("no contact at {} mm", 1e3 * ref.depths[k]);
      return;
    }
    worst = std::max(worst, (nearest[k].force - ref.reactions[k]).norm() / std::max(ref.reactions[k].norm(), 1e-12));
  }
  cell.force_error = worst;
  if (have_settled && std::abs(ref.top.z() - settled.device.z() - ref.depths.back()) < 1e-6) {
    cell.force_error_settled =
        (settled.force - ref.reactions.back()).norm() / std::max(ref.reactions.back().norm(), 1e-12);
  }
}

}  // namespace hof::app::bench
