// Recording the stylus: the trajectory in the replay format with the settings changed
// meanwhile as events, and beside it the project that replays it; the current shape exported.
#include <fmt/format.h>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/core/file_write.h"
#include "hof/mesh/mesh_io.h"

namespace hof::app::gui {

Expected<void> GuiWindow::start_recording(const std::filesystem::path& file) {
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

Expected<void> GuiWindow::stop_recording() {
  if (!recording_) return make_error(ErrorCode::kInvalidArgument, "not recording");
  Recording r = std::move(*recording_);
  recording_.reset();
  if (r.samples.size() < 2)
    return make_error(ErrorCode::kInvalidArgument, "nothing recorded (the stylus sent no reading)", r.file.string());
  std::error_code ec;
  if (r.file.has_parent_path()) std::filesystem::create_directories(r.file.parent_path(), ec);
  // The trajectory, in the replay format (docs/device-protocol.md), written whole then renamed.
  std::string text = fmt::format(
      "# hof gui recording of {} ({}), device {}\n# t s, x y z m in the device frame; calibration (row-major):",
      file_.string(), world_name_, device_spec_);
  for (int i = 0; i < 16; ++i) text += fmt::format(" {}", calibration_.position(i / 4, i % 4));
  text += "\n";
  for (const std::string& e : r.events) text += "# event " + e + "\n";
  text += "t,x,y,z,button\n";
  for (const haptics::ReplaySample& s : r.samples) {
    text += fmt::format("{:.6f},{:.9g},{:.9g},{:.9g},{}\n", s.t_s, s.position_m.x(), s.position_m.y(), s.position_m.z(),
                        s.buttons);
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
    for (int i = 0; i < 16; ++i)
      out.position_calibration[static_cast<std::size_t>(i)] = calibration_.position(i / 4, i % 4);
    if (auto ok = scene::write_project(out, project_file); !ok) return ok;
    replay_project = fmt::format("; replay it with `hof run {} --deterministic`", project_file.string());
  }
  report(fmt::format("recorded {:.2f} s of the stylus ({} samples) to {}{}", r.seconds(), r.samples.size(),
                     r.file.string(), replay_project),
         false);
  return {};
}

Expected<void> GuiWindow::export_shape(const std::filesystem::path& path) {
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

}  // namespace hof::app::gui
