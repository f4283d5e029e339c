#include "hof/app/run_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "hof/core/progress.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/mechanics/step.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/mesh_io.h"
#include "hof/scene/project.h"
#include "hof/scene/sofa_scene.h"
#include "hof/scene/x3d_scene.h"

namespace hof::app {

namespace {

int fail(const Error& e) {
  std::fprintf(stderr, "hof: %s\n", e.to_string().c_str());
  return 1;
}
int fail(const std::string& message) {
  std::fprintf(stderr, "hof: %s\n", message.c_str());
  return 1;
}

struct Loaded {
  scene::HofProject project;
  scene::SofaScene sofa;
  std::filesystem::path scene_path;
};

// An X3D scene with H3D nodes: its DeformableShape (else its first touchable shape) becomes
// the simulated body — the thesis' surface model: springs on the triangle edges (the
// MeshSpringForceField it recommends), uniform mass, the open border held (or, for a closed
// surface, its lowest tenth) — driven by the mechanics instead of H3D's CoordinateDeformer.
// The surface, renderer and calibration come from the scene's Appearance and DeviceInfo.
Expected<Loaded> load_x3d(const std::filesystem::path& file) {
  auto x3d = scene::read_x3d_scene(file);
  if (!x3d) return std::unexpected(x3d.error());
  const scene::X3dShape* chosen = nullptr;
  for (const auto& shape : x3d->shapes) {
    if (!shape.touchable || shape.mesh_W.triangles.empty()) continue;
    if (!chosen || (shape.deformable && !chosen->deformable)) chosen = &shape;
  }
  if (!chosen) return make_error(ErrorCode::kInvalidArgument, "the scene has no touchable shape (a Shape whose Appearance has a surface)", file.string());
  Loaded l;
  l.project.name = file.stem().string();
  l.project.surface = chosen->surface;
  if (!chosen->solid) l.project.touchable_face = collision::TouchableFace::kFrontAndBack;  // X3D solid='false' 
  if (!x3d->devices.empty()) {
    const scene::X3dDevice& device = x3d->devices.front();
    l.project.position_calibration = device.position_calibration;
    if (device.renderer && device.renderer->kind) {
      l.project.renderer = *device.renderer->kind;
      l.project.proxy_radius_m = device.renderer->proxy_radius_m;
    }
  }
  l.project.effects = x3d->force_effects;
  if (!x3d->viewpoints.empty()) l.project.graphics.viewpoint_m = x3d->viewpoints.front().position;
  l.scene_path = file;
  scene::SofaSceneModel model;
  model.node_path = chosen->def.empty() ? std::string("shape") : chosen->def;
  mechanics::ModelConfig& c = model.config;
  c.name = model.node_path;
  c.positions = chosen->mesh_W.vertices;
  c.triangles = chosen->mesh_W.triangles;
  c.mass.kind = mechanics::MassKind::kUniform;
  c.mass.total_mass_kg = 0.1;
  c.gravity_m_per_s2 = Vec3::Zero();
  mechanics::ForceFieldConfig springs;
  springs.name = "springs";
  springs.mesh_springs = mechanics::MeshSpringConfig{100.0, 0.5};
  c.force_fields.push_back(springs);
  // Hold the open border; a closed surface is held by its lowest tenth.
  std::vector<std::int32_t> held;
  {
    std::vector<std::array<std::int32_t, 2>> edges;
    for (const mesh::Tri& t : c.triangles) {
      for (int k = 0; k < 3; ++k) edges.push_back({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i + 1;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i == 1) held.insert(held.end(), edges[i].begin(), edges[i].end());
      i = j;
    }
    std::sort(held.begin(), held.end());
    held.erase(std::unique(held.begin(), held.end()), held.end());
    if (held.empty()) {
      double lo = c.positions.front().y(), hi = lo;
      for (const Vec3& p : c.positions) {
        lo = std::min(lo, p.y());
        hi = std::max(hi, p.y());
      }
      for (std::size_t i = 0; i < c.positions.size(); ++i) {
        if (c.positions[i].y() <= lo + 0.1 * (hi - lo)) held.push_back(static_cast<std::int32_t>(i));
      }
    }
  }
  c.fixed.push_back(mechanics::FixedConstraintConfig{"border", held, std::nullopt, false, {true, true, true}});
  c.ode.rayleigh_mass = c.ode.rayleigh_stiffness = 0.1;
  c.linear.iterations = 25;
  c.dt_s = 0.01;
  l.sofa.file = file;
  l.sofa.models.push_back(std::move(model));
  l.sofa.skipped = x3d->unsupported;
  l.sofa.warnings = x3d->warnings;
  return l;
}

Expected<Loaded> load(const std::filesystem::path& file) {
  Loaded l;
  const std::string ext = file.extension().string();
  if (ext == ".hof") {
    auto project = scene::read_project(file);
    if (!project) return std::unexpected(project.error());
    l.project = *project;
    l.scene_path = scene::scene_file(l.project, file);
  } else if (ext == ".scn") {
    l.project.name = file.stem().string();
    l.project.mechanics_scene = file.filename();
    l.scene_path = file;
  } else if (ext == ".x3d") {
    return load_x3d(file);
  } else {
    return make_error(ErrorCode::kUnsupported, "expected a .hof project, a .scn SOFA scene or an .x3d scene", file.string());
  }
  auto sofa = scene::read_sofa_scene(l.scene_path);
  if (!sofa) return std::unexpected(sofa.error());
  if (sofa->models.empty()) {
    return make_error(ErrorCode::kInvalidArgument, "the scene has no simulated body (a node with an ODE solver and a MechanicalObject)",
                      l.scene_path.string());
  }
  l.sofa = std::move(*sofa);
  return l;
}

// The body of the session: the first model, with its visual mesh (barycentric) as the touchable
// surface when it has one, else the boundary of its tetrahedra (shared nodes).
Expected<coupling::SessionBody> make_body(const scene::SofaSceneModel& m) {
  auto model = mechanics::build_model(m.config);
  if (!model) return std::unexpected(model.error());
  coupling::SessionBody body{m.config.name.empty() ? std::string("model") : m.config.name, std::move(*model), {}, {}};
  if (m.visual_mesh && m.visual_barycentric) {
    auto visual = mesh::read_mesh(*m.visual_mesh);
    if (!visual) return std::unexpected(visual.error());
    body.surface.vertices = visual->mesh.nodes;
    body.surface.triangles = visual->mesh.triangles;
    auto mapping = coupling::SurfaceMapping::barycentric(m.config.positions, m.config.tets, body.surface.vertices);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  } else if (m.config.tets.empty()) {
    // A surface model (springs on triangles): the surface is the model itself.
    body.surface.vertices = m.config.positions;
    body.surface.triangles = m.config.triangles;
    std::vector<mesh::NodeIndex> identity(m.config.positions.size());
    for (std::size_t i = 0; i < identity.size(); ++i) identity[i] = static_cast<mesh::NodeIndex>(i);
    auto mapping = coupling::SurfaceMapping::by_index(m.config.positions, body.surface.vertices, identity);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  } else {
    const mesh::BoundarySurface b = mesh::extract_boundary(m.config.positions, m.config.tets);
    body.surface = b.surface;
    auto mapping = coupling::SurfaceMapping::by_index(m.config.positions, b.surface.vertices, b.surface_to_volume);
    if (!mapping) return std::unexpected(mapping.error());
    body.mapping = std::move(*mapping);
  }
  if (body.surface.triangles.empty()) return make_error(ErrorCode::kInvalidMesh, fmt::format("model '{}' has no surface to touch", body.name));
  return body;
}

std::string csv_number(double v) { return fmt::format("{:.9g}", v); }

void write_plots(const std::filesystem::path& dir, const coupling::SessionReport& report, bool quiet) {
  // Period histogram data (µs, count), then one gnuplot script for all plots, PNG and SVG.
  {
    std::ofstream h(dir / "haptic_period_histogram.dat");
    const auto& bins = report.haptic_periods.bins();
    for (std::size_t b = 0; b < bins.size(); ++b) {
      if (bins[b]) h << b << " " << bins[b] << "\n";
    }
  }
  // One small gnuplot script per plot, so that a plot with no data (no contact, say) does not
  // stop the others; plots.gp collects them for the user.
  struct Plot {
    const char* name;
    const char* body;
  };
  const Plot plots[] = {
      {"force_over_time",
       "set datafile separator ','\nset xlabel 'time (s)'\nset ylabel 'force (N)'\n"
       "plot 'telemetry.csv' every ::1 using 1:(sqrt($8**2+$9**2+$10**2)) with lines title '|F| sent to the device'\n"},
      {"force_vs_indentation",
       "set datafile separator ','\nset xlabel 'indentation (mm)'\nset ylabel 'force (N)'\n"
       "plot 'telemetry.csv' every ::1 using ($11 > 0 ? $12*1000 : 1/0):(sqrt($8**2+$9**2+$10**2)) with points pt 7 ps 0.3 title 'in contact'\n"},
      {"haptic_period_histogram",
       "set xlabel 'haptic period (us)'\nset ylabel 'ticks'\nset logscale y\n"
       "plot 'haptic_period_histogram.dat' using 1:2 with impulses lw 2 title 'period'\n"},
  };
  std::ofstream all(dir / "plots.gp");
  std::string failed;
  for (const Plot& plot : plots) {
    for (const char* ext : {"png", "svg"}) {
      const std::string script = fmt::format("set terminal {} size 960,540\nset output '{}.{}'\nset grid\nset key top left\n{}",
                                             std::string(ext) == "png" ? "pngcairo" : "svg", plot.name, ext, plot.body);
      all << script << "\n";
      const std::filesystem::path file = dir / fmt::format("{}.{}.gp", plot.name, ext);
      std::ofstream(file) << script;
      const std::string command = fmt::format("cd '{}' && gnuplot '{}' 2>/dev/null", dir.string(), file.filename().string());
      if (std::system(command.c_str()) != 0 && std::string(ext) == "png") failed += std::string(failed.empty() ? "" : ", ") + plot.name;
      std::filesystem::remove(file);
    }
  }
  if (!failed.empty() && !quiet) {
    std::fprintf(stderr, "hof: note: no plot for %s (no data, or gnuplot missing); plots.gp is in %s\n", failed.c_str(),
                 dir.c_str());
  }
}

}  // namespace

int run_session(const RunOptions& options) {
  auto loaded = load(options.file);
  if (!loaded) return fail(loaded.error());
  for (const std::string& w : loaded->sofa.warnings) {
    if (!options.quiet) std::fprintf(stderr, "hof: warning: %s\n", w.c_str());
  }
  const scene::SofaSceneModel& first = loaded->sofa.models.front();
  auto body = make_body(first);
  if (!body) return fail(body.error());
  const std::string device_spec = options.device.value_or(loaded->project.device);
  auto device = haptics::open_device(device_spec);
  if (!device) return fail(device.error());
  coupling::SessionConfig config = scene::session_config(loaded->project);
  config.haptics.realtime_priority = !options.deterministic;
  const std::string model_name = body->name;
  const double dt = body->model.dt_s;
  auto session = coupling::Session::make(std::move(*body), std::move(*device), config);
  if (!session) return fail(session.error());

  double seconds = options.seconds.value_or(5.0);
  if (options.steps) seconds = static_cast<double>(*options.steps) * dt;
  if (!(seconds > 0.0) || !std::isfinite(seconds)) return fail(fmt::format("run length must be > 0 s, got {}", seconds));

  // Telemetry straight to the report folder.
  std::FILE* telemetry = nullptr;
  if (options.out) {
    std::error_code ec;
    std::filesystem::create_directories(*options.out, ec);
    if (ec) return fail(Error{ErrorCode::kIo, "cannot create the report folder: " + ec.message(), options.out->string(), 0, -1});
    telemetry = std::fopen((*options.out / "telemetry.csv").c_str(), "w");
    if (!telemetry) return fail(Error{ErrorCode::kIo, "cannot write telemetry.csv", options.out->string(), 0, -1});
    std::fputs("t,device_x,device_y,device_z,proxy_x,proxy_y,proxy_z,force_x,force_y,force_z,contact,penetration,period\n",
               telemetry);
  }
  double next_row = 0.0;
  auto on_sample = [&](const haptics::HapticSample& s) {
    if (!telemetry) return;
    if (options.telemetry_rate_hz > 0.0) {
      if (s.time_s + 1e-12 < next_row) return;
      next_row += 1.0 / options.telemetry_rate_hz;
    }
    std::fputs(fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csv_number(s.time_s), csv_number(s.device.x()),
                           csv_number(s.device.y()), csv_number(s.device.z()), csv_number(s.proxy.x()),
                           csv_number(s.proxy.y()), csv_number(s.proxy.z()), csv_number(s.force.x()),
                           csv_number(s.force.y()), csv_number(s.force.z()), s.contact ? 1 : 0,
                           csv_number(s.penetration_m), csv_number(s.period_s))
                   .c_str(),
               telemetry);
  };
  const auto progress = make_terminal_progress(options.quiet);
  const coupling::SessionReport report = options.deterministic ? (*session)->run_virtual(seconds, on_sample, progress)
                                                               : (*session)->run_realtime(seconds, on_sample, progress);
  if (telemetry) std::fclose(telemetry);

