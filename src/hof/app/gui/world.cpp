// The world on screen: opened from a file (or from the project in memory), closed, saved;
// the camera framed on it; the needle mounted; the animation paused and resumed.
#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/scene/device_config.h"

namespace hof::app::gui {

namespace {

/// What the panels show of each body of a world just built.
std::vector<BodyView> body_views(const scene::World& world) {
  std::vector<BodyView> bodies;
  for (const coupling::SessionBody& b : world.bodies) {
    BodyView v;
    v.name = b.name;
    v.deformable = b.deformable();
    v.layer = b.layer;
    v.collides = b.collision.enabled;
    v.group = b.collision.group;
    if (b.config) v.set_structure(*b.config);
    if (const auto a = world.appearances.find(b.name); a != world.appearances.end()) {
      render::Material m;
      m.diffuse = render::Rgba(
          static_cast<float>(a->second.diffuse_color.x()), static_cast<float>(a->second.diffuse_color.y()),
          static_cast<float>(a->second.diffuse_color.z()), static_cast<float>(1.0 - a->second.transparency));
      v.material = m;
    }
    bodies.push_back(std::move(v));
  }
  return bodies;
}

}  // namespace

void GuiWindow::close_session() {
  if (recording_) {
    if (auto ok = stop_recording(); !ok) report(ok.error().to_string(), true);
  }
  if (session_) {
    session_->stop_realtime();
    session_.reset();
  }
  needle_.reset();
  shaped_tool_.reset();
  tool_mesh_.reset();
  contacts_ = nullptr;
  mouse_ = nullptr;
}

Expected<void> GuiWindow::open(const std::filesystem::path& file, const scene::HofProject* in_memory) {
  // Everything is built beside the running world, which stays as it is if anything fails.
  const bool is_project = file.extension() == ".hof";
  scene::HofProject project;
  Expected<scene::World> world = make_error(ErrorCode::kIo, "not read");
  if (in_memory) {
    project = *in_memory;
    world = scene::build_world(project, file, options_.device);
  } else if (is_project) {
    auto read = scene::read_project(file);
    if (!read) return std::unexpected(read.error());
    project = *read;
    world = scene::build_world(project, file, options_.device);
  } else {
    const std::string ext = file.extension().string();
    if (ext != ".scn" && ext != ".x3d") {
      return make_error(ErrorCode::kUnsupported, "expected a .hof project, a .scn SOFA scene or an .x3d scene",
                        file.string());
    }
    world = scene::build_world(file, options_.device);
    if (world) project = world->project;
  }
  if (!world) return std::unexpected(world.error());
  warned_.clear();
  for (const std::string& w : world->warnings) {
    warned_.insert(w);
    report("warning: " + w, false);
  }
  // The builder's probe is for headless runs; here the user holds the stylus: the mouse, or
  // the project's own device when it names one.
  std::string spec = world->default_probe && options_.device.empty() ? std::string("mouse") : world->device;
  auto device = scene::open_device(spec);
  if (!device && spec != "mouse") {
    report(
        fmt::format("device '{}' does not answer ({}): the mouse holds the stylus", spec, device.error().to_string()),
        true);
    spec = "mouse";
    device = scene::open_device(spec);
  }
  if (!device) return std::unexpected(device.error());
  auto* mouse = dynamic_cast<haptics::MouseDevice*>(device->get());
  const double max_force = (*device)->spec().max_force_n;
  const double workspace = (*device)->spec().workspace_radius_m;
  std::vector<BodyView> bodies = body_views(*world);
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = true;
  config.simulation_threads = options_.simulation_threads;
  config.pin_threads = options_.pin_threads;
  // The builder fitted the probe's workspace to the world. The mouse reaches anywhere, so a
  // world in metres keeps the file's own calibration (a recording then replays with
  // `hof run FILE --device replay:REC.csv` just as it was made); a SOFA scene, which has no
  // unit, keeps the fit: it gives the world its scale.
  if (spec == "mouse" && world->default_probe && world->length_unit == "m") {
    for (int i = 0; i < 16; ++i)
      config.haptics.calibration.position(i / 4, i % 4) = world->file_calibration[static_cast<std::size_t>(i)];
  }
  auto made = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  if (!made) return std::unexpected(made.error());

  // Accepted: the new world replaces the old one.
  close_session();
  submitted_changes_.clear();
  calibrations_submitted_ = 0;
  calibration_pending_ = false;
  session_ = std::move(*made);
  needle_ = std::dynamic_pointer_cast<procedures::NeedleTool>(config.tool);
  shaped_tool_ = std::dynamic_pointer_cast<const procedures::ShapedTool>(config.tool);
  contact_settings_ = config.contacts;
  disabled_pairs_ = std::set<BodyPair>(config.contacts.disabled_pairs.begin(), config.contacts.disabled_pairs.end());
  tool_panel_.synced = false;
  mouse_orientation_ = Eigen::Quaterniond::Identity();
  needle_phase_ = procedures::NeedlePhase::kFree;
  mouse_ = mouse;
  calibration_ = config.haptics.calibration;
  max_force_n_ = max_force;
  workspace_radius_m_ = workspace;
  file_ = file;
  project_ = std::move(project);
  world_name_ = world->name;
  length_unit_ = world->length_unit;
  device_spec_ = spec;
  default_probe_ = world->default_probe;
  bodies_ = std::move(bodies);
  dirty_ = false;
  error_.clear();
  take_world_shapes(world->visuals);
  take_tool_shape();
  plot_force_.assign(kPlotPoints, 0.0f);
  plot_indentation_.assign(kPlotPoints, 0.0f);
  next_plot_time_ = 0.0;
  plot_force_sum_n_ = 0.0;
  plot_force_ticks_ = 0;
  stats_ = LiveStats{};
  max_force_seen_n_ = max_displacement_seen_m_ = 0.0;
  contact_ticks_ = 0;
  last_ = haptics::HapticSample{};
  was_in_contact_ = false;
  reset_camera();
  place_mouse_stylus_in_front();
  session_->set_realtime_pacing(realtime_pacing_);
  session_->start_realtime();
  if (!animating_) (void)session_->submit(coupling::command::Pause{});
  remember_recent(file);
  report(fmt::format("opened {} ({} bod{}, device {})", file.string(), bodies_.size(),
                     bodies_.size() == 1 ? "y" : "ies", spec),
         false);
  return {};
}

void GuiWindow::take_tool_shape() {
  // A mesh tool is drawn as its surface (its contact spheres sample it); read again here, as
  // the builder read it (relative to the project), in the tool's frame in world units.
  if (!shaped_tool_ || shaped_tool_->config().shape != procedures::ToolShape::kMesh) return;
  const std::filesystem::path mesh = shaped_tool_->config().mesh;
  auto surface = procedures::read_tool_mesh(mesh.is_relative() ? file_.parent_path() / mesh : mesh);
  if (!surface) return;  // the builder read it: only a file changed since could fail; drawn as spheres
  for (Vec3& v : surface->vertices) v /= shaped_tool_->metres_per_unit();
  const haptics::SurfaceSnapshot s = haptics::make_snapshot(*surface);  // for its vertex normals
  tool_mesh_.emplace();
  tool_mesh_->set_triangles(s.triangles);
  tool_mesh_->set_positions(s.vertices);
  tool_mesh_->set_normals(s.vertex_normals);
}

void GuiWindow::take_world_shapes(const std::vector<scene::VisualShape>& visuals) {
  visuals_.clear();
  for (const scene::VisualShape& shape : visuals) {
    VisualView v;
    const haptics::SurfaceSnapshot s = haptics::make_snapshot(shape.mesh);  // for its vertex normals
    v.mesh.set_triangles(s.triangles);
    v.mesh.set_positions(s.vertices);
    v.mesh.set_normals(s.vertex_normals);
    const Vec3& c = shape.appearance.diffuse_color;
    v.material.diffuse = render::Rgba(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()),
                                      static_cast<float>(1.0 - shape.appearance.transparency));
    visuals_.push_back(std::move(v));
  }
  layers_.clear();
  layers_.resize(session_->layer_count());
  bounds_min_ = Vec3::Constant(std::numeric_limits<double>::infinity());
  bounds_max_ = -bounds_min_;
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    auto& buffer = session_->graphics_surfaces(l);
    buffer.acquire();
    const haptics::SurfaceSnapshot& s = buffer.read();
    LayerView& view = layers_[l];
    view.parts = s.parts;
    view.rest = s.vertices;
    view.mesh.set_triangles(s.triangles);
    upload_layer(view, s);
    for (const Vec3& v : s.vertices) {
      bounds_min_ = bounds_min_.cwiseMin(v);
      bounds_max_ = bounds_max_.cwiseMax(v);
    }
  }
  for (const scene::VisualShape& shape : visuals) {
    for (const Vec3& v : shape.mesh.vertices) {
      bounds_min_ = bounds_min_.cwiseMin(v);
      bounds_max_ = bounds_max_.cwiseMax(v);
    }
  }
  if (!bounds_min_.allFinite()) {  // a world of force effects only
    bounds_min_ = Vec3::Constant(-0.05);
    bounds_max_ = Vec3::Constant(0.05);
  }
}

