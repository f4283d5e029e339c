#include "hof/haptics/device_backends/replay_device.h"
#include "hof/core/text.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string>
#include <string_view>

namespace hof::haptics {
namespace {

// ---------------------------------------------------------------------------------------
// CSV helpers

enum class Column : std::uint8_t { kT, kX, kY, kZ, kQw, kQx, kQy, kQz, kButton };
constexpr std::array<std::string_view, 9> kColumnNames{"t", "x", "y", "z", "qw", "qx", "qy", "qz", "button"};

/// The line without its comment, trimmed.
std::string_view content(std::string_view line) {
  if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
  return trim_whitespace(line);
}

/// Splits on ',' into `out` (trimmed fields).
void split_fields(std::string_view s, std::vector<std::string_view>& out) {
  out.clear();
  while (true) {
    const auto comma = s.find(',');
    out.push_back(trim_whitespace(s.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    s.remove_prefix(comma + 1);
  }
}

struct Parser {
  const std::filesystem::path& path;

  std::unexpected<Error> fail(std::int64_t line, std::string message) const {
    return make_error(ErrorCode::kParse, "replay: " + std::move(message), path.string(), line);
  }
};

// ---------------------------------------------------------------------------------------
// Header: "t" first, then x, y, z and the optional columns in any order.

Expected<std::vector<Column>> parse_header(const Parser& p, std::int64_t line_no,
                                           const std::vector<std::string_view>& fields) {
  if (fields.front() != "t") {
    return p.fail(line_no, fmt::format("the header must start with column 't' (found '{}')", fields.front()));
  }
  std::vector<Column> columns;
  std::array<bool, kColumnNames.size()> seen{};
  for (const std::string_view name : fields) {
    const auto it = std::find(kColumnNames.begin(), kColumnNames.end(), name);
    if (it == kColumnNames.end()) {
      return p.fail(line_no, fmt::format("unknown column '{}' (expected t, x, y, z, qw, qx, qy, qz, button)", name));
    }
    const auto index = static_cast<std::size_t>(it - kColumnNames.begin());
    if (seen[index]) return p.fail(line_no, fmt::format("duplicate column '{}'", name));
    if (index == 0 && !columns.empty()) return p.fail(line_no, "column 't' must come first");
    seen[index] = true;
    columns.push_back(static_cast<Column>(index));
  }
  for (const Column c : {Column::kX, Column::kY, Column::kZ}) {
    if (!seen[static_cast<std::size_t>(c)]) {
      return p.fail(line_no, fmt::format("missing column '{}'", kColumnNames[static_cast<std::size_t>(c)]));
    }
  }
  const int quaternion_columns = int{seen[4]} + int{seen[5]} + int{seen[6]} + int{seen[7]};
  if (quaternion_columns != 0 && quaternion_columns != 4) {
    return p.fail(line_no, "the orientation needs all four columns qw, qx, qy, qz");
  }
  return columns;
}

// ---------------------------------------------------------------------------------------
// Rows

Expected<ReplaySample> parse_row(const Parser& p, std::int64_t line_no, const std::vector<Column>& columns,
                                 const std::vector<std::string_view>& fields) {
  if (fields.size() != columns.size()) {
    return p.fail(line_no, fmt::format("expected {} columns, found {}", columns.size(), fields.size()));
  }
  ReplaySample s;
  Eigen::Vector4d q(1.0, 0.0, 0.0, 0.0);  // w, x, y, z
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const std::string_view text = fields[i];
    const std::string_view name = kColumnNames[static_cast<std::size_t>(columns[i])];
    if (columns[i] == Column::kButton) {
      std::uint32_t mask = 0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), mask);
      if (ec != std::errc{} || end != text.data() + text.size() || text.empty()) {
        return p.fail(line_no, fmt::format("bad button mask '{}' (expected an unsigned integer)", text));
      }
      s.buttons = mask;
      continue;
    }
    double value = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc{} || end != text.data() + text.size() || text.empty()) {
      return p.fail(line_no, fmt::format("bad number '{}' in column '{}'", text, name));
    }
    if (!std::isfinite(value)) {
      return p.fail(line_no, fmt::format("non-finite value '{}' (NaN or infinity) in column '{}'", text, name));
    }
    switch (columns[i]) {
      case Column::kT:
        s.t_s = value;
        break;
      case Column::kX:
        s.position_m.x() = value;
        break;
      case Column::kY:
        s.position_m.y() = value;
        break;
      case Column::kZ:
        s.position_m.z() = value;
        break;
      case Column::kQw:
        q[0] = value;
        break;
      case Column::kQx:
        q[1] = value;
        break;
      case Column::kQy:
        q[2] = value;
        break;
      case Column::kQz:
        q[3] = value;
        break;
      case Column::kButton:
        break;
    }
  }
  const double norm = q.norm();
  if (!(norm > 1e-9) || !std::isfinite(norm)) return p.fail(line_no, "the orientation quaternion has zero length");
  q /= norm;
  s.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  return s;
}

}  // namespace

