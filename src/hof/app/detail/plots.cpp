#include "hof/app/detail/plots.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>

namespace hof::app::detail {

std::string gnuplot_text(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\'')
      out += "''";
    else
      out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? ' ' : c;
  }
  return out;
}

std::vector<std::string> render_plots(const std::filesystem::path& dir, const std::string& title,
                                      const std::vector<Plot>& plots) {
  std::ofstream all(dir / "plots.gp");
  std::vector<std::string> failed;
  for (const Plot& plot : plots) {
    for (const char* ext : {"png", "svg"}) {
      const bool png = std::string(ext) == "png";
      const std::string script = fmt::format(
          "set terminal {} size 960,540 noenhanced\nset output '{}.{}'\nset grid\nset key top left\nset title '{}'\n{}",
          png ? "pngcairo" : "svg", plot.name, ext, gnuplot_text(title), plot.body);
      all << script << "\n";
      const std::filesystem::path file = dir / fmt::format("{}.{}.gp", plot.name, ext);
      std::ofstream(file) << script;
      const std::string command =
          fmt::format("cd '{}' && gnuplot '{}' 2>/dev/null", dir.string(), file.filename().string());
      if (std::system(command.c_str()) != 0 && png) failed.push_back(plot.name);
      std::filesystem::remove(file);
    }
  }
  return failed;
}

}  // namespace hof::app::detail
