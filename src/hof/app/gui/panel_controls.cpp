// The panel's head: the world's name and file, an error, the controls (animate, step, reset,
// real time, record), the live figures and the force and indentation plots.
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <ctime>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

std::string number_text(double v) { return fmt::format("{}", v); }

GuiCommands controls_panel(const WorldView& w) {
  GuiCommands out;
  ImGui::Text("%s%s", w.world_name.empty() ? "(nothing open: File > Open, or drop a file here)" : w.world_name.c_str(),
              w.dirty ? " *" : "");
  ImGui::TextDisabled("%s", w.file.string().c_str());
  if (!w.error.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s", w.error.c_str());
    ImGui::PopStyleColor();
    if (ImGui::SmallButton("dismiss")) out.push_back(action::DismissError{});
  }
  // Controls.
  if (ImGui::Button(w.animating ? "Stop" : "Animate")) out.push_back(action::SetAnimating{!w.animating});
  ImGui::SameLine();
  ImGui::BeginDisabled(w.animating);
  if (ImGui::Button("Step") && w.session) out.push_back(coupling::Command{coupling::command::SingleStep{1}});
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Reset") && w.session) out.push_back(action::ResetWorld{});
  ImGui::SameLine();
  bool realtime = w.realtime_pacing;
  if (ImGui::Checkbox("real time", &realtime)) out.push_back(action::SetRealtimePacing{realtime});
  if (!w.recording) {
    if (ImGui::Button("Record") && w.session) {
      const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
      std::array<char, 32> stamp{};
      std::strftime(stamp.data(), stamp.size(), "%Y%m%d-%H%M%S", std::localtime(&now));
      const std::filesystem::path file =
          std::filesystem::path("recordings") / fmt::format("{}-{}.csv", w.file.stem().string(), stamp.data());
      out.push_back(action::StartRecording{file});
    }
    ImGui::SameLine();
    ImGui::TextDisabled("the stylus, to replay (File > Replay)");
  } else {
    if (ImGui::Button("Stop recording")) out.push_back(action::StopRecording{});
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "recording %.1f s", w.recording ? w.recording->seconds() : 0.0);
  }
  // Live figures.
  ImGui::Text("%.0f frames/s   %.0f steps/s (dt %.3g s)", w.stats.fps, w.stats.steps_per_s,
              w.session ? w.session->dt() : 0.0);
  ImGui::Text("haptic %.0f Hz, period p50 %.3f ms, p99 %.3f ms", w.stats.haptic_hz, w.stats.period_p50_ms,
              w.stats.period_p99_ms);
  ImGui::Text("since the start: longest period %.3f ms, %llu over 2 ms", w.stats.longest_period_ms,
              static_cast<unsigned long long>(w.stats.periods_over_2ms));
  ImGui::Text("safety: %llu ticks at limit, %llu non-finite, %llu unread",
              static_cast<unsigned long long>(w.stats.clamped), static_cast<unsigned long long>(w.stats.non_finite),
              static_cast<unsigned long long>(w.stats.invalid));
  const float top = *std::max_element(w.plot_force.begin(), w.plot_force.end());
  ImGui::PlotLines("##force", w.plot_force.data(), static_cast<int>(w.plot_force.size()), 0,
                   fmt::format("|F| (N), last {:.0f} s, now {:.2f}", kPlotSeconds, w.last.force.norm()).c_str(), 0.0f,
                   std::max(top * 1.1f, 0.5f), ImVec2(kPanelWidth - 20, 70));
  const auto [lo, hi] = std::minmax_element(w.plot_indentation.begin(), w.plot_indentation.end());
  const double unit = w.length_unit == "m" ? 1.0 : 1e-3;  // telemetry is in scene units for a SOFA scene
  ImGui::PlotLines("##indentation", w.plot_indentation.data(), static_cast<int>(w.plot_indentation.size()), 0,
                   w.needle
                       ? fmt::format("needle depth (mm), now {:.2f}", 1e3 * w.last.tool.depth_m).c_str()
                       : fmt::format("indentation ({}), now {:.2f}", w.length_unit == "m" ? "mm" : "scene units / 1000",
                                     1e3 * w.indentation_m * unit)
                             .c_str(),
                   std::min(*lo, 0.0f), std::max(*hi * 1.1f, 1.0f), ImVec2(kPanelWidth - 20, 70));
  return out;
}

}  // namespace hof::app::gui
