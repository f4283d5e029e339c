// parse_device_spec(): spec strings into a typed DeviceConfig (device_config.h), and the
// transitional open_device(string) = parse + open. Strings end here: each backend gets a typed
// config. This file is bound for scene/ (scene/device_config.h is already the callers' door):
// it stays below coupling only while coupling's SetDevice carries a spec string.
//
//   SPEC    := BACKEND [':' ARGUMENT] (',' OPTION)*
//   OPTION  := KEY ['=' VALUE]          (a bare KEY is a flag)
//   VECTOR  := NUMBER ';' NUMBER ';' NUMBER
//
// ARGUMENT runs to the first ',' (a replay path cannot contain ','). Every error message
// starts with "device spec 'SPEC': ".

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "hof/core/text.h"
#include "hof/haptics/device.h"
#include "hof/haptics/device_config.h"
#include "hof/haptics/device_backends/dhd_device.h"
#include "hof/haptics/device_backends/openhaptics_device.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/haptics/device_backends/spacemouse_device.h"
#include "hof/haptics/device_backends/udp_device.h"
#include "hof/haptics/device_backends/virtual_hand_device.h"

namespace hof::haptics {

Expected<DeviceSpec> device_spec_for_model(std::string_view model) {
  DeviceSpec s;
  if (model == "virtual") return s;
  s.model = std::string(model);
  // {max force N, max stiffness N/m, max damping N·s/m, workspace radius m}
  std::array<double, 4> figures{};
  if (model == "falcon") {
    figures = {8.0, 3000.0, 20.0, 0.04};
  } else if (model == "omni") {
    figures = {3.3, 700.0, 5.0, 0.10};
  } else if (model == "touch") {
    figures = {3.3, 400.0, 4.0, 0.075};
  } else {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("unknown device model '{}' (known: virtual, falcon, omni, touch)", model));
  }
  s.max_force_n = figures[0];
  s.max_stiffness_n_per_m = figures[1];
  s.max_damping_n_s_per_m = figures[2];
  s.workspace_radius_m = figures[3];
  return s;
}

namespace {

constexpr double kHoldForever = std::numeric_limits<double>::infinity();

struct Option {
  std::string_view key;
  std::string_view value;
  bool has_value{false};
};

/// Splits and converts the parts of one spec string; every error names the spec.
class SpecParser {
 public:
  explicit SpecParser(std::string_view spec) : spec_(spec) {}

  std::unexpected<Error> fail(ErrorCode code, const std::string& what) const {
    return make_error(code, fmt::format("device spec '{}': {}", spec_, what));
  }
  std::unexpected<Error> fail(const std::string& what) const { return fail(ErrorCode::kInvalidArgument, what); }
  std::unexpected<Error> wrap(const Error& e) const {
    Error out = e;
    out.message = fmt::format("device spec '{}': {}", spec_, e.message);
    return std::unexpected(std::move(out));
  }

  /// Backend, argument and options; duplicate or empty options are errors.
  Expected<void> split() {
    std::string_view rest = spec_;
    const auto head_end = rest.find_first_of(":,");
    backend_ = trim_whitespace(rest.substr(0, head_end));
    if (head_end == std::string_view::npos) return {};
    if (rest[head_end] == ':') {
      has_argument_ = true;
      rest.remove_prefix(head_end + 1);
      const auto comma = rest.find(',');
      argument_ = trim_whitespace(rest.substr(0, comma));
      if (comma == std::string_view::npos) return {};
      rest.remove_prefix(comma);
    } else {
      rest.remove_prefix(head_end);
    }
    while (!rest.empty()) {  // rest starts with ','
      rest.remove_prefix(1);
      const auto comma = rest.find(',');
      const std::string_view token = trim_whitespace(rest.substr(0, comma));
      rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma);
      if (token.empty()) return fail("empty option (two commas in a row or a trailing comma)");
      Option o;
      const auto eq = token.find('=');
      o.key = trim_whitespace(token.substr(0, eq));
      if (eq != std::string_view::npos) {
        o.value = trim_whitespace(token.substr(eq + 1));
        o.has_value = true;
      }
      if (o.key.empty()) return fail(fmt::format("option '{}' has no key", token));
      for (const Option& seen : options_) {
        if (seen.key == o.key) return fail(fmt::format("key '{}' is given twice", o.key));
      }
      options_.push_back(o);
    }
    return {};
  }

