// parse_device_spec(): spec strings into a typed haptics::DeviceConfig, and open_device(string)
// = parse + open. Strings end here: each backend gets a typed config (haptics opens it).
//
//   SPEC    := BACKEND [':' ARGUMENT] (',' OPTION)*
//   OPTION  := KEY ['=' VALUE]          (a bare KEY is a flag)
//   VECTOR  := NUMBER ';' NUMBER ';' NUMBER
//
// ARGUMENT runs to the first ',' (a replay path cannot contain ','). Every error message
// starts with "device spec 'SPEC': ".

#include "hof/scene/device_config.h"

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

namespace hof::scene {

using haptics::DeviceConfig;
using haptics::DeviceModel;
using haptics::DeviceSpec;
using haptics::kMaxPalpationPresses;
using haptics::MotionConfig;
using haptics::MotionKind;
namespace udp = haptics::udp;

Expected<DeviceSpec> device_spec_for_model(std::string_view model) {
  static constexpr std::array<std::pair<std::string_view, DeviceModel>, 4> kModels{{
      {"virtual", DeviceModel::kVirtual},
      {"falcon", DeviceModel::kFalcon},
      {"omni", DeviceModel::kOmni},
      {"touch", DeviceModel::kTouch},
  }};
  for (const auto& [name, known] : kModels) {
    if (name == model) return haptics::device_spec_for_model(known);
  }
  return make_error(ErrorCode::kInvalidArgument,
                    fmt::format("unknown device model '{}' (known: virtual, falcon, omni, touch)", model));
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
    if (!o.has_value || o.value.empty())
      return fail(fmt::format("key '{}' needs a number (e.g. {}=0.01)", o.key, o.key));
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
  static constexpr std::string_view kPoke[] = {"start", "direction", "approach", "depth",
                                               "speed", "hold",      "repeat",   "force"};
  static constexpr std::string_view kSlide[] = {"start", "direction", "approach", "depth",    "speed",
                                                "hold",  "repeat",    "slide",    "distance", "slide_speed"};
  static constexpr std::string_view kPalpate[] = {"start", "direction", "approach", "depth", "speed",
                                                  "hold",  "repeat",    "step",     "count"};
  static constexpr std::string_view kCircle[] = {"centre", "center", "normal", "radius", "period", "repeat"};
  static constexpr std::string_view kHold[] = {"start", "hold", "repeat"};
  switch (kind) {
    case MotionKind::kPoke:
      return kPoke;
    case MotionKind::kPressAndSlide:
      return kSlide;
    case MotionKind::kCircle:
      return kCircle;
    case MotionKind::kHold:
      return kHold;
    case MotionKind::kPalpate:
      return kPalpate;
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

// ---------------------------------------------------------------------------------------
// Keys every backend shares, and the loop over a backend's options

/// Where a backend takes the shared keys: model= sets `spec` (the simulated and network
/// backends) or `sdk_model` (an SDK's device, whose own figures count unless a model is given);
/// library= (the SDK backends) sets `library`. Null: the backend has no such key.
struct SharedKeys {
  DeviceSpec* spec{nullptr};
  std::optional<DeviceSpec>* sdk_model{nullptr};
  std::string* library{nullptr};
  /// What model=virtual gives `spec` (the mouse keeps its own name).
  DeviceSpec virtual_spec{};
};

/// Applies `o` when it is a shared key the backend takes; false when it is not one.
Expected<bool> apply_shared_key(const SpecParser& p, const Option& o, const SharedKeys& shared) {
  if (o.key == "model" && (shared.spec || shared.sdk_model)) {
    const std::string_view name = o.has_value ? o.value : std::string_view{};
    auto known = device_spec_for_model(name);
    if (!known) return p.wrap(known.error());
    if (shared.spec) *shared.spec = name == "virtual" ? shared.virtual_spec : *known;
    if (shared.sdk_model) *shared.sdk_model = *known;
    return true;
  }
  if (o.key == "library" && shared.library) {
    *shared.library = std::string(o.value);
    return true;
  }
  return false;
}

/// Every option of the spec: the shared keys, then `own` (Expected<bool>(const Option&): applies
/// one of the backend's own keys, false when the key is not its); any other key is an error
/// listing `keys` as what `what` knows.
template <typename Own>
Expected<void> apply_options(const SpecParser& p, std::string_view what, std::span<const std::string_view> keys,
                             const SharedKeys& shared, Own own) {
  for (const Option& o : p.options()) {
    auto done = apply_shared_key(p, o, shared);
    if (!done) return std::unexpected(done.error());
    if (*done) continue;
    auto mine = own(o);
    if (!mine) return std::unexpected(mine.error());
    if (!*mine) return p.unknown_key(o, what, keys);
  }
  return {};
}

/// The own keys of a backend that has none but the shared ones.
constexpr auto kNoOwnKeys = [](const Option&) -> Expected<bool> { return false; };

// ---------------------------------------------------------------------------------------
// Backends

Expected<DeviceConfig> parse_replay(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"loop", "model"};
  if (p.argument().empty()) return p.fail("missing file (replay:PATH.csv)");
  haptics::ReplayConfig config{std::filesystem::path(std::string(p.argument())), false, {}};
  auto ok = apply_options(p, "replay", kKeys, SharedKeys{.spec = &config.spec}, [&](const Option& o) -> Expected<bool> {
    if (o.key != "loop") return false;
    auto f = p.flag(o);
    if (!f) return std::unexpected(f.error());
    config.loop = *f;
    return true;
  });
  if (!ok) return std::unexpected(ok.error());
  return config;
}

/// Motion, hand parameters and spec of `scripted:` and `virtual-hand:` specs.
struct SimulatedConfig {
  MotionConfig motion;
  haptics::VirtualHandParams hand;
  DeviceSpec spec;
};

/// The virtual hand's own keys (hand parameters and its integrator).
Expected<bool> apply_hand_key(const SpecParser& p, const Option& o, haptics::VirtualHandParams& hand) {
  if (o.key == "integrator") {
    if (o.value == "euler") {
      hand.integrator = haptics::HandIntegrator::kSemiImplicitEuler;
    } else if (o.value == "exact") {
      hand.integrator = haptics::HandIntegrator::kExactZeroOrderHold;
    } else {
      return p.fail(fmt::format("bad value '{}' for key 'integrator' (expected euler or exact)", o.value));
    }
    return true;
  }
  double* field = o.key == "mass"             ? &hand.mass_kg
                  : o.key == "stiffness"      ? &hand.stiffness_n_per_m
                  : o.key == "damping"        ? &hand.damping_n_s_per_m
                  : o.key == "device_damping" ? &hand.device_damping_n_s_per_m
                  : o.key == "substep"        ? &hand.substep_s
                                              : nullptr;
  if (!field) return false;
  auto v = p.number(o);
  if (!v) return std::unexpected(v.error());
  *field = *v;
  return true;
}

Expected<SimulatedConfig> parse_simulated(const SpecParser& p, bool hand) {
  static constexpr std::string_view kHandKeys[] = {"mass",    "stiffness",  "damping", "device_damping",
                                                   "substep", "integrator", "model"};
  SimulatedConfig c;
  auto kind = motion_kind(p, p.argument());
  if (!kind) return std::unexpected(kind.error());
  c.motion.kind = *kind;
  if (*kind == MotionKind::kHold) c.motion.hold_s = kHoldForever;  // a held target stays unless told
  const auto keys = motion_keys(*kind);
  std::vector<std::string_view> known(keys.begin(), keys.end());
  if (hand)
    known.insert(known.end(), std::begin(kHandKeys), std::end(kHandKeys));
  else
    known.push_back("model");
  const std::string what = fmt::format("{} {}", hand ? "virtual-hand" : "scripted", p.argument());
  auto ok = apply_options(p, what, known, SharedKeys{.spec = &c.spec}, [&](const Option& o) -> Expected<bool> {
    if (contains(keys, o.key)) {
      if (auto r = apply_motion_key(p, o, c.motion); !r) return std::unexpected(r.error());
      return true;
    }
    return hand ? apply_hand_key(p, o, c.hand) : Expected<bool>(false);
  });
  if (!ok) return std::unexpected(ok.error());
  return c;
}

Expected<DeviceConfig> parse_scripted(const SpecParser& p, bool hand) {
  auto c = parse_simulated(p, hand);
  if (!c) return std::unexpected(c.error());
  if (!hand) return haptics::ScriptedConfig{c->motion, c->spec};
  return haptics::VirtualHandConfig{c->motion, c->hand, c->spec};
}

Expected<DeviceConfig> parse_udp(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"timeout", "hello_wait", "key", "model"};
  haptics::UdpDeviceConfig config;
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
  auto ok = apply_options(p, "udp", kKeys, SharedKeys{.spec = &config.spec}, [&](const Option& o) -> Expected<bool> {
    if (o.key == "timeout" || o.key == "hello_wait") {
      auto v = p.number(o);
      if (!v) return std::unexpected(v.error());
      (o.key == "timeout" ? config.timeout_s : config.hello_wait_s) = *v;
      return true;
    }
    if (o.key != "key") return false;
    if (o.value.empty()) return p.fail("key needs a file (key=FILE; make one with `hof device keygen FILE`)");
    auto key = udp::read_key_file(std::string(o.value));
    if (!key) return p.fail(key.error().to_string());
    config.key = *key;
    return true;
  });
  if (!ok) return std::unexpected(ok.error());
  return config;
}

/// A backend that takes no ARGUMENT: an error naming it, with `hint` (how to choose one).
Expected<void> no_argument(const SpecParser& p, std::string_view backend, std::string_view hint = {}) {
  if (!p.has_argument()) return {};
  return p.fail(fmt::format("{} takes no argument (got '{}'{})", backend, p.argument(), hint));
}

Expected<DeviceConfig> parse_spacemouse(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"scale", "model"};
  if (auto none = no_argument(p, "spacemouse"); !none) return std::unexpected(none.error());
  haptics::SpacemouseConfig config;
  auto ok =
      apply_options(p, "spacemouse", kKeys, SharedKeys{.spec = &config.spec}, [&](const Option& o) -> Expected<bool> {
        if (o.key != "scale") return false;
        auto v = p.number(o);
        if (!v) return std::unexpected(v.error());
        config.scale_m_per_unit_s = *v;
        return true;
      });
  if (!ok) return std::unexpected(ok.error());
  return config;
}