  const auto& periods = report.haptic_periods;
  nlohmann::json summary;
  summary["file"] = options.file.string();
  summary["mode"] = options.deterministic ? "virtual-time (deterministic)" : "real-time";
  summary["device"] = device_spec;
  summary["simulated_s"] = report.simulated_s;
  summary["wall_s"] = report.wall_s;
  summary["haptic"] = {{"ticks", report.haptic_ticks},
                       {"rate_hz", periods.rate_hz()},
                       {"nominal_period_s", periods.nominal_s()},
                       {"period_p50_s", periods.quantile_s(0.5)},
                       {"period_p99_s", periods.quantile_s(0.99)},
                       {"period_max_s", periods.max_s()},
                       {"overruns", periods.overruns()}};
  summary["simulation"] = {{"steps", report.simulation_steps}, {"dt_s", dt}, {"steps_per_s", report.simulation_steps_per_s}};
  summary["graphics_equivalent_fps"] = {
      {"untouched", report.rate_untouched}, {"deforming", report.rate_deforming}, {"in_contact", report.rate_in_contact}};
  summary["max_force_n"] = report.max_force_n;
  summary["contact_time_s"] = report.contact_time_s;
  summary["fall_through_events"] = report.fall_through_events;
  summary["diverged"] = report.diverged;
  if (report.diverged) summary["divergence"] = report.divergence;
  summary["safety"] = {{"clamped_ticks", report.safety.clamped},
                       {"rate_limited_ticks", report.safety.rate_limited},
                       {"non_finite_ticks", report.safety.non_finite},
                       {"no_reading_ticks", report.safety.no_reading},
                       {"watchdog_ticks", report.safety.watchdog}};
  summary["models"] = nlohmann::json::array(
      {{{"name", model_name}, {"nodes", (*session)->model().node_count()}, {"max_displacement_m", report.max_displacement_m}}});
  summary["skipped_components"] = loaded->sofa.skipped;

