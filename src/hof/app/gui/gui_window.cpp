// The window: the GLFW window and its ImGui context, the frame loop, the menu and its
// dialogs, the panels laid out and their commands applied, the legend, the script's run.
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
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <type_traits>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/core/cpu_affinity.h"
#include "hof/core/file_write.h"
#include "hof/haptics/cpu_keep_awake.h"
#include "hof/render/colormap.h"
#include "hof/render/image.h"

namespace hof::app {

namespace gui {

namespace {

constexpr double kMaxFrameRateHz = 60.0;  // the window leaves the cores to the loops

std::filesystem::path recent_files_path() {
  const char* config = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  if (config && *config) return std::filesystem::path(config) / "hof" / "recent-files";
  if (home && *home) return std::filesystem::path(home) / ".config" / "hof" / "recent-files";
  return {};
}

}  // namespace

Expected<void> GuiWindow::create_window() {
  glfwSetErrorCallback(
      [](int code, const char* text) { std::fprintf(stderr, "hof gui: GLFW error %d: %s\n", code, text); });
  if (!glfwInit()) {
    return make_error(ErrorCode::kUnsupported,
                      "no display: the window needs X11 (run `hof run --headless`, or under xvfb-run)");
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
    if (count > 0) static_cast<GuiWindow*>(glfwGetWindowUserPointer(w))->dropped_ = std::filesystem::path(paths[0]);
  });
  glfwSetWindowCloseCallback(window_, [](GLFWwindow* w) {
    auto* gui = static_cast<GuiWindow*>(glfwGetWindowUserPointer(w));
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

void GuiWindow::shut_down() {
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

void GuiWindow::report(const std::string& message, bool error) {
  if (error) error_ = message;
  log_.push_back(message);
  while (log_.size() > 50) log_.pop_front();
  if (!options_.quiet || error) std::fprintf(stderr, "hof gui: %s%s\n", error ? "error: " : "", message.c_str());
}

void GuiWindow::remember_recent(const std::filesystem::path& file) {
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

float GuiWindow::draw_menu() {
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
      if (ImGui::MenuItem("Export shape (.obj, .vtu)...", nullptr, false, session_ != nullptr))
        want_export_dialog_ = true;
      if (ImGui::MenuItem("Replay a recording (.csv)...", nullptr, false, session_ != nullptr))
        want_replay_dialog_ = true;
      if (ImGui::MenuItem("Screenshot (.png)...")) want_screenshot_dialog_ = true;
      ImGui::Separator();
      if (ImGui::MenuItem("Quit", "Ctrl+Q")) {
        if (dirty_)
          confirm_quit_ = true;
        else
          quit_ = true;
      }
      ImGui::EndMenu();
    }
    menu_height = ImGui::GetWindowSize().y;
    ImGui::EndMainMenuBar();
  }
  return menu_height;
}

void GuiWindow::draw_dialogs() {
  if (want_open_dialog_) {
    want_open_dialog_ = false;
    dialog_.show("Open a project, SOFA scene or X3D scene", false, {".hof", ".scn", ".x3d"},
                 [this](const std::filesystem::path& p) { dropped_ = p; });
  }
  if (want_save_dialog_) {
    want_save_dialog_ = false;
    dialog_.show(
        "Save the project", true, {".hof"},
        [this](const std::filesystem::path& p) {
          std::filesystem::path target = p.extension() == ".hof" ? p : std::filesystem::path(p.string() + ".hof");
          if (auto ok = save(target); !ok) report(ok.error().to_string(), true);
        },
        file_.stem().string() + ".hof");
  }
  if (want_export_dialog_) {
    want_export_dialog_ = false;
    dialog_.show(
        "Export the current shape", true, {".obj", ".vtu"},
        [this](const std::filesystem::path& p) {
          if (auto ok = export_shape(p); !ok) report(ok.error().to_string(), true);
        },
        file_.stem().string() + "-shape.obj");
  }
  if (want_replay_dialog_) {
    want_replay_dialog_ = false;
    dialog_.show("Replay a recorded stylus trajectory", false, {".csv"}, [this](const std::filesystem::path& p) {
      if (auto ok = apply_set("haptics", "device", "replay:" + std::filesystem::absolute(p).string()); !ok)
        report(ok.error().to_string(), true);
    });
  }
  if (want_screenshot_dialog_) {
    want_screenshot_dialog_ = false;
    dialog_.show(
        "Save a screenshot", true, {".png"}, [this](const std::filesystem::path& p) { pending_screenshot_ = p; },
        file_.stem().string() + ".png");
  }
  dialog_.draw();
}

void GuiWindow::draw_unsaved_prompts() {
  if (pending_open_ && !ImGui::IsPopupOpen("Open another file")) ImGui::OpenPopup("Open another file");
  if (ImGui::BeginPopupModal("Open another file", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s has changes that are not saved.", file_.filename().string().c_str());
    const auto go = [&] {
      if (auto ok = open(*pending_open_); !ok) report(ok.error().to_string(), true);
      pending_open_.reset();
      ImGui::CloseCurrentPopup();
    };
    if (ImGui::Button("Save, then open")) {
      if (auto ok =
              file_.extension() == ".hof" ? save(file_) : save(std::filesystem::path(file_).replace_extension(".hof"));
          ok)
        go();
      else
        report(ok.error().to_string(), true);
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
      auto ok =
          file_.extension() == ".hof" ? save(file_) : save(std::filesystem::path(file_).replace_extension(".hof"));
      if (ok)
        quit_ = true;
      else
        report(ok.error().to_string(), true);
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
}

void GuiWindow::draw_panels() {
  const float menu_height = draw_menu();
  draw_dialogs();
  draw_unsaved_prompts();
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, menu_height));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y - menu_height));
  ImGui::Begin(
      "HoF", nullptr,
      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar);
  // Each panel is drawn over this frame's view, then its commands are applied (the next panel
  // sees them).
  apply(controls_panel(view()));
  if (ImGui::CollapsingHeader("Touch", ImGuiTreeNodeFlags_DefaultOpen)) apply(touch_panel(view()));
  if (open_panel_ == "tool") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Tool")) apply(tool_panel(view(), tool_panel_));
  if (open_panel_ == "contacts") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Contacts")) apply(contacts_panel(view(), view_options_));
  if (open_panel_ == "needle") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Needle")) apply(needle_panel(view()));
  if (open_panel_ == "mechanics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Mechanics")) apply(mechanics_panel(view(), mechanics_panel_));
  if (open_panel_ == "haptics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Haptics")) apply(haptics_panel(view(), haptics_panel_));
  if (open_panel_ == "graphics") ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("Graphics")) apply(graphics_panel(view(), view_options_));
  if (open_panel_ == "messages") ImGui::SetNextItemOpen(true);
  open_panel_.reset();
  if (ImGui::CollapsingHeader("Messages")) apply(messages_panel(view()));
  ImGui::End();
  draw_legend();
}

