// The window: GLFW + Dear ImGui 1.86 + OpenGL 3.3 (libepoxy). Threads: this one (the window)
// draws and reads; the session's haptic thread renders forces at 1 kHz; its simulation thread
// steps the bodies. What crosses: snapshots (triple buffers), telemetry (an SPSC ring), and
// commands (the session's seam). Nothing here waits on the haptic loop.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <charconv>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "hof/app/gui/gui_app.h"
#include "hof/app/gui/gui_script.h"
#include "hof/core/cpu_affinity.h"
#include "hof/core/file_write.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/mouse_device.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/haptics/device_backends/replay_device.h"
#include "hof/mechanics/model_parameters.h"
#include "hof/mechanics/von_mises_stress.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/surface_strain.h"
#include "hof/mesh/tet_geometry.h"
#include "hof/procedures/needle.h"
#include "hof/render/camera.h"
#include "hof/render/colormap.h"
#include "hof/render/gl_renderer.h"
#include "hof/render/image.h"
#include "hof/scene/project.h"
#include "hof/scene/sofa_scene_edit.h"
#include "hof/scene/world.h"

namespace hof::app {

namespace {

using Clock = std::chrono::steady_clock;
constexpr float kPanelWidth = 390.0f;
constexpr double kPlotSeconds = 5.0;
constexpr double kPlotRateHz = 100.0;
constexpr std::size_t kPlotPoints = static_cast<std::size_t>(kPlotSeconds * kPlotRateHz);
constexpr double kMaxFrameRateHz = 60.0;  // the window leaves the cores to the loops

double seconds_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

render::RenderMode render_mode_of(const std::string& mode) {
  if (mode == "wireframe") return render::RenderMode::kWireframe;
  if (mode == "points") return render::RenderMode::kPoints;
  if (mode == "shaded+wireframe") return render::RenderMode::kShadedWireframe;
  return render::RenderMode::kShaded;
}

std::string number_text(double v) { return fmt::format("{}", v); }

/// The twelve edges of the box [lo, hi] as line-segment end points, appended to `lines`.
void add_box_edges(std::vector<Vec3>& lines, const Vec3& lo, const Vec3& hi) {
  for (int a = 0; a < 3; ++a) {
    for (int c = 0; c < 4; ++c) {
      Vec3 p = lo;
      const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
      p[b1] = (c & 1) ? hi[b1] : lo[b1];
      p[b2] = (c & 2) ? hi[b2] : lo[b2];
      Vec3 q = p;
      q[a] = hi[a];
      lines.push_back(p);
      lines.push_back(q);
    }
  }
}

/// A snapshot layer as the window draws it.
struct LayerView {
  render::MeshBuffer mesh;
  std::vector<haptics::SurfacePart> parts;
  std::vector<Vec3> rest;
  std::vector<render::Rgba> colours;
  const haptics::SurfaceSnapshot* latest{nullptr};  // valid until the next acquire (this thread)
  double max_displacement_m{0.0};
  double max_strain{0.0};
  std::vector<double> strain;  // per vertex (colorBy strain)
  std::vector<double> stress;  // per vertex, Pa (colorBy stress; from the bodies' node stress)
  double max_stress_pa{0.0};
  std::vector<double> ranked;  // scratch for its percentile
};

/// A shape only seen (no haptic surface).
struct VisualView {
  render::MeshBuffer mesh;
  render::Material material;
};

struct BodyView {
  std::string name;
  std::optional<render::Material> material;  // the file's (an X3D Material), else the project's
  bool deformable{false};
  int layer{0};
  std::optional<mechanics::ModelConfig> config;  // as the accepted commands leave it
  std::vector<std::string> parameters;           // "component/parameter"
  std::vector<Vec3> fixed_points;
  std::shared_ptr<mechanics::VonMisesStress> stress;  // made on first use (colorBy stress)
  std::vector<double> node_stress;                    // Pa, scratch

  /// What the panels show of `c` (the model as the accepted commands leave it).
  void set_config(const mechanics::ModelConfig& c) {
    config = c;
    parameters = mechanics::parameter_names(c);
    fixed_points.clear();
    for (const auto& f : c.fixed) {
      for (const std::int32_t i : f.indices) {
        if (i >= 0 && static_cast<std::size_t>(i) < c.positions.size()) fixed_points.push_back(c.positions[static_cast<std::size_t>(i)]);
      }
    }
    stress.reset();
  }
};

/// Live figures over the last second (or the last samples).
struct LiveStats {
  std::deque<Clock::time_point> frames;
  std::deque<std::pair<Clock::time_point, std::uint64_t>> sim_sequences;
  std::deque<std::pair<Clock::time_point, std::uint64_t>> haptic_ticks;
  std::vector<double> periods;  // ring
  std::size_t period_next{0};
  std::uint64_t samples{0}, clamped{0}, invalid{0}, non_finite{0};
  double fps{0.0}, steps_per_s{0.0}, haptic_hz{0.0}, period_p50_ms{0.0}, period_p99_ms{0.0};
  // Over the whole run, not the last samples: one 20 ms stall is what a user feels, and a
  // percentile of the last 4,000 ticks forgets it within seconds.
  double longest_period_ms{0.0};
  std::uint64_t periods_over_2ms{0};
  Clock::time_point last_percentiles{};

  void add_period(double s) {
    longest_period_ms = std::max(longest_period_ms, 1e3 * s);
    if (s > 2e-3) ++periods_over_2ms;
    if (periods.size() < 4000) {
      periods.push_back(s);
    } else {
      periods[period_next] = s;
      period_next = (period_next + 1) % periods.size();
    }
  }
  void update(Clock::time_point now) {
    while (!frames.empty() && seconds_between(frames.front(), now) > 1.0) frames.pop_front();
    fps = static_cast<double>(frames.size()) / std::clamp(frames.empty() ? 1.0 : seconds_between(frames.front(), now), 0.25, 1.0);
    const auto rate = [&](auto& q) {
      while (q.size() > 2 && seconds_between(q.front().first, now) > 1.0) q.pop_front();
      if (q.size() < 2) return 0.0;
      const double span = seconds_between(q.front().first, q.back().first);
      return span > 0.0 ? static_cast<double>(q.back().second - q.front().second) / span : 0.0;
    };
    steps_per_s = rate(sim_sequences);
    haptic_hz = rate(haptic_ticks);
    if (seconds_between(last_percentiles, now) > 0.5 && !periods.empty()) {
      std::vector<double> sorted = periods;
      std::sort(sorted.begin(), sorted.end());
      period_p50_ms = 1e3 * sorted[sorted.size() / 2];
      period_p99_ms = 1e3 * sorted[std::min(sorted.size() - 1, sorted.size() * 99 / 100)];
      last_percentiles = now;
    }
  }
};

/// A minimal file chooser (ImGui has none): a folder listing and a name field.
struct FileDialog {
  bool open{false};
  bool saving{false};
  std::string title;
  std::vector<std::string> extensions;
  std::filesystem::path folder{std::filesystem::current_path()};
  std::array<char, 512> name{};
  std::function<void(const std::filesystem::path&)> on_choose;

  void show(const std::string& t, bool save, std::vector<std::string> exts, std::function<void(const std::filesystem::path&)> f,
            const std::string& suggested = {}) {
    open = true;
    saving = save;
    title = t;
    extensions = std::move(exts);
    on_choose = std::move(f);
    name.fill('\0');
    std::copy_n(suggested.begin(), std::min(suggested.size(), name.size() - 1), name.begin());
    ImGui::OpenPopup("##file");
  }

  void draw() {
    if (!open) return;
    ImGui::SetNextWindowSize(ImVec2(560, 420), ImGuiCond_Appearing);
    if (!ImGui::BeginPopupModal("##file", &open)) return;
    ImGui::TextUnformatted(title.c_str());
    ImGui::TextDisabled("%s", folder.string().c_str());
    ImGui::BeginChild("entries", ImVec2(0, -60), true);
    if (ImGui::Selectable("..")) folder = folder.parent_path();
    std::error_code ec;
    std::vector<std::filesystem::directory_entry> entries;
    for (const auto& e : std::filesystem::directory_iterator(folder, ec)) entries.push_back(e);
    std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.path().filename() < b.path().filename(); });
    for (const auto& e : entries) {
      const std::string file = e.path().filename().string();
      if (file.starts_with('.')) continue;
      if (e.is_directory(ec)) {
        if (ImGui::Selectable((file + "/").c_str())) folder = e.path();
      } else if (std::find(extensions.begin(), extensions.end(), e.path().extension().string()) != extensions.end()) {
        if (ImGui::Selectable(file.c_str())) {
          name.fill('\0');
          std::copy_n(file.begin(), std::min(file.size(), name.size() - 1), name.begin());
        }
      }
    }
    ImGui::EndChild();
    ImGui::InputText("file", name.data(), name.size());
    if (ImGui::Button(saving ? "Save" : "Open") && name[0] != '\0') {
      const std::filesystem::path chosen = folder / std::string(name.data());
      open = false;
      ImGui::CloseCurrentPopup();
      if (on_choose) on_choose(chosen);
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) {
      open = false;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
};

std::filesystem::path recent_files_path() {
  const char* config = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  if (config && *config) return std::filesystem::path(config) / "hof" / "recent-files";
  if (home && *home) return std::filesystem::path(home) / ".config" / "hof" / "recent-files";
  return {};
}

/// A stylus trajectory being recorded (the replay format, device frame) and the settings
/// changed meanwhile.
struct Recording {
  std::filesystem::path file;
  std::vector<haptics::ReplaySample> samples;
  std::vector<std::string> events;  // "t: what"
  double start_s{-1.0};             // haptic time of the first sample
  Eigen::Matrix4d world_to_device{Eigen::Matrix4d::Identity()};
  std::optional<scene::HofProject> project;  // the settings when it began (SOFA-based worlds)
  [[nodiscard]] double seconds() const { return samples.empty() ? 0.0 : samples.back().t_s; }
};

class Gui {
 public:
  explicit Gui(const GuiOptions& options) : options_(options) {}
  ~Gui() { shut_down(); }
  Gui(const Gui&) = delete;
  Gui& operator=(const Gui&) = delete;

  Expected<void> create_window();
  /// Opens `file` (or, given, the project in memory that lives at `file`).
  Expected<void> open(const std::filesystem::path& file, const scene::HofProject* in_memory = nullptr);
  int run(std::vector<ScriptAction> script, const std::string& script_name);

 private:
  // World.
  void close_session();
  void update_from_loops();
  void upload_layer(LayerView& layer, const haptics::SurfaceSnapshot& s);
  Expected<void> apply_set(const std::string& element, const std::string& attribute, const std::string& value);
  /// A structural change (the scene made inline in the project and edited; and/or the material
  /// regions replaced): the world's models are rebuilt from it and swapped in through the seam.
  Expected<void> change_structure(const std::optional<scene::SceneEdit>& edit,
                                  const std::optional<std::vector<scene::MaterialRegion>>& regions);
  /// A component's switch to another type, with the values that carry over (E, ν, masses).
  Expected<void> switch_component(const BodyView& body, const std::string& component, const std::string& choice);
  void update_stress();
  Expected<void> save(const std::filesystem::path& path);
  /// The project as it would be saved at `path` (scene re-anchored, parameters as <set>).
  scene::HofProject project_for(const std::filesystem::path& path) const;
  Expected<void> start_recording(const std::filesystem::path& file);
  Expected<void> stop_recording();
  Expected<void> export_shape(const std::filesystem::path& path);
  void set_animating(bool on);
  void report(const std::string& message, bool error);
  // Stylus from the mouse.
  std::optional<Vec3> pick(double x_px, double y_px) const;
  void mouse_to(double window_x, double window_y, double depth_m, bool new_plane);
  void set_mouse_target(const Vec3& world);
  // Drawing.
  void frame();
  void draw_scene(int width, int height);
  void draw_panels();
  void draw_legend();
  void draw_mechanics_panel();
  void draw_structure_editor(BodyView& body);
  void draw_haptics_panel();
  void draw_effects_editor();
  void draw_needle_editor();
  void draw_needle(double size);
  /// Mounts (or takes off) the needle: the world is opened again from the project in memory.
  Expected<void> mount_needle(bool on);
  void draw_graphics_panel();
  void handle_input();
  void reset_camera();
  /// The limit the safety filter holds: the device's, or the project's when lower.
  [[nodiscard]] double force_limit_n() const {
    return project_.safety.max_force_n > 0.0 ? std::min(max_force_n_, project_.safety.max_force_n) : max_force_n_;
  }
  [[nodiscard]] double scene_size() const { return std::max((bounds_max_ - bounds_min_).norm(), 1e-6); }
  // Script.
  bool step_script(std::vector<ScriptAction>& script, std::size_t& next, const std::string& name, int& status);
  void remember_recent(const std::filesystem::path& file);
  void shut_down();

  GuiOptions options_;
  GLFWwindow* window_{nullptr};
  bool imgui_ready_{false};
  std::unique_ptr<render::GlRenderer> renderer_;  // made once the context exists
  render::OrbitCamera camera_;
  int view_x_{0}, view_w_{1}, view_h_{1};

  // The world on screen.
  std::filesystem::path file_;
  scene::HofProject project_;  // what a save writes (the file's, with the changes made here)
  std::string world_name_, length_unit_{"m"}, device_spec_;
  bool default_probe_{false};
  std::unique_ptr<coupling::Session> session_;
  haptics::MouseDevice* mouse_{nullptr};
  std::shared_ptr<procedures::NeedleTool> needle_;  // the needle stylus, when the project mounts one
  procedures::NeedlePhase needle_phase_{procedures::NeedlePhase::kFree};  // at the last tick
  haptics::Calibration calibration_;
  double max_force_n_{8.0};
  double workspace_radius_m_{0.08};
  std::vector<LayerView> layers_;
  std::vector<BodyView> bodies_;
  std::vector<VisualView> visuals_;
  Vec3 bounds_min_{Vec3::Constant(-0.1)}, bounds_max_{Vec3::Constant(0.1)};
  bool animating_{true};
  bool dirty_{false};
  bool realtime_pacing_{true};

  // Telemetry.
  haptics::HapticSample last_{};
  LiveStats stats_;
  std::vector<float> plot_force_ = std::vector<float>(kPlotPoints, 0.0f);  // the last kPlotSeconds, oldest first
  std::vector<float> plot_indentation_ = std::vector<float>(kPlotPoints, 0.0f);
  double next_plot_time_{0.0};
  bool was_in_contact_{false};
  double displaced_at_contact_{0.0};
  double indentation_m_{0.0};
  double max_force_seen_n_{0.0};
  bool reading_{false};  // the device's latest tick had a reading
  double max_displacement_seen_m_{0.0};
  std::uint64_t contact_ticks_{0};
  std::int32_t contact_body_{-1};

  // Mouse stylus.
  Vec3 plane_point_{Vec3::Zero()};
  Vec3 mouse_world_{Vec3::Zero()};
  double mouse_depth_m_{0.0};
  bool dragging_stylus_{false};
  double last_x_{0.0}, last_y_{0.0};

