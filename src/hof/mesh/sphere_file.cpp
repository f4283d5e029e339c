#include "hof/mesh/sphere_file.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "hof/core/text.h"
#include "hof/mesh/detail/text_reader.h"

namespace hof::mesh {

namespace {

std::optional<double> number_of(std::string_view word) {
  double v = 0.0;
  const auto r = std::from_chars(word.data(), word.data() + word.size(), v);
  if (r.ec != std::errc() || r.ptr != word.data() + word.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

Expected<SphereSet> parse_sph(std::string_view text, const std::filesystem::path& path) {
  const std::string file = path.string();
  const auto fail = [&](std::int64_t line, std::string message) {
    return make_error(ErrorCode::kParse, std::move(message), file, line);
  };
  SphereSet out;
  std::optional<long long> announced;
  std::int64_t announced_line = 0;
  bool header = false;
  std::int64_t line_number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (line_number == 1 && line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const std::vector<std::string_view> w = blank_separated_words(line);
    if (w.empty()) continue;
    if (!header) {
      if (w.size() != 2 || w[0] != "sph" || w[1] != "1.0") {
        return fail(line_number,
                    fmt::format("not a sphere file: expected the header 'sph 1.0', found '{} ...'", std::string(w[0])));
      }
      header = true;
      continue;
    }
    if (w[0] == "nums") {
      long long n = -1;
      const bool whole = w.size() == 2 && [&] {
        const auto r = std::from_chars(w[1].data(), w[1].data() + w[1].size(), n);
        return r.ec == std::errc() && r.ptr == w[1].data() + w[1].size();
      }();
      if (!whole || n < 0) {
        return fail(line_number, "'nums' needs one whole number of spheres, ≥ 0");
      }
      announced = n;
      announced_line = line_number;
    } else if (w[0] == "sphe") {
      if (w.size() != 6) {
        return fail(line_number, fmt::format("'sphe' needs 5 values (index, x, y, z, radius), found {}", w.size() - 1));
      }
      double v[5]{};
      for (std::size_t k = 0; k < 5; ++k) {
        const auto n = number_of(w[k + 1]);
        if (!n) return fail(line_number, fmt::format("'{}' is not a finite number", std::string(w[k + 1])));
        v[k] = *n;
      }
      if (!(v[4] > 0.0)) return fail(line_number, fmt::format("sphere radius {} is not positive", v[4]));
      out.centers.emplace_back(v[1], v[2], v[3]);
      out.radii.push_back(v[4]);
    } else {
      return fail(line_number, fmt::format("unknown keyword '{}' (a sphere file has sph, nums, sphe and # comments)",
                                           std::string(w[0])));
    }
  }
  if (!header) return fail(1, "not a sphere file: empty (expected the header 'sph 1.0')");
  if (announced && static_cast<std::size_t>(*announced) != out.centers.size()) {
    return fail(announced_line, fmt::format("'nums {}' but the file has {} spheres", *announced, out.centers.size()));
  }
  if (out.centers.empty()) return fail(line_number, "the file has no sphere ('sphe' lines)");
  return out;
}

Expected<SphereSet> read_sph(const std::filesystem::path& path) {
  auto text = detail::read_whole_file(path);
  if (!text) return std::unexpected(text.error());
  return parse_sph(*text, path);
}

}  // namespace hof::mesh