void GuiWindow::draw_legend() {
  const scene::ColorBy by = project_.graphics.color_by;
  if (by == scene::ColorBy::kMaterial || layers_.empty()) return;
  const bool strain = by == scene::ColorBy::kStrain;
  const bool stress = by == scene::ColorBy::kStress;
  double range = 0.0;
  for (const LayerView& l : layers_)
    range = std::max(range, strain ? l.max_strain : stress ? l.max_stress_pa : l.max_displacement_m);
  range = std::max(range, strain ? 0.01 : stress ? 1e-6 : 0.01 * scene_size());
  const ImVec2 size(290, 58);
  ImGui::SetNextWindowPos(
      ImVec2(ImGui::GetIO().DisplaySize.x - size.x - 10, ImGui::GetIO().DisplaySize.y - size.y - 10));
  ImGui::SetNextWindowSize(size);
  ImGui::Begin("##legend", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoSavedSettings);
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

void GuiWindow::frame() {
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
      if (dirty_)
        confirm_quit_ = true;
      else
        quit_ = true;
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

int GuiWindow::run(std::vector<ScriptAction> script, const std::string& script_name) {
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
    std::printf(
        "hof gui: %llu frames in %.2f s (%.1f frames/s); last second: %.0f frames/s, %.0f simulation steps/s, haptic "
        "%.0f Hz, "
        "period p99 %.3f ms; whole run: longest period %.3f ms, %llu over 2 ms\n",
        static_cast<unsigned long long>(frames), wall, static_cast<double>(frames) / std::max(wall, 1e-9), stats_.fps,
        stats_.steps_per_s, stats_.haptic_hz, stats_.period_p99_ms, stats_.longest_period_ms,
        static_cast<unsigned long long>(stats_.periods_over_2ms));
    std::printf(
        "hof gui: contact %.3f s, max force %.3f N, max surface displacement %.3f %s, %llu ticks at the force limit\n",
        static_cast<double>(contact_ticks_) * 1e-3, max_force_seen_n_,
        length_unit_ == "m" ? 1e3 * max_displacement_seen_m_ : max_displacement_seen_m_,
        length_unit_ == "m" ? "mm" : length_unit_.c_str(), static_cast<unsigned long long>(stats_.clamped));
  }
  return status;
}

WorldView GuiWindow::view() const {
  return WorldView{file_,
                   project_,
                   world_name_,
                   length_unit_,
                   device_spec_,
                   session_.get(),
                   needle_.get(),
                   mouse_ != nullptr,
                   mouse_world_,
                   calibration_,
                   max_force_n_,
                   workspace_radius_m_,
                   bodies_,
                   shaped_tool_.get(),
                   contact_settings_,
                   disabled_pairs_,
                   contacts_,
                   bounds_min_,
                   bounds_max_,
                   animating_,
                   dirty_,
                   realtime_pacing_,
                   last_,
                   stats_,
                   plot_force_,
                   plot_indentation_,
                   indentation_m_,
                   reading_,
                   contact_body_,
                   recording_ ? &*recording_ : nullptr,
                   error_,
                   log_,
                   camera_};
}

void GuiWindow::apply(const GuiCommands& commands) {
  for (const GuiCommand& c : commands) {
    if (auto ok = apply(c); !ok) report(ok.error().to_string(), true);
  }
}

Expected<void> GuiWindow::apply(const GuiCommand& command) {
  return std::visit(
      [&](const auto& c) -> Expected<void> {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, coupling::Command>) {
          if (!session_) return {};
          // The commands the window keeps track of (to save them, to show them) go its way.
          if (const auto* set = std::get_if<coupling::command::SetParameter>(&c)) return set_parameter(*set);
          if (const auto* pair = std::get_if<coupling::command::SetContactPair>(&c)) return set_contact_pair(*pair);
          return session_->submit(c);
        } else if constexpr (std::is_same_v<T, action::SetAttribute>) {
          return apply_set(c.element, c.attribute, c.value);
        } else if constexpr (std::is_same_v<T, action::EditProject>) {
          return edit_project(c);
        } else if constexpr (std::is_same_v<T, action::SetGraphics>) {
          return set_graphics(c);
        } else if constexpr (std::is_same_v<T, action::SetSurface>) {
          return set_surface(c);
        } else if constexpr (std::is_same_v<T, action::SetRendering>) {
          return set_rendering(c);
        } else if constexpr (std::is_same_v<T, action::EditScene>) {
          return change_structure(c.edit, std::nullopt);
        } else if constexpr (std::is_same_v<T, action::AddComponent>) {
          return add_component(c);
        } else if constexpr (std::is_same_v<T, action::AddRegionAtStylus>) {
          return add_region_at_stylus(c);
        } else if constexpr (std::is_same_v<T, action::SwitchComponent>) {
          return switch_component(c.body, c.component, c.choice);
        } else if constexpr (std::is_same_v<T, action::SetRegions>) {
          return change_structure(std::nullopt, c.regions);
        } else if constexpr (std::is_same_v<T, action::SetEffects>) {
          return set_effects(c.effects);
        } else if constexpr (std::is_same_v<T, action::MountNeedle>) {
          return mount_needle(c.on);
        } else if constexpr (std::is_same_v<T, action::SetAnimating>) {
          set_animating(c.on);
        } else if constexpr (std::is_same_v<T, action::ResetWorld>) {
          reset_world();
        } else if constexpr (std::is_same_v<T, action::SetRealtimePacing>) {
          realtime_pacing_ = c.on;
          if (session_) session_->set_realtime_pacing(realtime_pacing_);
        } else if constexpr (std::is_same_v<T, action::StartRecording>) {
          return start_recording(c.file);
        } else if constexpr (std::is_same_v<T, action::StopRecording>) {
          return stop_recording();
        } else if constexpr (std::is_same_v<T, action::ResetCamera>) {
          reset_camera();
        } else if constexpr (std::is_same_v<T, action::DismissError>) {
          error_.clear();
        } else if constexpr (std::is_same_v<T, action::Report>) {
          report(c.message, c.error);
        }
        return {};
      },
      command);
}

}  // namespace gui

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
  gui::GuiWindow gui(options);
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