  // View options (not saved: debugging aids).
  bool show_bound_tree_{false};
  int bound_tree_depth_{4};
  bool show_contact_triangle_{true};
  bool show_fixed_nodes_{false};
  bool show_device_{true};
  bool show_regions_{true};
  std::set<std::string> warned_;  // warnings already shown for this world
  // Parameter changes submitted since the last structural change (some may still be queued).
  std::vector<coupling::ParameterChange> submitted_changes_;
  // A calibration change on its way to the haptic loop: the mouse keeps the old mapping until
  // the session has applied as many as were submitted.
  std::uint64_t calibrations_submitted_{0};
  bool calibration_pending_{false};
  haptics::Calibration pending_calibration_;
  /// The calibration the haptic loop reads the mouse stylus through right now.
  [[nodiscard]] const haptics::Calibration& mouse_calibration() const { return calibration_pending_ ? pending_calibration_ : calibration_; }
  Clock::time_point next_stress_{};
  // Structure editor inputs.
  float region_radius_m_{0.0f};  // 0: a tenth of the scene
  float region_factor_{4.0f};    // × the force field's modulus
  float pin_radius_m_{0.0f};     // 0: a twentieth of the scene
  float arrow_m_per_n_{0.0f};  // 0: automatic (an 8 N force as long as a third of the scene)

  // Messages and dialogs.
  std::string error_;
  std::deque<std::string> log_;
  FileDialog dialog_;
  bool want_open_dialog_{false}, want_save_dialog_{false}, want_export_dialog_{false}, want_screenshot_dialog_{false};
  bool confirm_quit_{false};
  bool quit_{false};
  std::optional<std::filesystem::path> pending_screenshot_;
  std::vector<std::filesystem::path> recent_;
  std::optional<std::filesystem::path> dropped_;
  std::optional<std::filesystem::path> pending_open_;
  std::optional<Recording> recording_;
  bool want_replay_dialog_{false};  // waits for the user's answer about unsaved changes
  Clock::time_point script_wait_until_{};
  bool script_waiting_{false};
  std::optional<std::string> open_panel_;  // a panel a script opened (taken by the next frame)
};

// ---------------------------------------------------------------------------------------------
// Window

Expected<void> Gui::create_window() {
  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "hof gui: GLFW error %d: %s\n", code, text); });
  if (!glfwInit()) {
    return make_error(ErrorCode::kUnsupported, "no display: the window needs X11 (run `hof run --headless`, or under xvfb-run)");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(options_.width, options_.height, "HoF", nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    return make_error(ErrorCode::kUnsupported, "cannot open an OpenGL 3.3 window on this display");
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(1);
  glfwSetWindowUserPointer(window_, this);
  glfwSetDropCallback(window_, [](GLFWwindow* w, int count, const char** paths) {
    if (count > 0) static_cast<Gui*>(glfwGetWindowUserPointer(w))->dropped_ = std::filesystem::path(paths[0]);
  });
  glfwSetWindowCloseCallback(window_, [](GLFWwindow* w) {
    auto* gui = static_cast<Gui*>(glfwGetWindowUserPointer(w));
    if (gui->dirty_) {
      glfwSetWindowShouldClose(w, GLFW_FALSE);  // ask first: unsaved changes are never lost silently
      gui->confirm_quit_ = true;
    }
  });
  renderer_ = std::make_unique<render::GlRenderer>();
  if (auto ok = renderer_->init(); !ok) return ok;
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // the layout is fixed; nothing written behind the user's back
  ImGui::StyleColorsDark();
  ImGui::GetStyle().WindowRounding = 0.0f;
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;
  // Recent files.
  if (const auto path = recent_files_path(); !path.empty()) {
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) {
      if (!line.empty()) recent_.emplace_back(line);
    }
  }
  return {};
}

void Gui::shut_down() {
  close_session();
  layers_.clear();
  if (imgui_ready_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    imgui_ready_ = false;
  }
  if (window_) {
    renderer_.reset();  // GL objects go while the context exists
    glfwDestroyWindow(window_);
    glfwTerminate();
    window_ = nullptr;
  }
}

void Gui::report(const std::string& message, bool error) {
  if (error) error_ = message;
  log_.push_back(message);
  while (log_.size() > 50) log_.pop_front();
  if (!options_.quiet || error) std::fprintf(stderr, "hof gui: %s%s\n", error ? "error: " : "", message.c_str());
}

void Gui::remember_recent(const std::filesystem::path& file) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(file, ec);
  std::erase(recent_, absolute);
  recent_.insert(recent_.begin(), absolute);
  if (recent_.size() > 8) recent_.resize(8);
  const auto path = recent_files_path();
  if (path.empty()) return;
  std::filesystem::create_directories(path.parent_path(), ec);
  std::string text;
  for (const auto& r : recent_) text += r.string() + '\n';
  (void)write_file_atomically(path, text);  // a convenience list: a failure costs nothing
}

// ---------------------------------------------------------------------------------------------
// World

void Gui::close_session() {
  if (recording_) {
    if (auto ok = stop_recording(); !ok) report(ok.error().to_string(), true);
  }
  if (session_) {
    session_->stop_realtime();
    session_.reset();
  }
  needle_.reset();
  mouse_ = nullptr;
}

Expected<void> Gui::open(const std::filesystem::path& file, const scene::HofProject* in_memory) {
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
      return make_error(ErrorCode::kUnsupported, "expected a .hof project, a .scn SOFA scene or an .x3d scene", file.string());
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
  auto device = haptics::open_device(spec);
  if (!device && spec != "mouse") {
    report(fmt::format("device '{}' does not answer ({}): the mouse holds the stylus", spec, device.error().to_string()), true);
    spec = "mouse";
    device = haptics::open_device(spec);
  }
  if (!device) return std::unexpected(device.error());
  auto* mouse = dynamic_cast<haptics::MouseDevice*>(device->get());
  const double max_force = (*device)->spec().max_force_n;
  const double workspace = (*device)->spec().workspace_radius_m;
  std::vector<BodyView> bodies;
  for (const coupling::SessionBody& b : world->bodies) {
    BodyView v;
    v.name = b.name;
    v.deformable = b.deformable();
    v.layer = b.layer;
    if (b.config) v.set_config(*b.config);
    if (const auto a = world->appearances.find(b.name); a != world->appearances.end()) {
      render::Material m;
      m.diffuse = render::Rgba(static_cast<float>(a->second.diffuse_color.x()), static_cast<float>(a->second.diffuse_color.y()),
                               static_cast<float>(a->second.diffuse_color.z()), static_cast<float>(1.0 - a->second.transparency));
      v.material = m;
    }
    bodies.push_back(std::move(v));
  }
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = true;
  config.simulation_threads = options_.simulation_threads;
  config.pin_threads = options_.pin_threads;
  // The builder fitted the probe's workspace to the world. The mouse reaches anywhere, so a
  // world in metres keeps the file's own calibration (a recording then replays with
  // `hof run FILE --device replay:REC.csv` just as it was made); a SOFA scene, which has no
  // unit, keeps the fit: it gives the world its scale.
  if (spec == "mouse" && world->default_probe && world->length_unit == "m") {
    for (int i = 0; i < 16; ++i) config.haptics.calibration.position(i / 4, i % 4) = world->file_calibration[static_cast<std::size_t>(i)];
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
  visuals_.clear();
  for (const scene::VisualShape& shape : world->visuals) {
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
  dirty_ = false;
  error_.clear();
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
  for (const scene::VisualShape& shape : world->visuals) {
    for (const Vec3& v : shape.mesh.vertices) {
      bounds_min_ = bounds_min_.cwiseMin(v);
      bounds_max_ = bounds_max_.cwiseMax(v);
    }
  }
  if (!bounds_min_.allFinite()) {  // a world of force effects only
    bounds_min_ = Vec3::Constant(-0.05);
    bounds_max_ = Vec3::Constant(0.05);
  }
  plot_force_.assign(kPlotPoints, 0.0f);
  plot_indentation_.assign(kPlotPoints, 0.0f);
  next_plot_time_ = 0.0;
  stats_ = LiveStats{};
  max_force_seen_n_ = max_displacement_seen_m_ = 0.0;
  contact_ticks_ = 0;
  last_ = haptics::HapticSample{};
  was_in_contact_ = false;
  reset_camera();
  // The mouse stylus starts in front of the scene, between it and the eye.
  if (mouse_) {
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
  session_->set_realtime_pacing(realtime_pacing_);
  session_->start_realtime();
  if (!animating_) (void)session_->submit(coupling::command::Pause{});
  remember_recent(file);
  report(fmt::format("opened {} ({} bod{}, device {})", file.string(), bodies_.size(), bodies_.size() == 1 ? "y" : "ies", spec), false);
  return {};
}

void Gui::reset_camera() {
  // Up is the scene's: y in X3D; against gravity when it has gravity; else z (HoF's organs).
  const bool x3d = file_.extension() == ".x3d";
  Vec3 up = x3d ? Vec3::UnitY() : Vec3::UnitZ();
  for (const BodyView& b : bodies_) {
    if (!x3d && b.config && b.config->gravity_m_per_s2.norm() > 0.0) {
      up = -b.config->gravity_m_per_s2.normalized();
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
  const bool frames = (centre - g.look_at_m).norm() < 0.5 * distance && radius > 0.05 * distance && radius < 2.0 * distance;
  if (file_.extension() == ".hof" && (!is_default || frames)) {
    camera_.look(g.viewpoint_m, g.look_at_m);
  } else if (x3d && g.viewpoint_m != defaults.viewpoint_m) {
    // The scene's X3D Viewpoint, which looks along −z (its orientation is not applied).
    camera_.look(g.viewpoint_m, g.viewpoint_m - Vec3::UnitZ() * std::max((centre - g.viewpoint_m).norm(), 1e-3));
  } else {
    camera_.fit(bounds_min_, bounds_max_);
  }
}

void Gui::upload_layer(LayerView& layer, const haptics::SurfaceSnapshot& s) {
  layer.latest = &s;
  layer.mesh.set_positions(s.vertices);
  layer.mesh.set_normals(s.vertex_normals);
  layer.max_displacement_m = 0.0;
  if (layer.rest.size() == s.vertices.size()) {
    for (std::size_t i = 0; i < s.vertices.size(); ++i) layer.max_displacement_m = std::max(layer.max_displacement_m, (s.vertices[i] - layer.rest[i]).norm());
  }
  const std::string& by = project_.graphics.color_by;
  if ((by != "displacement" && by != "strain" && by != "stress") || layer.rest.size() != s.vertices.size() ||
      (by == "stress" && layer.stress.size() != s.vertices.size())) {
    if (layer.mesh.has_colours()) layer.mesh.set_colours({});
    return;
  }
  // A scale that grows with the field and has a floor (1 % of the scene; 1 % strain), so that a
  // still body does not flicker through the colour map.
  layer.colours.resize(s.vertices.size());
  if (by == "strain") {
    mesh::vertex_strain_magnitude(layer.rest, s.vertices, s.triangles, layer.strain);
    // The scale: the 98th percentile, not the maximum — a point load strains the triangles
    // under it far more than the rest, which would leave the whole body one colour.
    layer.ranked = layer.strain;
    const auto at = layer.ranked.begin() + static_cast<std::ptrdiff_t>(0.98 * static_cast<double>(layer.ranked.size() - 1));
    std::nth_element(layer.ranked.begin(), at, layer.ranked.end());
    layer.max_strain = layer.ranked.empty() ? 0.0 : *at;
  }
  const double range = by == "strain"   ? std::max(layer.max_strain, 0.01)
                       : by == "stress" ? std::max(layer.max_stress_pa, 1e-6)
                                        : std::max(layer.max_displacement_m, 0.01 * scene_size());
  for (std::size_t i = 0; i < s.vertices.size(); ++i) {
    const double value = by == "strain" ? layer.strain[i] : by == "stress" ? layer.stress[i] : (s.vertices[i] - layer.rest[i]).norm();
    const Eigen::Vector3f c = render::viridis(static_cast<float>(value / range));
    layer.colours[i] = render::Rgba(c.x(), c.y(), c.z(), 1.0f);
  }
  layer.mesh.set_colours(layer.colours);
}

void Gui::update_stress() {
  // Von Mises stress from the bodies' node positions, on this thread, ten times a second.
  if (project_.graphics.color_by != "stress" || !session_) return;
  auto& states = session_->graphics_states();
  const auto now = Clock::now();
  if (now < next_stress_) return;
  if (!states.acquire() && !layers_.empty() && !layers_[0].stress.empty()) return;
  next_stress_ = now + std::chrono::milliseconds(100);
  const std::vector<std::vector<double>>& x = states.read();
  for (LayerView& layer : layers_) layer.stress.assign(layer.rest.size(), 0.0);
  std::vector<double> node_values;
  std::vector<Vec3> surface;
  for (std::size_t i = 0; i < bodies_.size() && i < x.size(); ++i) {
    BodyView& b = bodies_[i];
    if (!b.config || x[i].size() != 3 * b.config->positions.size()) continue;
    if (!b.stress) b.stress = std::make_shared<mechanics::VonMisesStress>(*b.config);
    if (!b.stress->available()) continue;
    b.stress->node_stress(x[i], b.node_stress);
    // Node values to the surface through the body's own mapping (a scalar in x).
    node_values.assign(3 * b.node_stress.size(), 0.0);
    for (std::size_t n = 0; n < b.node_stress.size(); ++n) node_values[3 * n] = b.node_stress[n];
    const coupling::SurfaceMapping& mapping = session_->body(i).mapping;
    surface.resize(mapping.surface_vertex_count());
    mapping.apply(node_values, surface);
    if (static_cast<std::size_t>(b.layer) >= layers_.size()) continue;
    LayerView& layer = layers_[static_cast<std::size_t>(b.layer)];
    for (const haptics::SurfacePart& part : layer.parts) {
      if (part.body != static_cast<std::int32_t>(i) || static_cast<std::size_t>(part.vertex_count) != surface.size()) continue;
      for (std::size_t v = 0; v < surface.size(); ++v) layer.stress[static_cast<std::size_t>(part.first_vertex) + v] = std::max(surface[v].x(), 0.0);
    }
  }
  for (LayerView& layer : layers_) {
    // The scale: the 98th percentile, as for strain (the load point peaks far above the rest).
    layer.ranked = layer.stress;
    if (layer.ranked.empty()) continue;
    const auto at = layer.ranked.begin() + static_cast<std::ptrdiff_t>(0.98 * static_cast<double>(layer.ranked.size() - 1));
    std::nth_element(layer.ranked.begin(), at, layer.ranked.end());
    layer.max_stress_pa = *at;
    if (layer.latest) upload_layer(layer, *layer.latest);
  }
}

void Gui::update_from_loops() {
  if (!session_) return;
  const auto now = Clock::now();
  // Telemetry: every tick since the last frame.
  std::uint64_t last_tick = 0;
  bool any = false;
  session_->poll([&](const haptics::HapticSample& s) {
    any = true;
    last_tick = s.tick;
    ++stats_.samples;
    reading_ = s.valid;
    if (!s.valid) {
      ++stats_.invalid;
      return;
    }
    if (!s.force.allFinite() || !s.requested_force.allFinite()) ++stats_.non_finite;
    // At the device's force limit (a fade-in after a device switch lowers the force too, but
    // is not the limit).
    if (s.requested_force.norm() > s.force.norm() + 1e-9 && s.force.norm() >= 0.999 * force_limit_n()) ++stats_.clamped;
    if (s.period_s > 0.0) stats_.add_period(s.period_s);
    if (recording_) {
      Recording& r = *recording_;
      if (r.start_s < 0.0) r.start_s = s.time_s;
      const double t = s.time_s - r.start_s;
      if (r.samples.empty() || t > r.samples.back().t_s) {
        haptics::ReplaySample sample;
        sample.t_s = t;
        sample.position_m = (r.world_to_device * s.device.homogeneous()).head<3>();
        sample.buttons = s.buttons;
        r.samples.push_back(sample);
      }
    }
    max_force_seen_n_ = std::max(max_force_seen_n_, s.force.norm());
    if (s.contact) ++contact_ticks_;
    // Indentation: as `hof run` (telemetry.csv) counts it, from where the contact began.
    double indentation = 0.0;
    if (s.contact && s.triangle >= 0) {
      const double from_rest = (session_->rest_point(s.triangle, s.barycentric, s.layer) - s.contact_point).dot(s.contact_normal);
      if (!was_in_contact_) displaced_at_contact_ = from_rest;
      indentation = from_rest - displaced_at_contact_;
      contact_body_ = session_->body_of_triangle(s.triangle, s.layer);
    }
    was_in_contact_ = s.contact && s.triangle >= 0;
    indentation_m_ = indentation;
    if (needle_ && s.tool.active) {
      // The needle's events, in the messages (the thesis' field network as a log).
      const auto phase = static_cast<procedures::NeedlePhase>(s.tool.phase);
      const std::string body = s.tool.body >= 0 && static_cast<std::size_t>(s.tool.body) < bodies_.size()
                                   ? bodies_[static_cast<std::size_t>(s.tool.body)].name
                                   : std::string("the body");
      const double shown = 1e3;  // the needle's lengths are SI
      const char* unit = "mm";
      if (phase == procedures::NeedlePhase::kPunctured && needle_phase_ == procedures::NeedlePhase::kPrePuncture) {
        report(fmt::format("needle: the capsule of {} broke at {:.1f} {} ({:.3f} N after)", body, shown * s.tool.depth_m, unit,
                           s.tool.axial_force_n), false);
      } else if (phase == procedures::NeedlePhase::kTouching && needle_phase_ != procedures::NeedlePhase::kTouching) {
        report(fmt::format("needle: touching {}", body), false);
      } else if (phase == procedures::NeedlePhase::kOut && needle_phase_ != procedures::NeedlePhase::kOut) {
        report("needle: withdrawn", false);
      }
      needle_phase_ = phase;
      indentation = s.tool.depth_m;  // the second plot shows the depth
    }
    if (s.time_s >= next_plot_time_) {
      next_plot_time_ = s.time_s + 1.0 / kPlotRateHz;
      std::rotate(plot_force_.begin(), plot_force_.begin() + 1, plot_force_.end());
      std::rotate(plot_indentation_.begin(), plot_indentation_.begin() + 1, plot_indentation_.end());
      plot_force_.back() = static_cast<float>(s.force.norm());
      plot_indentation_.back() = static_cast<float>(1e3 * indentation);
    }
    last_ = s;
  });
  if (any) stats_.haptic_ticks.emplace_back(now, last_tick);
  // The latest shapes.
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    auto& buffer = session_->graphics_surfaces(l);
    if (buffer.acquire()) {
      upload_layer(layers_[l], buffer.read());
      max_displacement_seen_m_ = std::max(max_displacement_seen_m_, layers_[l].max_displacement_m);
    } else {
      layers_[l].latest = &buffer.read();
    }
  }
  update_stress();
  if (calibration_pending_ && session_->calibrations_applied() >= calibrations_submitted_) {
    calibration_pending_ = false;
    if (mouse_) mouse_->place((calibration_.position.inverse() * mouse_world_.homogeneous()).head<3>());
  }
  stats_.sim_sequences.emplace_back(now, session_->steps_taken());
  stats_.frames.push_back(now);
  stats_.update(now);
  if (session_->simulation_ended()) {
    const coupling::SessionReport r = session_->stop_realtime();
    report(fmt::format("the simulation stopped: {} — change a setting and press Reset", r.divergence.empty() ? "it ended" : r.divergence),
           true);
    // The haptic loop has stopped with it (zero force sent); Reset starts both again.
  }
}

void Gui::set_animating(bool on) {
  animating_ = on;
  if (!session_) return;
  (void)session_->submit(on ? coupling::Command{coupling::command::Resume{}} : coupling::Command{coupling::command::Pause{}});
}

Expected<void> Gui::apply_set(const std::string& element, const std::string& attribute, const std::string& value) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  const std::string name = element + "@" + attribute;
  // mechanics/BODY/COMPONENT@PARAMETER (or mechanics/BODY@PARAMETER for the model's own).
  if (element == "mechanics" || element.starts_with("mechanics/")) {
    const std::string rest = element.size() > 10 ? element.substr(10) : std::string();
    const std::size_t slash = rest.find('/');
    const std::string body = rest.substr(0, slash);
    const std::string component = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
    if (body.empty()) return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': name a body: mechanics/BODY/COMPONENT@PARAMETER", name));
    double v = 0.0;
    const auto parsed = std::from_chars(value.data(), value.data() + value.size(), v);
    if (parsed.ec != std::errc() || parsed.ptr != value.data() + value.size() || !std::isfinite(v)) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': '{}' is not a number", name, value));
    }
    if (auto ok = session_->submit(coupling::command::SetParameter{body, component, attribute, v}); !ok) {
      Error e = ok.error();
      e.message = fmt::format("'{}': {}", name, e.message);
      return std::unexpected(e);
    }
    for (BodyView& b : bodies_) {
      if (b.name == body && b.config) {
        (void)mechanics::set_parameter(*b.config, component, attribute, v);
        b.stress.reset();  // its moduli may have changed
      }
    }
    submitted_changes_.push_back(coupling::ParameterChange{body, component, attribute, v});
    if (recording_) recording_->events.push_back(fmt::format("{:.3f}: set {} {}", recording_->seconds(), name, value));
    dirty_ = true;
    return {};
  }
  scene::HofProject next = project_;
  if (auto ok = scene::set_project_attribute(next, file_, element, attribute, value); !ok) return ok;
  const coupling::SessionConfig config = scene::session_config(next);
  if (element == "haptics/calibration") {
    const haptics::Calibration calibration = config.haptics.calibration;
    if (!calibration_pending_) pending_calibration_ = calibration_;  // in force until the loop has the new one
    if (auto ok = session_->submit(coupling::command::SetCalibration{calibration}); !ok) return ok;
    calibration_ = calibration;
    // The mouse stylus stays where it is in the world: its device position follows once the
    // haptic loop has the new calibration (before that, a new device position read through the
    // old one would put the stylus elsewhere for a few ticks).
    calibrations_submitted_ += 1;
    calibration_pending_ = true;
  } else if (element == "haptics" && attribute == "device") {
    // Opened here so that the window keeps a handle on a mouse stylus.
    const std::string spec = next.device == "auto" ? std::string("mouse") : next.device;
    if (spec.starts_with("openhaptics")) {
      // Its servo loop must be the haptic loop's clock from the start.
      return make_error(ErrorCode::kUnsupported, fmt::format("'{}': an OpenHaptics device drives the haptic loop from its own servo "
                                                             "loop: open the window with it (hof gui FILE --device {})",
                                                             name, spec));
    }
    auto opened = haptics::open_device(spec);
    if (!opened) return std::unexpected(opened.error());
    std::shared_ptr<haptics::Device> device(std::move(*opened));
    if (auto ok = session_->submit(coupling::command::SetDevice{spec, device}); !ok) return ok;
    mouse_ = dynamic_cast<haptics::MouseDevice*>(device.get());  // the session keeps the device alive
    if (mouse_) mouse_->place((mouse_calibration().position.inverse() * mouse_world_.homogeneous()).head<3>());
    device_spec_ = spec;
    max_force_n_ = device->spec().max_force_n;
    workspace_radius_m_ = device->spec().workspace_radius_m;
  } else if (element.starts_with("haptics/needle")) {
    // Taken by the needle's next tick: it keeps its place and phase.
    if (!needle_ || !next.needle) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("'{}': no needle is mounted (script: needle on)", name));
    }
    if (auto ok = needle_->configure(*next.needle); !ok) return ok;
  } else {
    std::vector<std::string> names;
    for (const BodyView& b : bodies_) names.push_back(b.name);
    const auto commands = scene::live_commands(next, element, attribute, names);
    if (!commands) report(fmt::format("'{}' is saved; it takes effect when the project is reopened", name), false);
    for (const coupling::Command& c : commands.value_or(std::vector<coupling::Command>{})) {
      if (auto ok = session_->submit(c); !ok) return ok;
    }
  }
  project_ = std::move(next);
  if (recording_) recording_->events.push_back(fmt::format("{:.3f}: set {} {}", recording_->seconds(), name, value));
  dirty_ = true;
  return {};
}

