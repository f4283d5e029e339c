// The Messages panel: what the window reported (opened files, warnings, errors, the needle's
// events), newest last.
#include <imgui.h>

#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

GuiCommands messages_panel(const WorldView& w) {
  for (const std::string& m : w.log) ImGui::TextWrapped("%s", m.c_str());
  return {};
}

}  // namespace hof::app::gui