  [[nodiscard]] std::string_view backend() const { return backend_; }
  [[nodiscard]] bool has_argument() const { return has_argument_; }
  [[nodiscard]] std::string_view argument() const { return argument_; }
  [[nodiscard]] const std::vector<Option>& options() const { return options_; }

  Expected<double> number(const Option& o) const {
    if (!o.has_value || o.value.empty()) return fail(fmt::format("key '{}' needs a number (e.g. {}=0.01)", o.key, o.key));
    double v = 0.0;
    const auto [end, ec] = std::from_chars(o.value.data(), o.value.data() + o.value.size(), v);
    if (ec != std::errc{} || end != o.value.data() + o.value.size() || !std::isfinite(v)) {
      return fail(fmt::format("bad value '{}' for key '{}' (expected a finite number)", o.value, o.key));
    }
    return v;
  }

  Expected<Vec3> vector(const Option& o) const {
    Vec3 v;
    std::string_view text = o.value;
    const auto bad = [&] {
      return fail(fmt::format("bad value '{}' for key '{}' (expected three numbers x;y;z)", o.value, o.key));
    };
    if (!o.has_value) return bad();
    for (int i = 0; i < 3; ++i) {
      const auto semi = text.find(';');
      const bool last = i == 2;
      if (last != (semi == std::string_view::npos)) return bad();  // exactly two ';'
      auto c = number(Option{o.key, trim_whitespace(text.substr(0, semi)), true});
      if (!c) return bad();
      v[i] = *c;
      if (!last) text.remove_prefix(semi + 1);
    }
    return v;
  }

  Expected<bool> flag(const Option& o) const {
    if (!o.has_value || o.value == "true" || o.value == "1" || o.value == "yes") return true;
    if (o.value == "false" || o.value == "0" || o.value == "no") return false;
    return fail(fmt::format("bad value '{}' for key '{}' (expected true or false)", o.value, o.key));
  }

  /// repeat: a bare key, "forever" or 0 → forever; else the number of cycles.
  Expected<std::uint32_t> repeat(const Option& o) const {
    if (!o.has_value || o.value == "forever") return 0U;
    std::uint32_t n = 0;
    const auto [end, ec] = std::from_chars(o.value.data(), o.value.data() + o.value.size(), n);
    if (ec != std::errc{} || end != o.value.data() + o.value.size() || o.value.empty()) {
      return fail(fmt::format("bad value '{}' for key 'repeat' (expected a count of cycles or 'forever')", o.value));
    }
    return n;
  }