Expected<std::vector<ReplaySample>> load_replay(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    std::error_code ec;
    const bool exists = std::filesystem::exists(path, ec);
    return make_error(ErrorCode::kIo, exists ? "replay: cannot open the file" : "replay: no such file", path.string());
  }
  const Parser p{path};

  std::vector<ReplaySample> samples;
  std::vector<Column> columns;
  std::vector<std::string_view> fields;
  std::string line;
  std::int64_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string_view text = content(line);
    if (text.empty()) continue;
    split_fields(text, fields);
    if (columns.empty()) {
      auto header = parse_header(p, line_no, fields);
      if (!header) return std::unexpected(header.error());
      columns = std::move(*header);
      continue;
    }
    auto sample = parse_row(p, line_no, columns, fields);
    if (!sample) return std::unexpected(sample.error());
    if (!samples.empty() && !(sample->t_s > samples.back().t_s)) {
      return p.fail(line_no,
                    fmt::format("time {} is not after the previous sample's time {}", sample->t_s, samples.back().t_s));
    }
    samples.push_back(*sample);
  }
  if (in.bad()) return make_error(ErrorCode::kIo, "replay: read error", path.string(), line_no);
  if (columns.empty()) return p.fail(0, "no header line (expected 't,x,y,z[,qw,qx,qy,qz][,button]')");
  if (samples.empty()) return p.fail(0, "no samples after the header");
  return samples;
}

// ---------------------------------------------------------------------------------------
// ReplayDevice

ReplayDevice::ReplayDevice(std::vector<ReplaySample> samples, bool loop, const DeviceSpec& spec)
    : spec_(spec), samples_(std::move(samples)), loop_(loop) {}

Expected<std::unique_ptr<ReplayDevice>> ReplayDevice::open(const std::filesystem::path& path, bool loop,
                                                           const DeviceSpec& spec) {
  auto samples = load_replay(path);
  if (!samples) return std::unexpected(samples.error());
  return std::make_unique<ReplayDevice>(std::move(*samples), loop, spec);
}

DeviceReading ReplayDevice::read(double time_s) {
  DeviceReading r;
  r.time_s = time_s;
  const ReplaySample& first = samples_.front();
  const ReplaySample& last = samples_.back();
  const double period = last.t_s - first.t_s;

  // Looping folds the time into [first, last); without it, the end is the end.
  double t = time_s;
  if (loop_ && t > last.t_s && period > 0.0) t = first.t_s + std::fmod(t - first.t_s, period);
  if (t > last.t_s) {
    r.position_m = last.position_m;
    r.orientation = last.orientation;
    r.buttons = last.buttons;
    r.valid = false;
    health_.store(DeviceHealth::kEnded, std::memory_order_release);
    return r;
  }
  health_.store(DeviceHealth::kOk, std::memory_order_release);
  r.valid = true;
  if (!(t >= first.t_s) || samples_.size() == 1) {  // before the start (or NaN): hold the first
    r.position_m = first.position_m;
    r.orientation = first.orientation;
    r.buttons = first.buttons;
    r.valid = !std::isnan(t);
    return r;
  }

  // The segment [a, b] with a.t ≤ t < b.t (the last segment at t = last.t).
  const auto after = std::upper_bound(samples_.begin(), samples_.end(), t,
                                      [](double value, const ReplaySample& s) { return value < s.t_s; });
  const std::size_t j =
      after == samples_.end() ? samples_.size() - 1 : static_cast<std::size_t>(after - samples_.begin());
  const ReplaySample& a = samples_[j - 1];
  const ReplaySample& b = samples_[j];
  const double dt = b.t_s - a.t_s;
  const double u = (t - a.t_s) / dt;
  r.velocity_m_per_s = (b.position_m - a.position_m) / dt;
  if (t >= b.t_s) {  // exactly the last sample
    r.position_m = b.position_m;
    r.orientation = b.orientation;
    r.buttons = b.buttons;
    return r;
  }
  r.position_m = a.position_m + u * (b.position_m - a.position_m);
  r.orientation = a.orientation.slerp(u, b.orientation);
  r.buttons = a.buttons;
  return r;
}

void ReplayDevice::write_force(const Vec3& /*force_n*/, const Vec3& /*torque_n_m*/) {}

}  // namespace hof::haptics