Expected<void> Gui::change_structure(const std::optional<scene::SceneEdit>& edit,
                                     const std::optional<std::vector<scene::MaterialRegion>>& regions) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (file_.extension() == ".x3d") {
    return make_error(ErrorCode::kUnsupported, "the scene tree edits SOFA scenes; an X3D scene's bodies are edited in its file", file_.string());
  }
  scene::HofProject next = project_;
  // The values changed so far go with the new models (the seam forgets them at the switch),
  // those still queued too.
  scene::record_parameters(next, session_->parameter_changes());
  scene::record_parameters(next, submitted_changes_);
  if (next.mechanics_inline.empty()) {
    // From now on the project holds its scene (the file it came from is left as it was).
    auto text = scene::inline_scene(scene::scene_file(project_, file_), file_.parent_path());
    if (!text) return std::unexpected(text.error());
    next.mechanics_inline = std::move(*text);
    next.mechanics_scene.clear();
  }
  if (edit) {
    auto text = scene::edit_scene(next.mechanics_inline, *edit);
    if (!text) return std::unexpected(text.error());
    next.mechanics_inline = std::move(*text);
    if (edit->action != scene::SceneEdit::Action::kAdd) {
      std::erase_if(next.parameters, [&](const coupling::ParameterChange& c) { return c.body == edit->node && c.component == edit->component; });
    }
  }
  if (regions) next.regions = *regions;
  auto world = scene::build_world(next, file_, "mouse");
  if (!world) {
    Error e = world.error();
    e.message = "the change is not made: " + e.message;
    return std::unexpected(e);
  }
  for (const coupling::SessionBody& b : world->bodies) {
    if (!b.config) continue;
    if (auto ok = session_->submit(coupling::command::SetModel{b.name, *b.config, nullptr}); !ok) {
      Error e = ok.error();
      e.message = "the change is not made: " + e.message;
      return std::unexpected(e);
    }
  }
  for (const coupling::SessionBody& b : world->bodies) {
    for (BodyView& v : bodies_) {
      if (v.name == b.name && b.config) v.set_config(*b.config);
    }
  }
  for (const std::string& w : world->warnings) {
    if (warned_.insert(w).second) report("warning: " + w, false);  // each once, not with every edit
  }
  if (edit) {
    const char* verb = edit->action == scene::SceneEdit::Action::kReplace ? "is now" : edit->action == scene::SceneEdit::Action::kAdd ? "added:" : "removed";
    report(fmt::format("{}/{} {} {}", edit->node, edit->component, verb, edit->type), false);
  }
  if (recording_) {
    recording_->events.push_back(fmt::format("{:.3f}: {}", recording_->seconds(),
                                             edit ? fmt::format("scene edit {}/{}", edit->node, edit->component) : std::string("material regions")));
  }
  project_ = std::move(next);
  submitted_changes_.clear();
  dirty_ = true;
  return {};
}

namespace {

/// The types a component of each role can be switched to (the window's scene tree).
const std::vector<std::string> kOdeSolvers{"EulerImplicitSolver", "EulerExplicitSolver", "RungeKutta4Solver", "StaticSolver"};
const std::vector<std::string> kLinearSolvers{"CGLinearSolver", "SparseLDLSolver"};
const std::vector<std::string> kMasses{"DiagonalMass", "UniformMass"};
const std::vector<std::string> kForceFields{"TetrahedronFEMForceField large", "TetrahedronFEMForceField small",
                                            "TetrahedronFEMForceField polar", "NeoHookean (TetrahedronHyperelasticityFEMForceField)",
                                            "MeshSpringForceField"};

/// E and ν of a model's first FEM force field (SOFA's defaults otherwise).
std::pair<double, double> elastic_moduli(const mechanics::ModelConfig& c) {
  for (const mechanics::ForceFieldConfig& f : c.force_fields) {
    if (f.tetrahedron_fem) return {f.tetrahedron_fem->young_modulus_pa, f.tetrahedron_fem->poisson_ratio};
    if (f.neo_hookean) return {f.neo_hookean->young_modulus_pa, f.neo_hookean->poisson_ratio};
    if (f.hexahedron_fem) return {f.hexahedron_fem->young_modulus_pa, f.hexahedron_fem->poisson_ratio};
    if (f.triangle_fem) return {f.triangle_fem->young_modulus_pa, f.triangle_fem->poisson_ratio};
  }
  return {5000.0, 0.45};
}

double mean_edge_length(const mechanics::ModelConfig& c) {
  double sum = 0.0;
  std::size_t count = 0;
  for (const mesh::Tet& t : c.tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        sum += (c.positions[static_cast<std::size_t>(t[static_cast<std::size_t>(i)])] - c.positions[static_cast<std::size_t>(t[static_cast<std::size_t>(j)])]).norm();
        ++count;
      }
    }
  }
  return count ? sum / static_cast<double>(count) : 0.01;
}

}  // namespace