  Expected<void> unknown_key(const Option& o, std::string_view what, std::span<const std::string_view> keys) const {
    std::string list;
    for (const std::string_view k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
    return fail(fmt::format("unknown key '{}' for {} (known: {})", o.key, what, list));
  }

 private:
  std::string_view spec_;
  std::string_view backend_;
  std::string_view argument_;
  bool has_argument_{false};
  std::vector<Option> options_;
};

bool contains(std::span<const std::string_view> keys, std::string_view key) {
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

// ---------------------------------------------------------------------------------------
// Keys shared by the simulated backends

constexpr std::string_view kMotions = "poke, press-and-slide, palpate, circle, hold";

Expected<MotionKind> motion_kind(const SpecParser& p, std::string_view name) {
  if (name == "poke") return MotionKind::kPoke;
  if (name == "press-and-slide") return MotionKind::kPressAndSlide;
  if (name == "circle") return MotionKind::kCircle;
  if (name == "palpate") return MotionKind::kPalpate;
  if (name == "hold") return MotionKind::kHold;
  if (name.empty()) return p.fail(fmt::format("missing motion (one of {})", kMotions));
  return p.fail(fmt::format("unknown motion '{}' (known: {})", name, kMotions));
}

std::span<const std::string_view> motion_keys(MotionKind kind) {
  static constexpr std::string_view kPoke[] = {"start", "direction", "approach", "depth", "speed", "hold", "repeat", "force"};
  static constexpr std::string_view kSlide[] = {"start", "direction", "approach", "depth",       "speed", "hold",
                                                "repeat", "slide",    "distance", "slide_speed"};
  static constexpr std::string_view kPalpate[] = {"start", "direction", "approach", "depth", "speed",
                                                  "hold",  "repeat",    "step",     "count"};
  static constexpr std::string_view kCircle[] = {"centre", "center", "normal", "radius", "period", "repeat"};
  static constexpr std::string_view kHold[] = {"start", "hold", "repeat"};
  switch (kind) {
    case MotionKind::kPoke: return kPoke;
    case MotionKind::kPressAndSlide: return kSlide;
    case MotionKind::kCircle: return kCircle;
    case MotionKind::kHold: return kHold;
    case MotionKind::kPalpate: return kPalpate;
  }
  return {};
}

/// Applies one motion key (already known to belong to the motion) to `c`.
Expected<void> apply_motion_key(const SpecParser& p, const Option& o, MotionConfig& c) {
  const auto set = [&](double& field) -> Expected<void> {
    auto v = p.number(o);
    if (!v) return std::unexpected(v.error());
    field = *v;
    return {};
  };
  const auto set_vec = [&](Vec3& field) -> Expected<void> {
    auto v = p.vector(o);
    if (!v) return std::unexpected(v.error());
    field = *v;
    return {};
  };
  const std::string_view k = o.key;
  if (k == "start") return set_vec(c.start_m);
  if (k == "direction") return set_vec(c.direction);
  if (k == "approach") return set(c.approach_m);
  if (k == "depth") return set(c.depth_m);
  if (k == "speed") return set(c.speed_m_per_s);
  if (k == "hold") {
    if (o.value == "forever" || o.value == "inf") {
      c.hold_s = kHoldForever;
      return {};
    }
    return set(c.hold_s);
  }
  if (k == "force") return set(c.stop_force_n);
  if (k == "slide") return set_vec(c.slide_direction);
  if (k == "distance") return set(c.slide_distance_m);
  if (k == "slide_speed") return set(c.slide_speed_m_per_s);
  if (k == "step") return set_vec(c.palpation_step_m);
  if (k == "count") {
    double count = 0.0;
    if (auto r = set(count); !r) return r;
    if (!(count >= 1.0 && count <= static_cast<double>(kMaxPalpationPresses)) || count != std::floor(count)) {
      return p.fail(fmt::format("count={}: a whole number of presses from 1 to {}", o.value, kMaxPalpationPresses));
    }
    c.palpation_count = static_cast<std::uint32_t>(count);
    return {};
  }
  if (k == "centre" || k == "center") return set_vec(c.centre_m);
  if (k == "normal") return set_vec(c.normal);
  if (k == "radius") return set(c.radius_m);
  if (k == "period") return set(c.period_s);
  if (k == "repeat") {
    auto n = p.repeat(o);
    if (!n) return std::unexpected(n.error());
    c.repeat = *n;
  }
  return {};
}

Expected<void> apply_model(const SpecParser& p, const Option& o, DeviceSpec& spec) {
  auto s = device_spec_for_model(o.has_value ? o.value : std::string_view{});
  if (!s) return p.wrap(s.error());
  spec = *s;
  return {};
}

// ---------------------------------------------------------------------------------------
// Backends

Expected<DeviceConfig> parse_replay(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"loop", "model"};
  if (p.argument().empty()) return p.fail("missing file (replay:PATH.csv)");
  bool loop = false;
  DeviceSpec spec;
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "loop") {
      auto f = p.flag(o);
      if (!f) return std::unexpected(f.error());
      loop = *f;
    } else if (o.key == "model") {
      r = apply_model(p, o, spec);
    } else {
      r = p.unknown_key(o, "replay", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return ReplayConfig{std::filesystem::path(std::string(p.argument())), loop, spec};
}

/// Motion, hand parameters and spec of `scripted:` and `virtual-hand:` specs.
struct SimulatedConfig {
  MotionConfig motion;
  VirtualHandParams hand;
  DeviceSpec spec;
};

Expected<SimulatedConfig> parse_simulated(const SpecParser& p, bool hand) {
  static constexpr std::string_view kHandKeys[] = {"mass",    "stiffness",  "damping", "device_damping",
                                                    "substep", "integrator", "model"};
  SimulatedConfig c;
  auto kind = motion_kind(p, p.argument());
  if (!kind) return std::unexpected(kind.error());
  c.motion.kind = *kind;
  if (*kind == MotionKind::kHold) c.motion.hold_s = kHoldForever;  // a held target stays unless told
  const auto keys = motion_keys(*kind);
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (contains(keys, o.key)) {
      r = apply_motion_key(p, o, c.motion);
    } else if (o.key == "model") {
      r = apply_model(p, o, c.spec);
    } else if (hand && o.key == "integrator") {
      if (o.value == "euler") {
        c.hand.integrator = HandIntegrator::kSemiImplicitEuler;
      } else if (o.value == "exact") {
        c.hand.integrator = HandIntegrator::kExactZeroOrderHold;
      } else {
        return p.fail(fmt::format("bad value '{}' for key 'integrator' (expected euler or exact)", o.value));
      }
    } else if (hand && contains(kHandKeys, o.key)) {
      auto v = p.number(o);
      if (!v) return std::unexpected(v.error());
      if (o.key == "mass") c.hand.mass_kg = *v;
      if (o.key == "stiffness") c.hand.stiffness_n_per_m = *v;
      if (o.key == "damping") c.hand.damping_n_s_per_m = *v;
      if (o.key == "device_damping") c.hand.device_damping_n_s_per_m = *v;
      if (o.key == "substep") c.hand.substep_s = *v;
    } else {
      std::vector<std::string_view> known(keys.begin(), keys.end());
      if (hand) known.insert(known.end(), std::begin(kHandKeys), std::end(kHandKeys));
      else known.push_back("model");
      r = p.unknown_key(o, fmt::format("{} {}", hand ? "virtual-hand" : "scripted", p.argument()), known);
    }
    if (!r) return std::unexpected(r.error());
  }
  return c;
}

Expected<DeviceConfig> parse_scripted(const SpecParser& p, bool hand) {
  auto c = parse_simulated(p, hand);
  if (!c) return std::unexpected(c.error());
  if (!hand) return ScriptedConfig{c->motion, c->spec};
  return VirtualHandConfig{c->motion, c->hand, c->spec};
}

Expected<DeviceConfig> parse_udp(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"timeout", "hello_wait", "key", "model"};
  UdpDeviceConfig config;
  const std::string_view arg = p.argument();
  if (arg.empty()) return p.fail("missing port (udp:PORT or udp:HOST:PORT)");
  const auto colon = arg.rfind(':');
  const std::string_view port_text = colon == std::string_view::npos ? arg : arg.substr(colon + 1);
  if (colon != std::string_view::npos) {
    config.host = std::string(arg.substr(0, colon));
    if (config.host.empty()) return p.fail("empty host before ':' (udp:HOST:PORT)");
  }
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), config.port);
  if (ec != std::errc{} || end != port_text.data() + port_text.size() || port_text.empty()) {
    return p.fail(fmt::format("bad port '{}' (expected 0 to 65535)", port_text));
  }
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "timeout" || o.key == "hello_wait") {
      auto v = p.number(o);
      if (!v) return std::unexpected(v.error());
      (o.key == "timeout" ? config.timeout_s : config.hello_wait_s) = *v;
    } else if (o.key == "model") {
      r = apply_model(p, o, config.spec);
    } else if (o.key == "key") {
      if (o.value.empty()) return p.fail("key needs a file (key=FILE; make one with `hof device keygen FILE`)");
      auto key = udp::read_key_file(std::string(o.value));
      if (!key) return p.fail(key.error().to_string());
      config.key = *key;
    } else {
      r = p.unknown_key(o, "udp", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return config;
}

Expected<DeviceConfig> parse_spacemouse(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"scale", "model"};
  if (p.has_argument()) return p.fail(fmt::format("spacemouse takes no argument (got '{}')", p.argument()));
  SpacemouseConfig config;
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "scale") {
      auto v = p.number(o);
      if (!v) return std::unexpected(v.error());
      config.scale_m_per_unit_s = *v;
    } else if (o.key == "model") {
      r = apply_model(p, o, config.spec);
    } else {
      r = p.unknown_key(o, "spacemouse", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return config;
}

Expected<DeviceConfig> parse_mouse(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"model"};
  if (p.has_argument()) return p.fail(fmt::format("mouse takes no argument (got '{}')", p.argument()));
  DeviceSpec spec;
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "model") {
      r = apply_model(p, o, spec);
    } else {
      r = p.unknown_key(o, "mouse", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return MouseConfig{spec};
}

Expected<DeviceConfig> parse_dhd(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"index", "library", "model"};
  if (p.has_argument()) return p.fail(fmt::format("dhd takes no argument (got '{}'; index=N chooses a device)", p.argument()));
  DhdConfig config;
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "index") {
      auto v = p.number(o);
      if (!v) return std::unexpected(v.error());
      if (*v < 0.0 || *v > 127.0 || *v != std::floor(*v)) return p.fail(fmt::format("index={}: a device number from 0", o.value));
      config.index = static_cast<int>(*v);
    } else if (o.key == "library") {
      config.library = std::string(o.value);
    } else if (o.key == "model") {
      auto known = device_spec_for_model(o.value);
      if (!known) return p.wrap(known.error());
      config.model = *known;
    } else {
      r = p.unknown_key(o, "dhd", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return config;
}

Expected<DeviceConfig> parse_openhaptics(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"device", "library", "model"};
  if (p.has_argument()) return p.fail(fmt::format("openhaptics takes no argument (got '{}'; device=NAME chooses one)", p.argument()));
  OpenHapticsConfig config;
  for (const Option& o : p.options()) {
    Expected<void> r;
    if (o.key == "device") {
      config.device = std::string(o.value);
    } else if (o.key == "library") {
      config.library = std::string(o.value);
    } else if (o.key == "model") {
      auto known = device_spec_for_model(o.value);
      if (!known) return p.wrap(known.error());
      config.model = *known;
    } else {
      r = p.unknown_key(o, "openhaptics", kKeys);
    }
    if (!r) return std::unexpected(r.error());
  }
  return config;
}

}  // namespace

