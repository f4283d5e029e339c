#pragma once
/// @file
/// A minimal file chooser (ImGui has none): a folder listing and a name field.

#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace hof::app::gui {

struct FileDialog {
  bool open{false};
  bool saving{false};
  std::string title;
  std::vector<std::string> extensions;
  std::filesystem::path folder{std::filesystem::current_path()};
  std::array<char, 512> name{};
  std::function<void(const std::filesystem::path&)> on_choose;

  void show(const std::string& t, bool save, std::vector<std::string> exts,
            std::function<void(const std::filesystem::path&)> f, const std::string& suggested = {});
  void draw();
};

}  // namespace hof::app::gui