void GuiWindow::place_mouse_stylus_in_front() {
  // The mouse stylus starts in front of the scene, between it and the eye.
  if (!mouse_) return;
  double nearest = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? bounds_max_.x() : bounds_min_.x(), (c & 2) ? bounds_max_.y() : bounds_min_.y(),
                      (c & 4) ? bounds_max_.z() : bounds_min_.z());
    nearest = std::min(nearest, (corner - camera_.eye()).dot(camera_.forward()));
  }
  mouse_world_ = camera_.eye() + camera_.forward() * std::max(nearest - 0.05 * scene_size(), 0.1 * camera_.distance());
  plane_point_ = mouse_world_;
  mouse_depth_m_ = 0.0;
  mouse_->place((calibration_.position.inverse() * mouse_world_.homogeneous()).head<3>());
}

void GuiWindow::reset_camera() {
  // Up is the scene's: y in X3D; against gravity when it has gravity; else z (HoF's organs).
  const bool x3d = file_.extension() == ".x3d";
  Vec3 up = x3d ? Vec3::UnitY() : Vec3::UnitZ();
  for (const BodyView& b : bodies_) {
    if (x3d || !b.structure) continue;
    if (const Vec3 gravity = current_config(b).gravity_m_per_s2; gravity.norm() > 0.0) {
      up = -gravity.normalized();
      break;
    }
  }
  camera_.set_up(up);
  const scene::GraphicsSetup defaults;
  const Vec3 centre = 0.5 * (bounds_min_ + bounds_max_);
  const double radius = 0.5 * scene_size();
  const scene::GraphicsSetup& g = project_.graphics;
  const double distance = (g.viewpoint_m - g.look_at_m).norm();
  // The project's viewpoint, unless it is the format's default and does not frame this scene
  // (a scene in millimetres, or somewhere else).
  const bool is_default = g.viewpoint_m == defaults.viewpoint_m && g.look_at_m == defaults.look_at_m;
  const bool frames =
      (centre - g.look_at_m).norm() < 0.5 * distance && radius > 0.05 * distance && radius < 2.0 * distance;
  if (file_.extension() == ".hof" && (!is_default || frames)) {
    camera_.look(g.viewpoint_m, g.look_at_m);
  } else if (x3d && g.viewpoint_m != defaults.viewpoint_m) {
    // The scene's X3D Viewpoint, which looks along −z (its orientation is not applied).
    camera_.look(g.viewpoint_m, g.viewpoint_m - Vec3::UnitZ() * std::max((centre - g.viewpoint_m).norm(), 1e-3));
  } else {
    camera_.fit(bounds_min_, bounds_max_);
  }
}