  if (options.out) {
    std::ofstream(*options.out / "summary.json") << summary.dump(2) << "\n";
    mesh::Mesh final_state;
    const auto& state = (*session)->state();
    for (std::size_t i = 0; i < (*session)->model().node_count(); ++i) {
      final_state.nodes.push_back(state.position(static_cast<std::int32_t>(i)));
    }
    final_state.tets = (*session)->model().tets;
    if (auto ok = mesh::write_vtu(final_state, *options.out / (model_name + ".vtu")); !ok) return fail(ok.error());
    write_plots(*options.out, report, options.quiet);
  }
  if (!options.quiet) {
    std::printf("%s: %.2f s simulated in %.2f s (%s)\n", options.file.c_str(), report.simulated_s, report.wall_s,
                options.deterministic ? "virtual time" : "real time");
    std::printf("  haptic      %lld ticks, %.0f Hz, period p50 %.1f us, p99 %.1f us, max %.1f us, %llu overruns\n",
                static_cast<long long>(report.haptic_ticks), periods.rate_hz(), 1e6 * periods.quantile_s(0.5),
                1e6 * periods.quantile_s(0.99), 1e6 * periods.max_s(), static_cast<unsigned long long>(periods.overruns()));
    std::printf("  simulation  %lld steps, %.0f steps/s\n", static_cast<long long>(report.simulation_steps),
                report.simulation_steps_per_s);
    std::printf("  contact     %.3f s, max force %.3f N, fall-through events %lld, max displacement %.2f mm\n",
                report.contact_time_s, report.max_force_n, static_cast<long long>(report.fall_through_events),
                1e3 * report.max_displacement_m);
    if (report.diverged) std::printf("  DIVERGED    %s\n", report.divergence.c_str());
    if (options.out) std::printf("  report      %s (telemetry.csv, summary.json, %s.vtu, plots)\n", options.out->c_str(), model_name.c_str());
  }
  return report.diverged ? 2 : 0;
}

int run_check(const CheckOptions& options) {
  const std::string ext = options.file.extension().string();
  if (ext == ".hof" || ext == ".scn") {
    auto loaded = load(options.file);
    if (!loaded) return fail(loaded.error());
    int problems = 0;
    for (const auto& m : loaded->sofa.models) {
      auto body = make_body(m);
      if (!body) {
        std::printf("%s\n", body.error().to_string().c_str());
        ++problems;
      } else {
        std::printf("%s: model '%s': %zu nodes, %zu tetrahedra, %zu surface triangles\n", loaded->scene_path.c_str(),
                    body->name.c_str(), body->model.node_count(), body->model.tets.size(), body->surface.triangles.size());
      }
    }
    for (const auto& w : loaded->sofa.warnings) std::printf("warning: %s\n", w.c_str());
    if (ext == ".hof") {
      if (auto device = haptics::open_device(loaded->project.device); !device) {
        std::printf("%s\n", device.error().to_string().c_str());
        ++problems;
      }
    }
    std::printf("%s\n", problems ? fmt::format("{} problem(s)", problems).c_str() : "ok");
    return problems ? 1 : 0;
  }
  if (ext == ".x3d") {
    auto x3d = scene::read_x3d_scene(options.file);
    if (!x3d) return fail(x3d.error());
    std::size_t touchable = 0, triangles = 0;
    for (const auto& shape : x3d->shapes) {
      touchable += shape.touchable ? 1 : 0;
      triangles += shape.mesh_W.triangles.size();
    }
    std::printf("%s: %zu shapes (%zu touchable, %zu triangles), %zu devices\n", options.file.c_str(), x3d->shapes.size(),
                touchable, triangles, x3d->devices.size());
    for (const auto& w : x3d->warnings) std::printf("warning: %s\n", w.c_str());
    std::printf("ok\n");
    return 0;
  }
  auto read = mesh::read_mesh(options.file);
  if (!read) return fail(read.error());
  std::printf("ok\n");
  return 0;
}

}  // namespace hof::app