Expected<DeviceConfig> parse_device_spec(std::string_view spec) {
  SpecParser p(spec);
  if (auto split = p.split(); !split) return std::unexpected(split.error());
  const std::string_view backend = p.backend();
  if (backend == "replay") return parse_replay(p);
  if (backend == "scripted") return parse_scripted(p, false);
  if (backend == "virtual-hand") return parse_scripted(p, true);
  if (backend == "udp") return parse_udp(p);
  if (backend == "spacemouse") return parse_spacemouse(p);
  if (backend == "mouse") return parse_mouse(p);
  if (backend == "dhd") return parse_dhd(p);
  if (backend == "openhaptics") return parse_openhaptics(p);
  constexpr std::string_view kKnown = "replay, scripted, virtual-hand, udp, spacemouse, mouse, dhd, openhaptics";
  if (backend.empty()) return p.fail(fmt::format("empty backend (known: {})", kKnown));
  return p.fail(fmt::format("unknown backend '{}' (known: {})", backend, kKnown));
}

Expected<std::unique_ptr<Device>> open_device(std::string_view spec) {
  auto config = parse_device_spec(spec);
  if (!config) return std::unexpected(config.error());
  auto device = open_device(*config);
  // A replay file's and the SpaceMouse's errors name what failed themselves (the file and
  // line, spnav's own message); the others say which spec they came from.
  const bool names_itself = std::holds_alternative<ReplayConfig>(*config) || std::holds_alternative<SpacemouseConfig>(*config);
  if (!device && !names_itself) {
    Error e = device.error();
    e.message = fmt::format("device spec '{}': {}", spec, e.message);
    return std::unexpected(std::move(e));
  }
  return device;
}

}  // namespace hof::haptics
