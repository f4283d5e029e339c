#include "hof/scene/sofa_legacy_formats.h"

#include <array>
#include <charconv>
#include <fstream>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "hof/core/text.h"

namespace hof::scene::detail {
namespace {

template <class T>
bool parse_token(std::string_view s, T& value) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  return ec == std::errc{} && ptr == s.data() + s.size();
}

std::unexpected<Error> error_at(const std::filesystem::path& path, std::int64_t line, std::string message) {
  return make_error(ErrorCode::kParse, std::move(message), path.string(), line);
}

// Reads all of `path` into lines.
Expected<std::vector<std::string>> read_lines(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kIo, fmt::format("cannot open '{}'", path.string()), path.string());
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

}  // namespace

Expected<LegacyMesh> read_legacy_mesh(const std::filesystem::path& path) {
  auto lines = read_lines(path);
  if (!lines) return std::unexpected(lines.error());
  LegacyMesh out;
  for (std::size_t l = 0; l < lines->size(); ++l) {
    const auto line_no = static_cast<std::int64_t>(l + 1);
    const auto tok = blank_separated_words((*lines)[l]);
    if (tok.empty() || tok[0].starts_with('#')) continue;
    // `tetra` and `triangle` are kept; other element kinds are counted.
    std::size_t count = 0;
    if (tok[0] == "tetra")
      count = 4;
    else if (tok[0] == "triangle")
      count = 3;
    if (count == 0) {
      ++out.ignored_lines;
      continue;
    }
    if (tok.size() < count + 1)
      return error_at(path, line_no, fmt::format("'{}' needs {} node indices", tok[0], count));
    std::array<std::int32_t, 4> idx{};
    for (std::size_t k = 0; k < count; ++k) {
      if (!parse_token(tok[k + 1], idx[k]) || idx[k] < 0)
        return error_at(path, line_no, fmt::format("'{}' is not a node index", tok[k + 1]));
    }
    if (count == 4)
      out.tets.push_back({idx[0], idx[1], idx[2], idx[3]});
    else
      out.triangles.push_back({idx[0], idx[1], idx[2]});
  }
  return out;
}

Expected<Xs3File> read_xs3(const std::filesystem::path& path) {
  auto lines = read_lines(path);
  if (!lines) return std::unexpected(lines.error());
  Xs3File out;
  bool header = false;
  std::int64_t declared = -1;
  for (std::size_t l = 0; l < lines->size(); ++l) {
    const auto line_no = static_cast<std::int64_t>(l + 1);
    const auto tok = blank_separated_words((*lines)[l]);
    if (tok.empty() || tok[0].starts_with('#')) continue;
    if (tok[0] == "Xsp") {
      header = true;
      continue;
    }
    if (!header) return error_at(path, line_no, "not an Xsp file (no 'Xsp' header)");
    if (tok[0] == "numm") {
      if (tok.size() < 2 || !parse_token(tok[1], declared) || declared < 0)
        return error_at(path, line_no, "'numm' needs a count");
    } else if (tok[0] == "mass") {
      // mass <id> <s|f> x y z vx vy vz m fixed
      if (tok.size() < 10) return error_at(path, line_no, "'mass' line needs at least 10 fields");
      std::array<double, 7> v{};
      for (std::size_t k = 0; k < 7; ++k) {
        if (!parse_token(tok[k + 3], v[k]))
          return error_at(path, line_no, fmt::format("'{}' is not a number", tok[k + 3]));
      }
      out.positions.emplace_back(v[0], v[1], v[2]);
      out.velocities.emplace_back(v[3], v[4], v[5]);
      out.masses.push_back(v[6]);
      int fixed = 0;
      if (tok.size() > 10 && !parse_token(tok[10], fixed))
        return error_at(path, line_no, fmt::format("'{}' is not a 0/1 flag", tok[10]));
      out.fixed.push_back(fixed != 0);
    } else if (tok[0] == "lspg" || tok[0] == "spg") {
      ++out.springs;
    }
    // nums, grav, visc, step and other global lines carry nothing a mechanical state needs.
  }
  if (!header) return error_at(path, 1, "not an Xsp file (no 'Xsp' header)");
  if (declared >= 0 && declared != static_cast<std::int64_t>(out.positions.size()))
    return error_at(path, 0, fmt::format("'numm' says {} masses but the file has {}", declared, out.positions.size()));
  return out;
}

}  // namespace hof::scene::detail