Expected<void> Gui::switch_component(const BodyView& body, const std::string& component, const std::string& choice) {
  if (!body.config) return make_error(ErrorCode::kInvalidArgument, fmt::format("body '{}' is rigid", body.name));
  const mechanics::ModelConfig& c = *body.config;
  scene::SceneEdit edit;
  edit.action = scene::SceneEdit::Action::kReplace;
  edit.node = body.name;
  edit.component = component;
  const auto num = [](double v) { return fmt::format("{}", v); };
  const auto [young, poisson] = elastic_moduli(c);
  if (choice.starts_with("TetrahedronFEMForceField")) {
    edit.type = "TetrahedronFEMForceField";
    edit.attributes = {{"youngModulus", num(young)}, {"poissonRatio", num(poisson)}, {"method", choice.substr(choice.find(' ') + 1)}};
  } else if (choice.starts_with("NeoHookean")) {
    // SOFA's NeoHookean ParameterSet is (μ, k): the same small-strain E and ν.
    edit.type = "TetrahedronHyperelasticityFEMForceField";
    const double mu = young / (2.0 * (1.0 + poisson)), bulk = young / (3.0 * (1.0 - 2.0 * poisson));
    edit.attributes = {{"materialName", "NeoHookean"}, {"ParameterSet", num(mu) + " " + num(bulk)}};
  } else if (choice == "MeshSpringForceField") {
    // A starting point of the same order as the continuum (k ~ E·l per spring over the mean
    // edge l, a dimensional estimate; springs have no exact equivalent in 3D): tune it in the
    // panel. SOFA's MeshSpringForceField divides the value by each spring's rest length.
    edit.type = "MeshSpringForceField";
    const double edge = mean_edge_length(c);
    edit.attributes = {{"stiffness", num(young * edge * edge)}, {"damping", "0"}};
  } else if (choice == "EulerImplicitSolver") {
    edit.type = choice;
    const double rk = c.ode.kind == mechanics::OdeSolverKind::kEulerImplicit ? c.ode.rayleigh_stiffness : 0.1;
    const double rm = c.ode.kind == mechanics::OdeSolverKind::kEulerImplicit ? c.ode.rayleigh_mass : 0.1;
    edit.attributes = {{"rayleighStiffness", num(rk)}, {"rayleighMass", num(rm)}};
  } else if (choice == "EulerExplicitSolver") {
    edit.type = choice;
    edit.attributes = {{"symplectic", "1"}};
  } else if (choice == "RungeKutta4Solver" || choice == "StaticSolver") {
    edit.type = choice;
  } else if (choice == "CGLinearSolver") {
    edit.type = choice;
    edit.attributes = {{"iterations", num(c.linear.iterations)}, {"tolerance", num(c.linear.tolerance)}, {"threshold", num(c.linear.threshold)}};
  } else if (choice == "SparseLDLSolver") {
    edit.type = choice;
  } else if (choice == "UniformMass") {
    edit.type = choice;
    double total = 0.0;
    if (auto model = mechanics::build_model(c)) total = model->total_mass_kg();
    edit.attributes = {{"totalMass", num(total > 0.0 ? total : 1.0)}};
  } else if (choice == "DiagonalMass") {
    edit.type = choice;
    double total = 0.0, volume = 0.0;
    if (auto model = mechanics::build_model(c)) total = model->total_mass_kg();
    for (const mesh::Tet& t : c.tets) {
      const auto corners = mesh::tet_corners(c.positions, t);
      volume += std::abs(mesh::tet_signed_volume(corners[0], corners[1], corners[2], corners[3]));
    }
    edit.attributes = {{"massDensity", num(volume > 0.0 && total > 0.0 ? total / volume : 1000.0)}};
  } else {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("no component type '{}'", choice));
  }
  auto done = change_structure(edit, std::nullopt);
  if (!done && (choice == "CGLinearSolver" || choice == "SparseLDLSolver")) {
    // The scene had no linear solver (its defaults were shown): add one.
    edit.action = scene::SceneEdit::Action::kAdd;
    return change_structure(edit, std::nullopt);
  }
  return done;
}