Expected<DeviceConfig> parse_mouse(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"model"};
  if (auto none = no_argument(p, "mouse"); !none) return std::unexpected(none.error());
  haptics::MouseConfig config;
  auto ok = apply_options(p, "mouse", kKeys, SharedKeys{.spec = &config.spec, .virtual_spec = config.spec}, kNoOwnKeys);
  if (!ok) return std::unexpected(ok.error());
  return config;
}

Expected<DeviceConfig> parse_dhd(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"index", "library", "model"};
  if (auto none = no_argument(p, "dhd", "; index=N chooses a device"); !none) return std::unexpected(none.error());
  haptics::DhdConfig config;
  auto ok = apply_options(p, "dhd", kKeys, SharedKeys{.sdk_model = &config.model, .library = &config.library},
                          [&](const Option& o) -> Expected<bool> {
                            if (o.key != "index") return false;
                            auto v = p.number(o);
                            if (!v) return std::unexpected(v.error());
                            if (*v < 0.0 || *v > 127.0 || *v != std::floor(*v)) {
                              return p.fail(fmt::format("index={}: a device number from 0", o.value));
                            }
                            config.index = static_cast<int>(*v);
                            return true;
                          });
  if (!ok) return std::unexpected(ok.error());
  return config;
}

Expected<DeviceConfig> parse_openhaptics(const SpecParser& p) {
  static constexpr std::string_view kKeys[] = {"device", "library", "model"};
  if (auto none = no_argument(p, "openhaptics", "; device=NAME chooses one"); !none)
    return std::unexpected(none.error());
  haptics::OpenHapticsConfig config;
  auto ok = apply_options(p, "openhaptics", kKeys, SharedKeys{.sdk_model = &config.model, .library = &config.library},
                          [&](const Option& o) -> Expected<bool> {
                            if (o.key != "device") return false;
                            config.device = std::string(o.value);
                            return true;
                          });
  if (!ok) return std::unexpected(ok.error());
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

Expected<std::unique_ptr<haptics::Device>> open_device(std::string_view spec) {
  auto config = parse_device_spec(spec);
  if (!config) return std::unexpected(config.error());
  auto device = haptics::open_device(*config);
  // A replay file's and the SpaceMouse's errors name what failed themselves (the file and
  // line, spnav's own message); the others say which spec they came from.
  const bool names_itself = std::holds_alternative<haptics::ReplayConfig>(*config) ||
                            std::holds_alternative<haptics::SpacemouseConfig>(*config);
  if (!device && !names_itself) {
    Error e = device.error();
    e.message = fmt::format("device spec '{}': {}", spec, e.message);
    return std::unexpected(std::move(e));
  }
  return device;
}

}  // namespace hof::scene
