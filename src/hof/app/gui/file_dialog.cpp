#include "hof/app/gui/detail/file_dialog.h"

#include <imgui.h>

#include <algorithm>

namespace hof::app::gui {

void FileDialog::show(const std::string& t, bool save, std::vector<std::string> exts,
                      std::function<void(const std::filesystem::path&)> f, const std::string& suggested) {
  open = true;
  saving = save;
  title = t;
  extensions = std::move(exts);
  on_choose = std::move(f);
  name.fill('\0');
  std::copy_n(suggested.begin(), std::min(suggested.size(), name.size() - 1), name.begin());
  ImGui::OpenPopup("##file");
}

void FileDialog::draw() {
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
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.path().filename() < b.path().filename(); });
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

}  // namespace hof::app::gui