Expected<void> Gui::save(const std::filesystem::path& path) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (file_.extension() == ".x3d") {
    return make_error(ErrorCode::kUnsupported, "an X3D scene cannot be saved as a project yet (the project format holds SOFA scenes)",
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

scene::HofProject Gui::project_for(const std::filesystem::path& path) const {
  scene::HofProject out = scene::moved_project(project_, file_, path);
  if (session_) scene::record_parameters(out, session_->parameter_changes());  // as <set> elements
  // And those submitted but not applied yet (a save right after a change, the simulation busy).
  scene::record_parameters(out, submitted_changes_);
  return out;
}

Expected<void> Gui::start_recording(const std::filesystem::path& file) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (recording_) return make_error(ErrorCode::kInvalidArgument, "already recording to " + recording_->file.string());
  Recording r;
  r.file = file;
  r.world_to_device = mouse_calibration().position.inverse();
  r.samples.reserve(60000);
  if (file_.extension() != ".x3d") r.project = project_for(std::filesystem::path(file).replace_extension(".hof"));
  recording_ = std::move(r);
  report("recording the stylus to " + file.string(), false);
  return {};
}

Expected<void> Gui::stop_recording() {
  if (!recording_) return make_error(ErrorCode::kInvalidArgument, "not recording");
  Recording r = std::move(*recording_);
  recording_.reset();
  if (r.samples.size() < 2) return make_error(ErrorCode::kInvalidArgument, "nothing recorded (the stylus sent no reading)", r.file.string());
  std::error_code ec;
  if (r.file.has_parent_path()) std::filesystem::create_directories(r.file.parent_path(), ec);
  // The trajectory, in the replay format (docs/device-protocol.md), written whole then renamed.
  std::string text = fmt::format("# hof gui recording of {} ({}), device {}\n# t s, x y z m in the device frame; calibration (row-major):", file_.string(),
                                 world_name_, device_spec_);
  for (int i = 0; i < 16; ++i) text += fmt::format(" {}", calibration_.position(i / 4, i % 4));
  text += "\n";
  for (const std::string& e : r.events) text += "# event " + e + "\n";
  text += "t,x,y,z,button\n";
  for (const haptics::ReplaySample& s : r.samples) {
    text += fmt::format("{:.6f},{:.9g},{:.9g},{:.9g},{}\n", s.t_s, s.position_m.x(), s.position_m.y(), s.position_m.z(), s.buttons);
  }
  if (auto written = write_file_atomically(r.file, text); !written) return std::unexpected(written.error());
  // Beside it, the project that replays it with the settings it began with and the calibration
  // the window used: `hof run NAME.hof --deterministic` reproduces the demonstration (the
  // settings changed meanwhile are listed as events in the recording's comments).
  std::string replay_project;
  if (r.project) {
    std::filesystem::path project_file = r.file;
    project_file.replace_extension(".hof");
    scene::HofProject out = *r.project;
    out.device = "replay:" + r.file.filename().string();
    for (int i = 0; i < 16; ++i) out.position_calibration[static_cast<std::size_t>(i)] = calibration_.position(i / 4, i % 4);
    if (auto ok = scene::write_project(out, project_file); !ok) return ok;
    replay_project = fmt::format("; replay it with `hof run {} --deterministic`", project_file.string());
  }
  report(fmt::format("recorded {:.2f} s of the stylus ({} samples) to {}{}", r.seconds(), r.samples.size(), r.file.string(), replay_project),
         false);
  return {};
}

Expected<void> Gui::export_shape(const std::filesystem::path& path) {
  mesh::Mesh m;
  for (const LayerView& l : layers_) {
    if (!l.latest) continue;
    const auto offset = static_cast<mesh::NodeIndex>(m.nodes.size());
    m.nodes.insert(m.nodes.end(), l.latest->vertices.begin(), l.latest->vertices.end());
    for (const mesh::Tri& t : l.latest->triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  if (auto ok = mesh::write_mesh(m, path); !ok) return ok;
  report("exported the current shape to " + path.string(), false);
  return {};
}

// ---------------------------------------------------------------------------------------------
// The mouse stylus

std::optional<Vec3> Gui::pick(double x_px, double y_px) const {
  const auto [origin, direction] = camera_.ray(x_px, y_px, view_w_, view_h_);
  const Vec3 far = origin + direction * (camera_.distance() * 20.0);
  std::optional<Vec3> best;
  double best_t = 2.0;
  for (const LayerView& l : layers_) {
    if (!l.latest || l.latest->triangles.empty()) continue;
    const collision::SweepHit hit = l.latest->tree.first_hit_segment(l.latest->view(), origin, far, collision::TouchableFace::kFrontAndBack);
    if (hit.triangle >= 0 && hit.t < best_t) {
      best_t = hit.t;
      best = hit.point;
    }
  }
  return best;
}

void Gui::set_mouse_target(const Vec3& world) {
  mouse_world_ = world;
  if (mouse_) mouse_->set_target((mouse_calibration().position.inverse() * world.homogeneous()).head<3>());
}

void Gui::mouse_to(double window_x, double window_y, double depth_m, bool new_plane) {
  const double x = window_x - view_x_, y = window_y;
  if (new_plane) {
    // The plane faces the camera and passes just in front of the surface under the cursor
    // (by the proxy's radius), or through the current stylus when there is none.
    const double clearance = std::max(project_.proxy_radius_m, 0.002 * scene_size()) * 1.5;
    if (const auto hit = pick(x, y)) {
      plane_point_ = *hit - camera_.forward() * clearance;
    } else {
      plane_point_ = mouse_world_;
    }
  }
  mouse_depth_m_ = depth_m;
  const auto [origin, direction] = camera_.ray(x, y, view_w_, view_h_);
  const Vec3 f = camera_.forward();
  const double plane_depth = (plane_point_ - origin).dot(f) + mouse_depth_m_;
  const double along = direction.dot(f);
  if (!(along > 1e-9)) return;
  set_mouse_target(origin + direction * (plane_depth / along));
}

void Gui::handle_input() {
  ImGuiIO& io = ImGui::GetIO();
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(window_, &x, &y);
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x;
  last_y_ = y;
  // Depth: the wheel while the stylus is held, or W/S at any time.
  const double depth_step = 0.01 * scene_size();
  double push = 0.0;
  if (!io.WantCaptureKeyboard && !io.KeyCtrl) {
    if (ImGui::IsKeyPressed(GLFW_KEY_W)) push += depth_step;
    if (ImGui::IsKeyPressed(GLFW_KEY_S)) push -= depth_step;
  }
  if (io.WantCaptureMouse && !dragging_stylus_) {
    if (push != 0.0 && mouse_) {
      mouse_depth_m_ += push;
      set_mouse_target(mouse_world_ + camera_.forward() * push);
    }
    return;
  }
  const bool left = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  const bool right = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool middle = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  const bool shift = io.KeyShift;
  // Left: the stylus follows the cursor on a plane facing the camera (set where the drag
  // starts, just in front of the surface under the cursor). Right: orbit; middle or
  // shift+right: pan; wheel: zoom (while the stylus is held: depth).
  if (left && mouse_) {
    if (!dragging_stylus_) {
      mouse_to(x, y, 0.0, true);
      dragging_stylus_ = true;
    }
    mouse_to(x, y, mouse_depth_m_ + push + depth_step * io.MouseWheel, false);
    return;
  }
  dragging_stylus_ = false;
  if (push != 0.0 && mouse_) {
    mouse_depth_m_ += push;
    set_mouse_target(mouse_world_ + camera_.forward() * push);
  }
  if ((right && shift) || middle) {
    camera_.pan(dx, dy, view_h_);
  } else if (right) {
    camera_.orbit(dx, dy);
  }
  if (io.MouseWheel != 0.0f) camera_.zoom(std::pow(0.9, io.MouseWheel));
}

// ---------------------------------------------------------------------------------------------
// Drawing

render::Rgba phase_colour(procedures::NeedlePhase phase);

void Gui::draw_scene(int width, int height) {
  view_x_ = static_cast<int>(kPanelWidth);
  view_w_ = std::max(width - view_x_, 1);
  view_h_ = std::max(height, 1);
  glViewport(0, 0, width, height);
  glClearColor(0.12f, 0.13f, 0.15f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  renderer_->begin(camera_, view_x_, 0, view_w_, view_h_, render::Rgba(0.16f, 0.18f, 0.22f, 1.0f));

  const scene::GraphicsSetup& g = project_.graphics;
  render::Material tissue;
  tissue.diffuse = render::Rgba(static_cast<float>(g.diffuse_color.x()), static_cast<float>(g.diffuse_color.y()),
                                static_cast<float>(g.diffuse_color.z()), static_cast<float>(1.0 - g.transparency));
  tissue.specular = g.specular_color.cast<float>();
  tissue.shininess = static_cast<float>(g.shininess);
  render::Material rigid;
  rigid.diffuse = render::Rgba(0.62f, 0.64f, 0.68f, 1.0f);
  rigid.specular = {0.3f, 0.3f, 0.3f};
  const render::RenderMode mode = render_mode_of(g.render_mode);
  render::Lighting lighting;
  lighting.headlight_intensity = g.headlight ? static_cast<float>(g.headlight_intensity) : 0.0f;
  lighting.direction = g.light_direction.cast<float>();
  lighting.intensity = static_cast<float>(g.light_intensity);
  lighting.ambient = static_cast<float>(g.ambient_intensity);
  renderer_->set_lighting(lighting);
  const double size = scene_size();
  // Opaque parts first, then transparent ones (shapes only seen among them).
  for (int pass = 0; pass < 2; ++pass) {
    // The needle is opaque: drawn before the transparent bodies it is seen through.
    if (pass == 1 && last_.valid && needle_) draw_needle(size);
    for (const VisualView& v : visuals_) {
      if ((v.material.diffuse.w() < 0.999f) == (pass == 1)) renderer_->draw(v.mesh, v.material, render::RenderMode::kShaded);
    }
    for (LayerView& l : layers_) {
      for (const haptics::SurfacePart& part : l.parts) {
        const BodyView* body = part.body >= 0 && static_cast<std::size_t>(part.body) < bodies_.size() ? &bodies_[static_cast<std::size_t>(part.body)] : nullptr;
        const render::Material& m = body && body->material ? *body->material : part.is_static ? rigid : tissue;
        if ((m.diffuse.w() < 0.999f) != (pass == 1)) continue;
        renderer_->draw(l.mesh, m, part.is_static ? render::RenderMode::kShaded : mode, Eigen::Matrix4f::Identity(),
                       static_cast<std::size_t>(part.first_triangle), static_cast<std::size_t>(part.triangle_count));
      }
    }
  }
  if (last_.valid && needle_ && last_.tool.touched) {
    // The needle inside a body, seen through it (as an X-ray): the path from the entry point to
    // the tip and the tip marker, over everything.
    glDisable(GL_DEPTH_TEST);
    const haptics::ToolState& t = last_.tool;
    const Vec3 path[2] = {t.entry, last_.device};
    renderer_->draw_lines(path, render::Rgba(0.9f, 0.92f, 0.95f, 1.0f));
    renderer_->draw_sphere(last_.device, 0.004 * size, phase_colour(static_cast<procedures::NeedlePhase>(t.phase)));
    renderer_->draw_sphere(t.entry, 0.004 * size, render::Rgba(1.0f, 0.15f, 0.1f, 1.0f));
    glEnable(GL_DEPTH_TEST);
  }
  // Debug views.
  if (show_bound_tree_) {
    std::vector<Vec3> lines;
    for (const LayerView& l : layers_) {
      if (!l.latest) continue;
      for (const auto& [lo, hi] : l.latest->tree.boxes(bound_tree_depth_)) add_box_edges(lines, lo, hi);
    }
    renderer_->draw_lines(lines, render::Rgba(0.3f, 0.9f, 0.4f, 1.0f));
  }
  if (show_fixed_nodes_) {
    for (const BodyView& b : bodies_) renderer_->draw_points(b.fixed_points, render::Rgba(0.2f, 0.6f, 1.0f, 1.0f), 5.0f);
  }
  if (show_regions_) {
    for (const scene::MaterialRegion& r : project_.regions) {
      if (r.shape == scene::MaterialRegion::Shape::kSphere) {
        renderer_->draw_sphere(r.center, r.radius, render::Rgba(1.0f, 0.55f, 0.1f, 0.3f));
        continue;
      }
      if (r.shape != scene::MaterialRegion::Shape::kBox) continue;  // a physical group has no shape of its own
      std::vector<Vec3> lines;
      add_box_edges(lines, r.box_min, r.box_max);
      renderer_->draw_lines(lines, render::Rgba(1.0f, 0.55f, 0.1f, 1.0f));
    }
  }
  // Spring effects: the anchor, and the sphere within which the spring catches the stylus.
  for (const haptics::SpringEffect& e : project_.effects.springs) {
    renderer_->draw_sphere(e.position_m, std::max(0.003 * size, 1e-6), render::Rgba(0.3f, 0.9f, 0.5f, 1.0f));
    renderer_->draw_sphere(e.position_m, e.start_distance_m, render::Rgba(0.3f, 0.9f, 0.5f, 0.25f));
  }
  // The stylus, the proxy, the device, the contact.
  const double proxy_radius = std::max(project_.renderer == haptics::RendererKind::kRuspini ? project_.proxy_radius_m : project_.stylus_radius_m,
                                       0.004 * size);
  if (last_.valid && !needle_) {
    const Vec3 shaft = (camera_.up_on_screen() * 0.8 - camera_.forward() * 0.6).normalized();
    const double length = std::clamp(project_.stylus_length_m, 0.05 * size, 0.6 * size);
    renderer_->draw_cylinder(last_.proxy, last_.proxy + shaft * length, proxy_radius * 0.45, render::Rgba(0.75f, 0.78f, 0.82f, 1.0f));
    renderer_->draw_sphere(last_.proxy, proxy_radius, render::Rgba(0.35f, 0.75f, 1.0f, 1.0f));
    if (show_device_) {
      renderer_->draw_sphere(last_.device, proxy_radius * 0.6, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
      const Vec3 segment[2] = {last_.proxy, last_.device};
      renderer_->draw_lines(segment, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
    }
    if (last_.contact) {
      renderer_->draw_sphere(last_.contact_point, proxy_radius * 0.5, render::Rgba(1.0f, 0.85f, 0.1f, 1.0f));
      const Vec3 normal[2] = {last_.contact_point, last_.contact_point + last_.contact_normal * 0.08 * size};
      renderer_->draw_lines(normal, render::Rgba(0.3f, 1.0f, 0.3f, 1.0f));
      const double per_n = arrow_m_per_n_ > 0.0f ? arrow_m_per_n_ : size / 3.0 / std::max(max_force_n_, 1e-6);
      const Vec3 force = last_.force;
      if (force.norm() > 1e-6) {
        renderer_->draw_arrow(last_.proxy, last_.proxy + force * per_n, proxy_radius * 0.35, render::Rgba(1.0f, 0.25f, 0.2f, 1.0f));
      }
      if (show_contact_triangle_ && last_.triangle >= 0 && static_cast<std::size_t>(last_.layer) < layers_.size()) {
        const haptics::SurfaceSnapshot* s = layers_[static_cast<std::size_t>(last_.layer)].latest;
        if (s && static_cast<std::size_t>(last_.triangle) < s->triangles.size()) {
          const mesh::Tri& t = s->triangles[static_cast<std::size_t>(last_.triangle)];
          const Vec3 lift = last_.contact_normal * 0.001 * size;
          const Vec3 a = s->vertices[static_cast<std::size_t>(t[0])] + lift, b = s->vertices[static_cast<std::size_t>(t[1])] + lift,
                     c = s->vertices[static_cast<std::size_t>(t[2])] + lift;
          const Vec3 edges[6] = {a, b, b, c, c, a};
          renderer_->draw_lines(edges, render::Rgba(0.2f, 1.0f, 1.0f, 1.0f));
        }
      }
    }
  }
  glViewport(0, 0, width, height);
}

// The colour of each needle phase (the tip marker, the touch panel).
render::Rgba phase_colour(procedures::NeedlePhase phase) {
  switch (phase) {
    case procedures::NeedlePhase::kTouching: return {1.0f, 0.85f, 0.1f, 1.0f};
    case procedures::NeedlePhase::kPrePuncture: return {0.75f, 0.35f, 1.0f, 1.0f};
    case procedures::NeedlePhase::kPunctured: return {0.1f, 0.8f, 0.5f, 1.0f};
    case procedures::NeedlePhase::kRelaxation: return {0.35f, 0.75f, 1.0f, 1.0f};
    case procedures::NeedlePhase::kExtraction: return {1.0f, 0.6f, 0.1f, 1.0f};
    default: return {0.85f, 0.85f, 0.85f, 1.0f};
  }
}

void Gui::draw_needle(double size) {
  // The thesis' stylus (Zamani et al.): a thin tip section, the shaft, then the syringe, drawn
  // from the tip back along the needle. Inside a body the needle lies on its insertion axis;
  // outside, it points into the view. Diameters below what a screen shows are widened, in
  // proportion.
  const procedures::NeedleGeometry& g = project_.needle ? project_.needle->geometry : procedures::NeedleGeometry{};
  const haptics::ToolState& tool = last_.tool;
  const auto phase = static_cast<procedures::NeedlePhase>(tool.phase);
  const bool inside = tool.touched && tool.axis.squaredNorm() > 0.5;
  const Vec3 back = inside ? Vec3(-tool.axis) : Vec3((camera_.up_on_screen() * 0.8 - camera_.forward() * 0.6).normalized());
  const Vec3 tip = last_.device;
  const double visible = 0.0012 * size;  // the thinnest radius worth drawing
  const double widen = std::max(1.0, visible / (0.5 * g.tip_diameter_m));
  const Vec3 tip_end = tip + back * g.tip_length_m;
  const Vec3 hub = tip + back * g.length_m;
  renderer_->draw_cylinder(tip, tip_end, 0.5 * g.tip_diameter_m * widen, render::Rgba(0.85f, 0.87f, 0.9f, 1.0f));
  renderer_->draw_cylinder(tip_end, hub, 0.5 * g.shaft_diameter_m * std::min(widen, std::max(1.0, 2.0 * visible / (0.5 * g.shaft_diameter_m))),
                           render::Rgba(0.75f, 0.78f, 0.82f, 1.0f));
  renderer_->draw_cylinder(hub, hub + back * g.syringe_length_m, 0.5 * g.syringe_diameter_m, render::Rgba(0.8f, 0.9f, 1.0f, 0.45f));
  // The tip marker (the thesis' sphere at the tip), in the phase's colour, and the entry point.
  renderer_->draw_sphere(tip, std::max(0.0025 * size, g.tip_diameter_m), phase_colour(phase));
  if (tool.touched) {
    renderer_->draw_sphere(tool.entry, std::max(0.003 * size, g.shaft_diameter_m), render::Rgba(1.0f, 0.15f, 0.1f, 1.0f));
    const Vec3 path[2] = {tool.entry, tool.entry + tool.axis * std::max(tool.depth_m, 0.0)};
    renderer_->draw_lines(path, render::Rgba(1.0f, 0.4f, 0.3f, 1.0f));
  }
  const double per_n = arrow_m_per_n_ > 0.0f ? arrow_m_per_n_ : size / 3.0 / std::max(max_force_n_, 1e-6);
  if (last_.force.norm() > 1e-6) {
    renderer_->draw_arrow(hub, hub + last_.force * per_n, 0.0015 * size, render::Rgba(1.0f, 0.25f, 0.2f, 1.0f));
  }
}

void Gui::draw_legend() {
  const std::string& by = project_.graphics.color_by;
  if ((by != "displacement" && by != "strain" && by != "stress") || layers_.empty()) return;
  const bool strain = by == "strain";
  const bool stress = by == "stress";
  double range = 0.0;
  for (const LayerView& l : layers_) range = std::max(range, strain ? l.max_strain : stress ? l.max_stress_pa : l.max_displacement_m);
  range = std::max(range, strain ? 0.01 : stress ? 1e-6 : 0.01 * scene_size());
  const ImVec2 size(290, 58);
  ImGui::SetNextWindowPos(ImVec2(ImGui::GetIO().DisplaySize.x - size.x - 10, ImGui::GetIO().DisplaySize.y - size.y - 10));
  ImGui::SetNextWindowSize(size);
  ImGui::Begin("##legend", nullptr, ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoSavedSettings);
  const double scale = strain ? 100.0 : stress ? (range >= 1e3 ? 1e-3 : 1.0) : length_unit_ == "m" ? 1e3 : 1.0;
  if (strain) {
    ImGui::Text("surface strain (%%, to its 98th pct)");
  } else if (stress) {
    ImGui::Text("von Mises stress (%s, to its 98th pct)", range >= 1e3 ? "kPa" : "Pa");
  } else {
    ImGui::Text("displacement from rest (%s)", length_unit_ == "m" ? "mm" : length_unit_.c_str());
  }
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const ImVec2 p = ImGui::GetCursorScreenPos();
  constexpr int kSteps = 32;
  const float w = (size.x - 80) / kSteps;
  for (int i = 0; i < kSteps; ++i) {
    const Eigen::Vector3f c = render::viridis(static_cast<float>(i) / (kSteps - 1));
    const float x0 = p.x + static_cast<float>(i) * w;
    draw->AddRectFilled(ImVec2(x0, p.y), ImVec2(x0 + w, p.y + 14), ImColor(c.x(), c.y(), c.z()));
  }
  ImGui::Dummy(ImVec2(size.x - 80, 14));
  ImGui::SameLine();
  ImGui::Text("0 - %.3g", range * scale);
  ImGui::End();
}

namespace {

/// The scene-tree rows of a model: each component with its SOFA type, in the order a scene
/// lists them ("" is the node itself: dt, gravity, ...).
std::vector<std::pair<std::string, std::string>> components_of(const mechanics::ModelConfig& c) {
  std::vector<std::pair<std::string, std::string>> out;
  out.emplace_back("", "Node");
  const char* ode = c.ode.kind == mechanics::OdeSolverKind::kEulerExplicit ? "EulerExplicitSolver"
                    : c.ode.kind == mechanics::OdeSolverKind::kRungeKutta4 ? "RungeKutta4Solver"
                    : c.ode.kind == mechanics::OdeSolverKind::kStatic      ? "StaticSolver"
                                                                           : "EulerImplicitSolver";
  out.emplace_back(c.ode.name, ode);
  out.emplace_back(c.linear.name, c.linear.kind == mechanics::LinearSolverKind::kSparseLdlt ? "SparseLDLSolver" : "CGLinearSolver");
  out.emplace_back(c.mass.name, c.mass.kind == mechanics::MassKind::kUniform ? "UniformMass" : "DiagonalMass");
  for (const mechanics::ForceFieldConfig& f : c.force_fields) {
    const char* type = f.mesh_springs      ? "MeshSpringForceField"
                       : f.tetrahedron_fem ? "TetrahedronFEMForceField"
                       : f.neo_hookean     ? "TetrahedronHyperelasticityFEMForceField (NeoHookean)"
                                           : "ConstantForceField";
    out.emplace_back(f.name, type);
  }
  for (const mechanics::FixedConstraintConfig& f : c.fixed) out.emplace_back(f.name, "FixedProjectiveConstraint");
  return out;
}

}  // namespace

void Gui::draw_mechanics_panel() {
  ImGui::TextDisabled("Enter applies a value (validated; saved with the project)");
  for (BodyView& b : bodies_) {
    const std::string label = fmt::format("{} ({})", b.name, b.deformable ? "deformable" : "rigid");
    if (!ImGui::TreeNodeEx(label.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) continue;
    if (!b.config) {
      ImGui::TextDisabled("fixed shape: touchable, never deforms");
      ImGui::TreePop();
      continue;
    }
    ImGui::TextDisabled("%zu nodes, %zu tetrahedra, %zu fixed", b.config->positions.size(), b.config->tets.size(), b.fixed_points.size());
    for (const auto& [component, type] : components_of(*b.config)) {
      const std::string prefix = component + "/";
      const bool has_parameters = std::any_of(b.parameters.begin(), b.parameters.end(), [&](const std::string& p) { return p.starts_with(prefix); });
      const std::string node = fmt::format("{} {}##{}/{}", type, component.empty() ? b.name : component, b.name, component);
      // The force fields (what is tuned most) start open.
      const bool force_field = type.find("ForceField") != std::string::npos;
      const ImGuiTreeNodeFlags flags = !has_parameters ? ImGuiTreeNodeFlags_Leaf : force_field ? ImGuiTreeNodeFlags_DefaultOpen : ImGuiTreeNodeFlags_None;
      // Interactive: components can be opened (to switch or remove them) even without parameters.
      const bool editable = !component.empty();
      if (!ImGui::TreeNodeEx(node.c_str(), editable ? (flags & ~ImGuiTreeNodeFlags_Leaf) : flags)) continue;
      if (editable) {
        const std::vector<std::string>* choices = type.find("Solver") != std::string::npos && type != "CGLinearSolver" && type != "SparseLDLSolver"
                                                      ? &kOdeSolvers
                                                  : type == "CGLinearSolver" || type == "SparseLDLSolver" ? &kLinearSolvers
                                                  : type.find("Mass") != std::string::npos                ? &kMasses
                                                  : type.find("ForceField") != std::string::npos && type != "ConstantForceField" ? &kForceFields
                                                                                                          : nullptr;
        if (choices) {
          ImGui::SetNextItemWidth(200);
          const std::string combo = fmt::format("type##{}/{}", b.name, component);
          if (ImGui::BeginCombo(combo.c_str(), "switch to...")) {
            for (const std::string& choice : *choices) {
              if (ImGui::Selectable(choice.c_str())) {
                if (auto ok = switch_component(b, component, choice); !ok) report(ok.error().to_string(), true);
              }
            }
            ImGui::EndCombo();
          }
        }
        const bool removable = type.find("ForceField") != std::string::npos || type.find("Constraint") != std::string::npos;
        if (removable) {
          if (choices) ImGui::SameLine();
          const std::string remove = fmt::format("remove##{}/{}", b.name, component);
          if (ImGui::SmallButton(remove.c_str())) {
            if (auto ok = change_structure(scene::SceneEdit{scene::SceneEdit::Action::kRemove, b.name, component, "", {}}, std::nullopt); !ok) {
              report(ok.error().to_string(), true);
            }
          }
        }
      }
      for (const std::string& p : b.parameters) {
        if (!p.starts_with(prefix)) continue;
        const std::string parameter = p.substr(prefix.size());
        const auto value = mechanics::get_parameter(*b.config, component, parameter);
        if (!value) continue;
        double v = *value;
        ImGui::SetNextItemWidth(130);
        const std::string id = fmt::format("{}##{}/{}", parameter, b.name, p);
        if (ImGui::InputDouble(id.c_str(), &v, 0.0, 0.0, "%.6g", ImGuiInputTextFlags_EnterReturnsTrue)) {
          const std::string element = component.empty() ? "mechanics/" + b.name : "mechanics/" + b.name + "/" + component;
          if (auto ok = apply_set(element, parameter, number_text(v)); !ok) report(ok.error().to_string(), true);
        }
      }
      ImGui::TreePop();
    }
    draw_structure_editor(b);
    ImGui::TreePop();
  }
}

void Gui::draw_structure_editor(BodyView& b) {
  if (!b.config) return;
  const double size = scene_size();
  const std::string id = b.name;
  // Add a component.
  ImGui::SetNextItemWidth(200);
  if (ImGui::BeginCombo(fmt::format("add##{}", id).c_str(), "add a component...")) {
    const auto unique = [&](const std::string& base) {
      std::string name = base;
      for (int n = 2; std::any_of(b.parameters.begin(), b.parameters.end(), [&](const std::string& p) { return p.starts_with(name + "/"); }) ||
                      std::any_of(b.config->fixed.begin(), b.config->fixed.end(), [&](const auto& f) { return f.name == name; }) ||
                      std::any_of(b.config->force_fields.begin(), b.config->force_fields.end(), [&](const auto& f) { return f.name == name; });
           ++n) {
        name = base + std::to_string(n);
      }
      return name;
    };
    const auto [young, poisson] = elastic_moduli(*b.config);
    scene::SceneEdit edit{scene::SceneEdit::Action::kAdd, b.name, "", "", {}};
    if (ImGui::Selectable("TetrahedronFEMForceField")) {
      edit.component = unique("FEM");
      edit.type = "TetrahedronFEMForceField";
      edit.attributes = {{"youngModulus", fmt::format("{}", young)}, {"poissonRatio", fmt::format("{}", poisson)}, {"method", "large"}};
    }
    if (ImGui::Selectable("MeshSpringForceField")) {
      edit.component = unique("springs");
      edit.type = "MeshSpringForceField";
      const double edge = mean_edge_length(*b.config);  // per spring ~E·l; SOFA divides by l
      edit.attributes = {{"stiffness", fmt::format("{}", young * edge * edge)}};
    }
    const bool at_stylus = last_.valid;
    if (ImGui::Selectable("FixedProjectiveConstraint: the nodes near the stylus", false, at_stylus ? 0 : ImGuiSelectableFlags_Disabled)) {
      const double radius = pin_radius_m_ > 0.0f ? pin_radius_m_ : 0.05 * size;
      std::string indices;
      for (std::size_t i = 0; i < b.config->positions.size(); ++i) {
        if ((b.config->positions[i] - last_.proxy).norm() <= radius) indices += (indices.empty() ? "" : " ") + std::to_string(i);
      }
      if (indices.empty()) {
        report(fmt::format("no node of {} within {:.3g} of the stylus: nothing to pin", b.name, radius), true);
      } else {
        edit.component = unique("pin");
        edit.type = "FixedProjectiveConstraint";
        edit.attributes = {{"indices", indices}};
      }
    }
    ImGui::EndCombo();
    if (!edit.type.empty()) {
      if (auto ok = change_structure(edit, std::nullopt); !ok) report(ok.error().to_string(), true);
    }
  }
  ImGui::SetNextItemWidth(120);
  ImGui::InputFloat(fmt::format("pin radius (0: auto)##{}", id).c_str(), &pin_radius_m_, 0.0f, 0.0f, "%.4g");

  // Material regions.
  ImGui::TextDisabled("tissue regions (elements whose centroid is inside, or a Gmsh physical group)");
  std::optional<std::vector<scene::MaterialRegion>> regions;
  for (std::size_t i = 0; i < project_.regions.size(); ++i) {
    const scene::MaterialRegion& r = project_.regions[i];
    if (r.body != b.name) continue;
    std::string material;
    if (r.young_modulus_pa) material += fmt::format(" E = {:.4g} Pa", *r.young_modulus_pa);
    if (r.poisson_ratio) material += fmt::format(" nu = {:.3g}", *r.poisson_ratio);
    if (r.mass_density_kg_per_m3) material += fmt::format(" rho = {:.4g}", *r.mass_density_kg_per_m3);
    const std::string where = r.shape == scene::MaterialRegion::Shape::kSphere ? fmt::format("sphere r {:.3g}", r.radius)
                              : r.shape == scene::MaterialRegion::Shape::kBox  ? std::string("box")
                                                                               : fmt::format("group {}", r.physical_group);
    ImGui::BulletText("%s: %s,%s", r.name.c_str(), where.c_str(), material.c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton(fmt::format("remove##region{}", i).c_str())) {
      regions = project_.regions;
      regions->erase(regions->begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  ImGui::SetNextItemWidth(90);
  ImGui::InputFloat(fmt::format("radius##{}", id).c_str(), &region_radius_m_, 0.0f, 0.0f, "%.4g");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(70);
  ImGui::InputFloat(fmt::format("x E##{}", id).c_str(), &region_factor_, 0.0f, 0.0f, "%.3g");
  const bool has_tets = std::any_of(b.config->force_fields.begin(), b.config->force_fields.end(),
                                    [](const auto& f) { return f.tetrahedron_fem || f.neo_hookean || f.triangle_fem || f.hexahedron_fem; });
  if (!has_tets) ImGui::TextDisabled("(regions need an FEM force field)");
  if (has_tets && ImGui::Button(fmt::format("+ region at the stylus##{}", id).c_str())) {
    if (!last_.valid) {
      report("the stylus has no position yet", true);
    } else {
      scene::MaterialRegion r;
      r.name = fmt::format("region{}", project_.regions.size() + 1);
      r.body = b.name;
      r.center = last_.contact ? last_.contact_point : last_.proxy;
      r.radius = region_radius_m_ > 0.0f ? region_radius_m_ : 0.1 * size;
      r.young_modulus_pa = elastic_moduli(*b.config).first * std::max(static_cast<double>(region_factor_), 1e-3);
      regions = project_.regions;
      regions->push_back(r);
    }
  }
  if (regions) {
    if (auto ok = change_structure(std::nullopt, regions); !ok) report(ok.error().to_string(), true);
  }
}

void Gui::draw_effects_editor() {
  ImGui::Separator();
  ImGui::TextDisabled("force effects (H3D; Enter applies)");
  const auto set = [&](const std::string& element, const char* attribute, const std::string& value) {
    if (auto ok = apply_set(element, attribute, value); !ok) report(ok.error().to_string(), true);
  };
  const auto number = [&](const std::string& element, const char* attribute, double value) {
    ImGui::SetNextItemWidth(160);
    if (ImGui::InputDouble(attribute, &value, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) set(element, attribute, number_text(value));
  };
  const auto vector = [&](const std::string& element, const char* attribute, const Vec3& value) {
    double v[3] = {value.x(), value.y(), value.z()};
    ImGui::SetNextItemWidth(240);
    if (ImGui::InputScalarN(attribute, ImGuiDataType_Double, v, 3, nullptr, nullptr, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
      set(element, attribute, fmt::format("{} {} {}", v[0], v[1], v[2]));
    }
  };
  // Adding or removing an effect changes the list as a whole (one command).
  const auto change = [&](const auto& mutate) {
    haptics::ForceEffects effects = project_.effects;
    mutate(effects);
    if (auto ok = session_->submit(coupling::command::SetEffects{effects}); !ok) {
      report(ok.error().to_string(), true);
      return;
    }
    project_.effects = std::move(effects);
    dirty_ = true;
  };
  std::optional<std::function<void(haptics::ForceEffects&)>> pending;  // applied after the loops below
  for (std::size_t i = 0; i < project_.effects.springs.size(); ++i) {
    const haptics::SpringEffect e = project_.effects.springs[i];
    const std::string element = fmt::format("haptics/effects/SpringEffect[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("SpringEffect %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) pending = [i](haptics::ForceEffects& f) { f.springs.erase(f.springs.begin() + static_cast<std::ptrdiff_t>(i)); };
    vector(element, "position", e.position_m);
    number(element, "springConstant", e.spring_constant_n_per_m);
    number(element, "startDistance", e.start_distance_m);
    number(element, "escapeDistance", e.escape_distance_m);
    number(element, "damping", e.damping_n_s_per_m);
    ImGui::PopID();
  }
  for (std::size_t i = 0; i < project_.effects.viscosities.size(); ++i) {
    const haptics::ViscosityEffect e = project_.effects.viscosities[i];
    const std::string element = fmt::format("haptics/effects/ViscosityEffect[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("ViscosityEffect %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) pending = [i](haptics::ForceEffects& f) { f.viscosities.erase(f.viscosities.begin() + static_cast<std::ptrdiff_t>(i)); };
    number(element, "viscosity", e.viscosity_pa_s);
    number(element, "radius", e.radius_m);
    number(element, "dampingFactor", e.damping_factor);
    bool enabled = e.enabled;
    if (ImGui::Checkbox("enabled", &enabled)) set(element, "enabled", enabled ? "true" : "false");
    ImGui::PopID();
  }
  for (std::size_t i = 0; i < project_.effects.constants.size(); ++i) {
    const std::string element = fmt::format("haptics/effects/ForceField[{}]", i + 1);
    ImGui::PushID(element.c_str());
    ImGui::Text("ForceField %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) pending = [i](haptics::ForceEffects& f) { f.constants.erase(f.constants.begin() + static_cast<std::ptrdiff_t>(i)); };
    vector(element, "force", project_.effects.constants[i].force_n);
    ImGui::PopID();
  }
  // New effects start where the stylus is (a spring holds it there at once) and with H3D's defaults.
  if (ImGui::SmallButton("+ spring")) {
    pending = [at = last_.valid ? last_.proxy : mouse_world_](haptics::ForceEffects& f) {
      haptics::SpringEffect spring;
      spring.position_m = at;
      f.springs.push_back(spring);
    };
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("+ viscosity")) pending = [](haptics::ForceEffects& f) { f.viscosities.emplace_back(); };
  ImGui::SameLine();
  if (ImGui::SmallButton("+ force field")) pending = [](haptics::ForceEffects& f) { f.constants.emplace_back(); };
  if (pending && session_) change(*pending);
}

void Gui::draw_haptics_panel() {
  const auto set = [&](const std::string& element, const char* attribute, const std::string& value) {
    if (auto ok = apply_set(element, attribute, value); !ok) report(ok.error().to_string(), true);
  };
  ImGui::Text("device: %s", device_spec_.c_str());
  ImGui::SameLine();
  if (reading_) {
    ImGui::TextColored(ImVec4(0.4f, 0.9f, 0.4f, 1.0f), "reading");
  } else {
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "no reading (absent, timed out or ended): no force");
  }
  if (session_) {
    ImGui::TextDisabled("device limit %.3g N; %s", max_force_n_, mouse_ ? "left-drag in the view moves the stylus" : "");
  }
  static std::array<char, 256> spec{};
  ImGui::SetNextItemWidth(220);
  ImGui::InputTextWithHint("##spec", "dhd, udp:5005, spacemouse, mouse", spec.data(), spec.size());
  ImGui::SameLine();
  if (ImGui::Button("Connect") && spec[0] != '\0') set("haptics", "device", spec.data());
  // The vendors' SDKs, loaded when asked for (docs/devices.md): a clear message when absent.
  if (ImGui::Button("Force Dimension")) set("haptics", "device", "dhd");
  ImGui::SameLine();
  if (ImGui::Button("Mouse")) set("haptics", "device", "mouse");
  int renderer = static_cast<int>(project_.renderer);
  const char* renderers[] = {"PenaltyRenderer", "GodObjectRenderer", "RuspiniRenderer"};
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("renderer", &renderer, renderers, 3)) set("haptics", "renderer", renderers[renderer]);
  double radius = project_.proxy_radius_m;
  ImGui::SetNextItemWidth(200);
  if (ImGui::InputDouble("proxyRadius (m)", &radius, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    set("haptics", "proxyRadius", number_text(radius));
  }
  double limit = project_.safety.max_force_n;
  ImGui::SetNextItemWidth(200);
  if (ImGui::TreeNode("Calibration (device -> world)")) {
    const Eigen::Matrix3d linear = calibration_.position.topLeftCorner<3, 3>();
    const Vec3 offset = calibration_.position.topRightCorner<3, 1>();
    ImGui::Text("scale %.4g, offset %.4g %.4g %.4g", std::cbrt(std::abs(linear.determinant())), offset.x(), offset.y(), offset.z());
    ImGui::TextDisabled("device workspace radius %.3g m", workspace_radius_m_);
    const auto apply = [&](const Eigen::Matrix4d& m) {
      std::string text;
      for (int i = 0; i < 16; ++i) text += fmt::format("{}{}", i ? " " : "", m(i / 4, i % 4));
      if (auto ok = apply_set("haptics/calibration", "positionCalibration", text); !ok) report(ok.error().to_string(), true);
    };
    if (ImGui::Button("Fit the workspace to the scene")) {
      // The device's reach spans the scene's bounding sphere (keeping the axes).
      Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
      const double scale = 0.5 * scene_size() / std::max(workspace_radius_m_, 1e-6);
      m.topLeftCorner<3, 3>() *= scale;
      m.topRightCorner<3, 1>() = 0.5 * (bounds_min_ + bounds_max_);
      apply(m);
    }
    ImGui::SameLine();
    if (ImGui::Button("Identity")) apply(Eigen::Matrix4d::Identity());
    ImGui::TreePop();
  }
  if (ImGui::InputDouble("force limit (N, 0: device's)", &limit, 0.0, 0.0, "%.3g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    set("haptics/safety", "maxForce", number_text(limit));
  }
  bool shading = project_.force_shading;
  if (ImGui::Checkbox("forceShading", &shading)) set("haptics", "forceShading", shading ? "true" : "false");
  int face = static_cast<int>(project_.touchable_face);
  const char* faces[] = {"FRONT", "BACK", "FRONT_AND_BACK"};
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("touchableFace", &face, faces, 3)) set("haptics", "touchableFace", faces[face]);
  ImGui::Separator();
  ImGui::TextDisabled("surface");
  int kind = static_cast<int>(project_.surface.kind);
  const char* kinds[] = {"SmoothSurface", "FrictionalSurface", "MagneticSurface"};
  ImGui::SetNextItemWidth(200);
  if (kind >= 0 && kind < 3 && ImGui::Combo("type", &kind, kinds, 3)) set("haptics/surface", "type", kinds[kind]);
  const auto number = [&](const char* label, const char* attribute, double value) {
    ImGui::SetNextItemWidth(200);
    if (ImGui::InputDouble(label, &value, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
      set("haptics/surface", attribute, number_text(value));
    }
  };
  number("stiffness", "stiffness", project_.surface.stiffness);
  number("damping (N s/m)", "damping", project_.surface.damping_n_s_per_m);
  number("staticFriction", "staticFriction", project_.surface.static_friction);
  number("dynamicFriction", "dynamicFriction", project_.surface.dynamic_friction);
  bool relative = project_.surface.use_relative_values;
  if (ImGui::Checkbox("useRelativeValues", &relative)) set("haptics/surface", "useRelativeValues", relative ? "true" : "false");
  ImGui::Separator();
  ImGui::TextDisabled("options (saved; they apply when the project is reopened)");
  bool tree = project_.use_bound_tree;
  if (ImGui::Checkbox("useBoundTree", &tree)) set("haptics/options", "useBoundTree", tree ? "true" : "false");
  draw_effects_editor();
}

Expected<void> Gui::mount_needle(bool on) {
  if (!session_) return make_error(ErrorCode::kInvalidArgument, "no world is open");
  if (on == project_.needle.has_value()) return {};
  if (file_.extension() == ".x3d") return make_error(ErrorCode::kUnsupported, "the needle is mounted in a .hof project (save the scene as one)");
  scene::HofProject next = project_;
  // The parameters changed so far go with the reopened world.
  scene::record_parameters(next, session_->parameter_changes());
  scene::record_parameters(next, submitted_changes_);
  if (on) {
    next.needle = procedures::NeedleConfig{};
  } else {
    next.needle.reset();
  }
  if (auto ok = open(file_, &next); !ok) return ok;
  dirty_ = true;
  report(on ? "the needle is mounted: its tissue parameters are in the Needle panel" : "the needle is taken off", false);
  return {};
}

void Gui::draw_needle_editor() {
  bool mounted = project_.needle.has_value();
  if (ImGui::Checkbox("the stylus is a needle (reopens the world)", &mounted)) {
    if (auto ok = mount_needle(mounted); !ok) report(ok.error().to_string(), true);
  }
  if (!project_.needle || !needle_) {
    ImGui::TextDisabled("insertion with Maurin's or Simone-Okamura's model (docs/needle.md)");
    return;
  }
  const auto set = [&](const std::string& element, const char* attribute, const std::string& value) {
    if (auto ok = apply_set(element, attribute, value); !ok) report(ok.error().to_string(), true);
  };
  procedures::NeedleConfig& n = *project_.needle;
  int axis = static_cast<int>(n.axis);
  const char* axes[] = {"motion", "normal", "stylus"};
  ImGui::SetNextItemWidth(120);
  if (ImGui::Combo("axis at first contact", &axis, axes, 3)) set("haptics/needle", "axis", axes[axis]);
  double filter = n.velocity_filter_s;
  ImGui::SetNextItemWidth(120);
  if (ImGui::InputDouble("velocityFilter (s)", &filter, 0.0, 0.0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)) {
    set("haptics/needle", "velocityFilter", number_text(filter));
  }
  // The common set (every deformable body), then each body's own: tissue[k] as the file orders them.
  const auto edit_tissue = [&](const std::string& element, const procedures::TissueNeedleParameters& t, const std::string& label) {
    if (!ImGui::TreeNodeEx(label.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
    int model = static_cast<int>(t.model);
    const char* models[] = {"fung", "simone-okamura"};
    ImGui::SetNextItemWidth(150);
    if (ImGui::Combo("model", &model, models, 2)) set(element, "model", models[model]);
    bool pierceable = t.pierceable;
    if (ImGui::Checkbox("pierceable", &pierceable)) set(element, "pierceable", pierceable ? "true" : "false");
    const auto number = [&](const char* text, const char* attribute, double value) {
      ImGui::SetNextItemWidth(150);
      if (ImGui::InputDouble(text, &value, 0.0, 0.0, "%.5g", ImGuiInputTextFlags_EnterReturnsTrue)) set(element, attribute, number_text(value));
    };
    const auto numbers = [&](const char* text, const char* attribute, std::vector<double> values) {
      std::array<float, 4> f{};
      for (std::size_t i = 0; i < values.size(); ++i) f[i] = static_cast<float>(values[i]);
      ImGui::SetNextItemWidth(230);
      bool changed = values.size() == 4 ? ImGui::InputFloat4(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue)
                                        : ImGui::InputFloat3(text, f.data(), "%.4g", ImGuiInputTextFlags_EnterReturnsTrue);
      if (!changed) return;
      std::string joined;
      // A float's shortest text (0.01145, not 0.011450000107…): the values the user sees.
      for (std::size_t i = 0; i < values.size(); ++i) joined += (i ? " " : "") + fmt::format("{}", f[i]);
      set(element, attribute, joined);
    };
    number("capsule (m)", "capsule", t.capsule_m);
    number("punctureForce (N)", "punctureForce", t.puncture_force_n);
    number("relaxationTime (s)", "relaxationTime", t.relaxation_time_s);
    if (t.model == procedures::NeedleForceModel::kFung) {
      int form = static_cast<int>(t.fung_form);
      const char* forms[] = {"integrated", "printed"};
      ImGui::SetNextItemWidth(150);
      if (ImGui::Combo("fungForm", &form, forms, 2)) set(element, "fungForm", forms[form]);
      numbers("fungPre a b d0 F0", "fungPre", {t.fung_pre.a_per_m, t.fung_pre.b_n, t.fung_pre.d0_m, t.fung_pre.f0_n});
      numbers("fungPost a b d0 F0", "fungPost", {t.fung_post.a_per_m, t.fung_post.b_n, t.fung_post.d0_m, t.fung_post.f0_n});
      ImGui::TextDisabled(t.fung_form == procedures::FungForm::kIntegrated ? "f(d) = (F0 + b) exp(a (d - d0)) - b; SI: 1/m, N, m, N"
                                                                             : "f(d) = (F0 + b) exp(a (d - d0)) + b; SI: 1/m, N, m, N");
    } else {
      numbers("stiffness a0 a1 a2", "stiffness", {t.stiffness.a0_n, t.stiffness.a1_n_per_m, t.stiffness.a2_n_per_m2});
      number("cuttingForce (N)", "cuttingForce", t.cutting_force_n);
    }
    numbers("friction Cp Cn bp bn", "friction",
            {t.friction.static_positive_n_per_m, t.friction.static_negative_n_per_m, t.friction.damping_positive_n_s_per_m2,
             t.friction.damping_negative_n_s_per_m2});
    number("frictionVelocityBand (m/s)", "frictionVelocityBand", t.friction.velocity_band_m_per_s);
    number("lateralStiffness (N/m)", "lateralStiffness", t.lateral_stiffness_n_per_m);
    number("lateralDamping (N s/m)", "lateralDamping", t.lateral_damping_n_s_per_m);
    number("spreadRadius (m)", "spreadRadius", t.spread_radius_m);
    number("pathTolerance (m)", "pathTolerance", t.path_tolerance_m);
    ImGui::TreePop();
  };
  const procedures::NeedleConfig current = n;  // the editors may replace project_ while drawing
  edit_tissue("haptics/needle/tissue", current.tissue, "tissue of every deformable body");
  for (std::size_t k = 0; k < current.bodies.size(); ++k) {
    edit_tissue(fmt::format("haptics/needle/tissue[{}]", k + 2), current.bodies[k].second, "tissue of " + current.bodies[k].first);
  }
}

void Gui::draw_graphics_panel() {
  const auto set = [&](const char* element, const char* attribute, const std::string& value) {
    if (auto ok = apply_set(element, attribute, value); !ok) report(ok.error().to_string(), true);
  };
  scene::GraphicsSetup& g = project_.graphics;
  const char* modes[] = {"shaded", "wireframe", "shaded+wireframe", "points"};
  int mode = static_cast<int>(std::find(std::begin(modes), std::end(modes), g.render_mode) - std::begin(modes));
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("renderMode", &mode, modes, 4)) set("graphics", "renderMode", modes[mode]);
  const char* colourings[] = {"material", "displacement", "strain", "stress"};
  int colouring = g.color_by == "displacement" ? 1 : g.color_by == "strain" ? 2 : g.color_by == "stress" ? 3 : 0;
  ImGui::SetNextItemWidth(200);
  if (ImGui::Combo("colorBy", &colouring, colourings, 4)) set("graphics", "colorBy", colourings[colouring]);
  float diffuse[3] = {static_cast<float>(g.diffuse_color.x()), static_cast<float>(g.diffuse_color.y()), static_cast<float>(g.diffuse_color.z())};
  if (ImGui::ColorEdit3("diffuseColor", diffuse)) {
    set("graphics/material", "diffuseColor", fmt::format("{} {} {}", diffuse[0], diffuse[1], diffuse[2]));
  }
  float shininess = static_cast<float>(g.shininess), transparency = static_cast<float>(g.transparency);
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("shininess", &shininess, 0.0f, 1.0f)) set("graphics/material", "shininess", number_text(shininess));
  ImGui::SetNextItemWidth(200);
  if (ImGui::SliderFloat("transparency", &transparency, 0.0f, 0.9f)) set("graphics/material", "transparency", number_text(transparency));
  if (ImGui::TreeNode("Lights")) {
    bool headlight = g.headlight;
    if (ImGui::Checkbox("headlight", &headlight)) set("graphics/light", "headlight", headlight ? "true" : "false");
    float head = static_cast<float>(g.headlight_intensity), key = static_cast<float>(g.light_intensity),
          ambient = static_cast<float>(g.ambient_intensity);
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("headlightIntensity", &head, 0.0f, 1.0f)) set("graphics/light", "headlightIntensity", number_text(head));
    float direction[3] = {static_cast<float>(g.light_direction.x()), static_cast<float>(g.light_direction.y()),
                          static_cast<float>(g.light_direction.z())};
    ImGui::SetNextItemWidth(200);
    if (ImGui::SliderFloat3("direction", direction, -1.0f, 1.0f) && Eigen::Vector3f(direction[0], direction[1], direction[2]).norm() > 1e-3f) {
      set("graphics/light", "direction", fmt::format("{} {} {}", direction[0], direction[1], direction[2]));
    }
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("intensity", &key, 0.0f, 1.0f)) set("graphics/light", "intensity", number_text(key));
    ImGui::SetNextItemWidth(160);
    if (ImGui::SliderFloat("ambientIntensity", &ambient, 0.0f, 1.0f)) set("graphics/light", "ambientIntensity", number_text(ambient));
    ImGui::TreePop();
  }
  if (ImGui::Button("Reset view")) reset_camera();
  ImGui::SameLine();
  if (ImGui::Button("Keep this view in the project")) {
    const Vec3 eye = camera_.eye(), target = camera_.target();
    set("graphics", "viewpoint", fmt::format("{} {} {}", eye.x(), eye.y(), eye.z()));
    set("graphics", "lookAt", fmt::format("{} {} {}", target.x(), target.y(), target.z()));
  }
  ImGui::Separator();
  ImGui::TextDisabled("debug views");
  ImGui::Checkbox("bound-tree boxes", &show_bound_tree_);
  if (show_bound_tree_) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(100);
    ImGui::SliderInt("depth", &bound_tree_depth_, 0, 12);
  }
  ImGui::Checkbox("contact triangle", &show_contact_triangle_);
  ImGui::Checkbox("fixed nodes", &show_fixed_nodes_);
  ImGui::Checkbox("material regions", &show_regions_);
  ImGui::Checkbox("device position", &show_device_);
  ImGui::SetNextItemWidth(200);
  ImGui::SliderFloat("force arrow (m/N, 0 = auto)", &arrow_m_per_n_, 0.0f, 0.1f, "%.3f");
}

void Gui::draw_panels() {
  ImGuiIO& io = ImGui::GetIO();
  // Menu.
  float menu_height = 0.0f;
  if (ImGui::BeginMainMenuBar()) {
    if (ImGui::BeginMenu("File")) {
      if (ImGui::MenuItem("Open...", "Ctrl+O")) want_open_dialog_ = true;
      if (ImGui::BeginMenu("Open recent", !recent_.empty())) {
        for (const auto& r : recent_) {
          if (ImGui::MenuItem(r.string().c_str())) dropped_ = r;
        }
        ImGui::EndMenu();
      }
      if (ImGui::MenuItem("Save", "Ctrl+S", false, session_ && file_.extension() == ".hof")) {
        if (auto ok = save(file_); !ok) report(ok.error().to_string(), true);
      }
      if (ImGui::MenuItem("Save as...", nullptr, false, session_ != nullptr)) want_save_dialog_ = true;
      if (ImGui::MenuItem("Export shape (.obj, .vtu)...", nullptr, false, session_ != nullptr)) want_export_dialog_ = true;
      if (ImGui::MenuItem("Replay a recording (.csv)...", nullptr, false, session_ != nullptr)) want_replay_dialog_ = true;
      if (ImGui::MenuItem("Screenshot (.png)...")) want_screenshot_dialog_ = true;
      ImGui::Separator();
      if (ImGui::MenuItem("Quit", "Ctrl+Q")) {
        if (dirty_) confirm_quit_ = true;
        else quit_ = true;
      }
      ImGui::EndMenu();
    }
    menu_height = ImGui::GetWindowSize().y;
    ImGui::EndMainMenuBar();
  }
  if (want_open_dialog_) {
    want_open_dialog_ = false;
    dialog_.show("Open a project, SOFA scene or X3D scene", false, {".hof", ".scn", ".x3d"}, [this](const std::filesystem::path& p) { dropped_ = p; });
  }
  if (want_save_dialog_) {
    want_save_dialog_ = false;
    dialog_.show("Save the project", true, {".hof"}, [this](const std::filesystem::path& p) {
      std::filesystem::path target = p.extension() == ".hof" ? p : std::filesystem::path(p.string() + ".hof");
      if (auto ok = save(target); !ok) report(ok.error().to_string(), true);
    }, file_.stem().string() + ".hof");
  }
  if (want_export_dialog_) {
    want_export_dialog_ = false;
    dialog_.show("Export the current shape", true, {".obj", ".vtu"}, [this](const std::filesystem::path& p) {
      if (auto ok = export_shape(p); !ok) report(ok.error().to_string(), true);
    }, file_.stem().string() + "-shape.obj");
  }
  if (want_replay_dialog_) {
    want_replay_dialog_ = false;
    dialog_.show("Replay a recorded stylus trajectory", false, {".csv"}, [this](const std::filesystem::path& p) {
      if (auto ok = apply_set("haptics", "device", "replay:" + std::filesystem::absolute(p).string()); !ok) report(ok.error().to_string(), true);
    });
  }
  if (want_screenshot_dialog_) {
    want_screenshot_dialog_ = false;
    dialog_.show("Save a screenshot", true, {".png"}, [this](const std::filesystem::path& p) { pending_screenshot_ = p; },
                 file_.stem().string() + ".png");
  }
  dialog_.draw();
  if (pending_open_ && !ImGui::IsPopupOpen("Open another file")) ImGui::OpenPopup("Open another file");
  if (ImGui::BeginPopupModal("Open another file", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has changes that are not saved.", file_.filename().string().c_str());
    const auto go = [&] {
      if (auto ok = open(*pending_open_); !ok) report(ok.error().to_string(), true);
      pending_open_.reset();
      ImGui::CloseCurrentPopup();
    };
    if (ImGui::Button("Save, then open") ) {
      if (auto ok = file_.extension() == ".hof" ? save(file_) : save(std::filesystem::path(file_).replace_extension(".hof")); ok) go();
      else report(ok.error().to_string(), true);
    }
    ImGui::SameLine();
    if (ImGui::Button("Discard them and open")) go();
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) {
      pending_open_.reset();
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
  if (confirm_quit_) {
    ImGui::OpenPopup("Unsaved changes");
    confirm_quit_ = false;
  }
  if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has changes that are not saved.", file_.filename().string().c_str());
    if (ImGui::Button("Save and quit")) {
      auto ok = file_.extension() == ".hof" ? save(file_) : save(std::filesystem::path(file_).replace_extension(".hof"));
      if (ok) quit_ = true;
      else report(ok.error().to_string(), true);
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (ImGui::Button("Quit without saving")) {
      quit_ = true;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }

  ImGui::SetNextWindowPos(ImVec2(0, menu_height));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y - menu_height));
  ImGui::Begin("HoF", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar);
  ImGui::Text("%s%s", world_name_.empty() ? "(nothing open: File > Open, or drop a file here)" : world_name_.c_str(), dirty_ ? " *" : "");
  ImGui::TextDisabled("%s", file_.string().c_str());
  if (!error_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s", error_.c_str());
    ImGui::PopStyleColor();
    if (ImGui::SmallButton("dismiss")) error_.clear();
  }
  // Controls.
  if (ImGui::Button(animating_ ? "Stop" : "Animate")) set_animating(!animating_);
  ImGui::SameLine();
  ImGui::BeginDisabled(animating_);
  if (ImGui::Button("Step") && session_) (void)session_->submit(coupling::command::SingleStep{1});
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Reset") && session_) {
    if (!session_->realtime_running()) session_->start_realtime();
    (void)session_->submit(coupling::command::Reset{});
    if (!animating_) (void)session_->submit(coupling::command::Pause{});
  }
  ImGui::SameLine();
  if (ImGui::Checkbox("real time", &realtime_pacing_) && session_) session_->set_realtime_pacing(realtime_pacing_);
  if (!recording_) {
    if (ImGui::Button("Record") && session_) {
      const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
      std::array<char, 32> stamp{};
      std::strftime(stamp.data(), stamp.size(), "%Y%m%d-%H%M%S", std::localtime(&now));
      const std::filesystem::path file = std::filesystem::path("recordings") / fmt::format("{}-{}.csv", file_.stem().string(), stamp.data());
      if (auto ok = start_recording(file); !ok) report(ok.error().to_string(), true);
    }
    ImGui::SameLine();
    ImGui::TextDisabled("the stylus, to replay (File > Replay)");
  } else {
    if (ImGui::Button("Stop recording")) {
      if (auto ok = stop_recording(); !ok) report(ok.error().to_string(), true);
    }
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "recording %.1f s", recording_ ? recording_->seconds() : 0.0);
  }
  // Live figures.
  ImGui::Text("%.0f frames/s   %.0f steps/s (dt %.3g s)", stats_.fps, stats_.steps_per_s, session_ ? session_->dt() : 0.0);
  ImGui::Text("haptic %.0f Hz, period p50 %.3f ms, p99 %.3f ms", stats_.haptic_hz, stats_.period_p50_ms, stats_.period_p99_ms);
  ImGui::Text("since the start: longest period %.3f ms, %llu over 2 ms", stats_.longest_period_ms,
              static_cast<unsigned long long>(stats_.periods_over_2ms));
  ImGui::Text("safety: %llu ticks at limit, %llu non-finite, %llu unread", static_cast<unsigned long long>(stats_.clamped),
              static_cast<unsigned long long>(stats_.non_finite), static_cast<unsigned long long>(stats_.invalid));
  const float top = *std::max_element(plot_force_.begin(), plot_force_.end());
  ImGui::PlotLines("##force", plot_force_.data(), static_cast<int>(plot_force_.size()), 0,
                   fmt::format("|F| (N), last {:.0f} s, now {:.2f}", kPlotSeconds, last_.force.norm()).c_str(), 0.0f,
                   std::max(top * 1.1f, 0.5f), ImVec2(kPanelWidth - 20, 70));
  const auto [lo, hi] = std::minmax_element(plot_indentation_.begin(), plot_indentation_.end());
  const double unit = length_unit_ == "m" ? 1.0 : 1e-3;  // telemetry is in scene units for a SOFA scene
  ImGui::PlotLines("##indentation", plot_indentation_.data(), static_cast<int>(plot_indentation_.size()), 0,
                   needle_ ? fmt::format("needle depth (mm), now {:.2f}", 1e3 * last_.tool.depth_m).c_str()
                           : fmt::format("indentation ({}), now {:.2f}", length_unit_ == "m" ? "mm" : "scene units / 1000", 1e3 * indentation_m_ * unit).c_str(),
                   std::min(*lo, 0.0f), std::max(*hi * 1.1f, 1.0f), ImVec2(kPanelWidth - 20, 70));
  // Touch.
  if (ImGui::CollapsingHeader("Touch", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (needle_ && last_.tool.active) {
      // The thesis' field network (touched, capsule, broken, distance, force, normal), live.
      const haptics::ToolState& t = last_.tool;
      const auto phase = static_cast<procedures::NeedlePhase>(t.phase);
      const render::Rgba c = phase_colour(phase);
      ImGui::Text("needle");
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(c.x(), c.y(), c.z(), 1.0f), "%s", std::string(procedures::phase_name(phase)).c_str());
      const double to_shown = 1e3;  // the needle's lengths are SI
      const char* length = "mm";
      const std::string body = t.body >= 0 && static_cast<std::size_t>(t.body) < bodies_.size() ? bodies_[static_cast<std::size_t>(t.body)].name : "-";
      const double capsule = t.body >= 0 ? needle_->parameters(static_cast<std::size_t>(t.body)).capsule_m : 0.0;
      ImGui::Text("touched %s, capsule %s, body %s", t.touched ? "yes" : "no",
                  !t.touched ? "-" : t.broken ? "broken" : fmt::format("intact ({:.1f} {})", to_shown * capsule, length).c_str(), body.c_str());
      ImGui::Text("depth %.2f %s, force along the needle %.3f N", to_shown * t.depth_m, length, t.axial_force_n);
      ImGui::Text("sent %.3f N, normal %.2f %.2f %.2f", last_.force.norm(), t.normal.x(), t.normal.y(), t.normal.z());
      if (t.touched) ImGui::Text("entry  %.4f %.4f %.4f", t.entry.x(), t.entry.y(), t.entry.z());
    } else if (last_.contact) {
      const std::string body = contact_body_ >= 0 && static_cast<std::size_t>(contact_body_) < bodies_.size()
                                   ? bodies_[static_cast<std::size_t>(contact_body_)].name
                                   : "?";
      ImGui::Text("body %s, triangle %d", body.c_str(), last_.triangle);
      ImGui::Text("point  %.4f %.4f %.4f", last_.contact_point.x(), last_.contact_point.y(), last_.contact_point.z());
      ImGui::Text("normal %.3f %.3f %.3f", last_.contact_normal.x(), last_.contact_normal.y(), last_.contact_normal.z());
      ImGui::Text("force  %.3f N  (%.2f %.2f %.2f)", last_.force.norm(), last_.force.x(), last_.force.y(), last_.force.z());
      ImGui::Text("indentation %.2f mm, proxy-device %.2f mm", 1e3 * indentation_m_ * unit, 1e3 * last_.penetration_m * unit);
    } else {
      ImGui::TextDisabled("no contact%s", mouse_ ? " (left-drag onto a body, wheel or W/S to press)" : "");
    }
  }
  if (open_panel_ == "needle") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Needle")) draw_needle_editor();
  if (open_panel_ == "mechanics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Mechanics")) draw_mechanics_panel();
  if (open_panel_ == "haptics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Haptics")) draw_haptics_panel();
  if (open_panel_ == "graphics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Graphics")) draw_graphics_panel();
  if (open_panel_ == "messages") ImGui::SetNextItemOpen(true);
  open_panel_.reset();
  if (ImGui::CollapsingHeader("Messages")) {
    for (const std::string& m : log_) ImGui::TextWrapped("%s", m.c_str());
  }
  ImGui::End();
  draw_legend();
}

void Gui::frame() {
  const auto start = Clock::now();
  glfwPollEvents();
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (dropped_) {
    const std::filesystem::path file = *dropped_;
    dropped_.reset();
    if (dirty_) {
      pending_open_ = file;  // asked in draw_panels()
    } else if (auto ok = open(file); !ok) {
      report(ok.error().to_string(), true);
    }
  }
  ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureKeyboard && io.KeyCtrl) {
    if (ImGui::IsKeyPressed(GLFW_KEY_S) && file_.extension() == ".hof") {
      if (auto ok = save(file_); !ok) report(ok.error().to_string(), true);
    }
    if (ImGui::IsKeyPressed(GLFW_KEY_O)) want_open_dialog_ = true;
    if (ImGui::IsKeyPressed(GLFW_KEY_Q)) {
      if (dirty_) confirm_quit_ = true;
      else quit_ = true;
    }
  } else if (!io.WantCaptureKeyboard && ImGui::IsKeyPressed(GLFW_KEY_SPACE)) {
    set_animating(!animating_);
  }
  handle_input();
  update_from_loops();
  draw_panels();
  ImGui::Render();
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  draw_scene(width, height);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  if (pending_screenshot_) {
    render::Image image{width, height, renderer_->read_pixels(width, height)};
    if (auto ok = render::write_png(image, *pending_screenshot_); !ok) {
      report(ok.error().to_string(), true);
    } else {
      report("screenshot " + pending_screenshot_->string(), false);
    }
    pending_screenshot_.reset();
  }
  glfwSwapBuffers(window_);
  // At most kMaxFrameRateHz: the cores are the haptic and simulation loops' first.
  const auto budget = std::chrono::duration<double>(1.0 / kMaxFrameRateHz);
  const auto spent = Clock::now() - start;
  if (spent < budget) std::this_thread::sleep_for(budget - spent);
}

// ---------------------------------------------------------------------------------------------
// Script and main loop

bool Gui::step_script(std::vector<ScriptAction>& script, std::size_t& next, const std::string& name, int& status) {
  while (next < script.size()) {
    const ScriptAction& a = script[next];
    const auto fail = [&](const Error& e) {
      std::fprintf(stderr, "hof gui: %s:%d: '%s': %s\n", name.c_str(), a.line, a.text.c_str(), e.to_string().c_str());
      status = 1;
      return false;
    };
    switch (a.kind) {
      case ScriptAction::Kind::kWait:
        if (!script_waiting_) {
          script_waiting_ = true;
          script_wait_until_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.number));
        }
        if (Clock::now() < script_wait_until_) return true;
        script_waiting_ = false;
        break;
      case ScriptAction::Kind::kAnimate:
        set_animating(a.on);
        break;
      case ScriptAction::Kind::kNeedle:
        if (auto ok = mount_needle(a.on); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kStep:
        if (session_) {
          if (auto ok = session_->submit(coupling::command::SingleStep{static_cast<int>(a.number)}); !ok) return fail(ok.error());
        }
        break;
      case ScriptAction::Kind::kReset:
        if (session_) (void)session_->submit(coupling::command::Reset{});
        break;
      case ScriptAction::Kind::kSet:
        if (auto ok = apply_set(a.element, a.attribute, a.value); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kEdit: {
        // mechanics/BODY/COMPONENT (replace, remove) or mechanics/BODY (add).
        const std::string path = a.element.substr(std::string("mechanics/").size());
        const std::size_t slash = path.find('/');
        scene::SceneEdit edit;
        edit.action = a.value == "replace" ? scene::SceneEdit::Action::kReplace
                      : a.value == "add"   ? scene::SceneEdit::Action::kAdd
                                           : scene::SceneEdit::Action::kRemove;
        edit.node = path.substr(0, slash);
        edit.component = a.value == "add" ? a.name : path.substr(slash + 1);
        edit.type = a.type;
        edit.attributes = a.attributes;
        if (auto ok = change_structure(edit, std::nullopt); !ok) return fail(ok.error());
        break;
      }
      case ScriptAction::Kind::kRegion: {
        std::vector<scene::MaterialRegion> regions;
        if (!a.numbers.empty()) {
          regions = project_.regions;
          scene::MaterialRegion r;
          r.name = fmt::format("region{}", regions.size() + 1);
          r.body = a.element;
          r.shape = a.box ? scene::MaterialRegion::Shape::kBox : scene::MaterialRegion::Shape::kSphere;
          if (a.box) {
            r.box_min = Vec3(a.numbers[0], a.numbers[1], a.numbers[2]);
            r.box_max = Vec3(a.numbers[3], a.numbers[4], a.numbers[5]);
          } else {
            r.center = Vec3(a.numbers[0], a.numbers[1], a.numbers[2]);
            r.radius = a.numbers[3];
          }
          r.young_modulus_pa = a.numbers.back();
          regions.push_back(r);
        }
        if (auto ok = change_structure(std::nullopt, regions); !ok) return fail(ok.error());
        break;
      }
      case ScriptAction::Kind::kMouse:
        if (!mouse_) return fail(Error{ErrorCode::kInvalidArgument, "the stylus is not the mouse (device " + device_spec_ + ")", "", 0, -1});
        mouse_to(a.number, a.y, 0.0, true);
        mouse_to(a.number, a.y, a.depth, false);
        break;
      case ScriptAction::Kind::kOpen:
        // The window's own error path: shown, and the world stays as it was.
        if (auto ok = open(a.file); !ok) report(ok.error().to_string(), true);
        break;
      case ScriptAction::Kind::kShow:
        open_panel_ = a.value;
        break;
      case ScriptAction::Kind::kRecord:
        if (auto ok = a.on ? start_recording(a.file) : stop_recording(); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kScreenshot:
        pending_screenshot_ = a.file;
        ++next;
        return true;  // taken at the end of the next frame
      case ScriptAction::Kind::kSave:
        if (auto ok = save(a.file); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kQuit:
        next = script.size();
        return false;
    }
    ++next;
  }
  return false;
}

int Gui::run(std::vector<ScriptAction> script, const std::string& script_name) {
  const bool scripted = !script_name.empty();
  std::size_t next = 0;
  int status = 0;
  const auto started = Clock::now();
  std::uint64_t frames = 0;
  while (!quit_) {
    if (glfwWindowShouldClose(window_)) break;
    frame();
    ++frames;
    if (scripted && !step_script(script, next, script_name, status)) {
      if (pending_screenshot_) continue;  // the last action was a screenshot: draw it first
      break;
    }
  }
  if (options_.result) {
    options_.result->frames = frames;
    options_.result->wall_s = seconds_between(started, Clock::now());
    if (session_) options_.result->session = session_->stop_realtime();
  }
  if (scripted && !options_.quiet) {
    const double wall = seconds_between(started, Clock::now());
    std::printf("hof gui: %llu frames in %.2f s (%.1f frames/s); last second: %.0f frames/s, %.0f simulation steps/s, haptic %.0f Hz, "
                "period p99 %.3f ms; whole run: longest period %.3f ms, %llu over 2 ms\n",
                static_cast<unsigned long long>(frames), wall, static_cast<double>(frames) / std::max(wall, 1e-9), stats_.fps,
                stats_.steps_per_s, stats_.haptic_hz, stats_.period_p99_ms, stats_.longest_period_ms,
                static_cast<unsigned long long>(stats_.periods_over_2ms));
    std::printf("hof gui: contact %.3f s, max force %.3f N, max surface displacement %.3f %s, %llu ticks at the force limit\n",
                static_cast<double>(contact_ticks_) * 1e-3, max_force_seen_n_,
                length_unit_ == "m" ? 1e3 * max_displacement_seen_m_ : max_displacement_seen_m_, length_unit_ == "m" ? "mm" : length_unit_.c_str(),
                static_cast<unsigned long long>(stats_.clamped));
  }
  return status;
}

}  // namespace

int run_gui(const GuiOptions& options) {
  std::vector<ScriptAction> script;
  std::string script_name;
  if (options.script) {
    auto read = read_script(*options.script);
    if (!read) {
      std::fprintf(stderr, "hof gui: %s\n", read.error().to_string().c_str());
      return 1;
    }
    script = std::move(*read);
    script_name = options.script->string();
  }
  // Before the window: its threads, and the session's, start with the CPUs kept awake.
  const haptics::CpuKeepAwake keep_awake(options.keep_awake);
  Gui gui(options);
  // The window's renderer threads (Mesa's llvmpipe starts them with the context, where there
  // is no GPU) are made on the CPU the haptic loop will have: the simulation keeps its CPUs.
  const std::vector<int> cpus = allowed_cpus();
  const CpuPlan plan = options.pin_threads ? plan_cpus(cpus) : CpuPlan{};
  if (plan.pinned()) pin_current_thread(std::array<int, 1>{plan.haptic});
  auto window = gui.create_window();
  if (plan.pinned()) pin_current_thread(cpus);  // this thread itself goes where it likes
  if (!window) {
    std::fprintf(stderr, "hof gui: %s\n", window.error().to_string().c_str());
    return 1;
  }
  if (options.file) {
    if (auto ok = gui.open(*options.file); !ok) {
      std::fprintf(stderr, "hof gui: %s\n", ok.error().to_string().c_str());
      if (options.script) return 1;  // a script cannot go on without its world
    }
  }
  return gui.run(std::move(script), script_name);
}

}  // namespace hof::app