void GuiWindow::set_animating(bool on) {
  animating_ = on;
  if (!session_) return;
  (void)session_->submit(on ? coupling::Command{coupling::command::Resume{}}
                            : coupling::Command{coupling::command::Pause{}});
}

void GuiWindow::reset_world() {
  if (!session_) return;
  if (!session_->realtime_running()) session_->start_realtime();
  (void)session_->submit(coupling::command::Reset{});
  if (!animating_) (void)session_->submit(coupling::command::Pause{});
}

Expected<void> GuiWindow::save(const std::filesystem::path& path) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (file_.extension() == ".x3d") {
    return make_error(ErrorCode::kUnsupported,
                      "an X3D scene cannot be saved as a project yet (the project format holds SOFA scenes)",
                      path.string());
  }
  scene::HofProject out = project_for(path);
  if (auto ok = scene::write_project(out, path); !ok) return ok;
  // As in any editor, the saved file is now the one open (Ctrl+S writes it again).
  project_ = std::move(out);
  file_ = path;
  dirty_ = false;
  remember_recent(path);
  report("saved " + path.string(), false);
  return {};
}

scene::HofProject GuiWindow::project_for(const std::filesystem::path& path) const {
  scene::HofProject out = scene::moved_project(project_, file_, path);
  if (session_) scene::record_parameters(out, scene::parameter_changes(*session_));  // as <set> elements
  // And those submitted but not applied yet (a save right after a change, the simulation busy).
  scene::record_parameters(out, submitted_changes_);
  return out;
}

Expected<void> GuiWindow::mount_needle(bool on) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (on == project_.needle.has_value()) return {};
  if (file_.extension() == ".x3d")
    return make_error(ErrorCode::kUnsupported, "the needle is mounted in a .hof project (save the scene as one)");
  scene::HofProject next = project_;
  if (on) {
    next.needle = procedures::NeedleConfig{};
    next.tool.reset();  // one tool on the stylus
  } else {
    next.needle.reset();
  }
  if (auto ok = reopen_with(std::move(next)); !ok) return ok;
  report(on ? "the needle is mounted: its tissue parameters are in the Needle panel" : "the needle is taken off",
         false);
  return {};
}

Expected<void> GuiWindow::reopen_with(scene::HofProject next) {
  // The parameters changed so far go with the reopened world.
  scene::record_parameters(next, scene::parameter_changes(*session_));
  scene::record_parameters(next, submitted_changes_);
  const render::OrbitCamera camera = camera_;
  const Eigen::Quaterniond turned = mouse_orientation_;
  const Vec3 stylus = mouse_world_;
  if (auto ok = open(file_, &next); !ok) return ok;
  // The user looks where they looked, the stylus stays where it was, turned as it was.
  camera_ = camera;
  if (mouse_) {
    mouse_world_ = plane_point_ = stylus;
    mouse_->place((calibration_.position.inverse() * mouse_world_.homogeneous()).head<3>());
    set_mouse_orientation(turned);
  }
  dirty_ = true;
  return {};
}

}  // namespace hof::app::gui
