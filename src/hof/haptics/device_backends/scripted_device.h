#pragma once
/// @file
/// Built-in stylus motions as pure functions of time (ScriptedMotion) and the device that
/// plays one back (ScriptedDevice, spec `scripted:MOTION[,key=value...]`). The same motion is
/// the target of the compliant virtual hand (virtual_hand_device.h).
///
/// Motions (device frame, metres, seconds; t = 0 is the start of the motion):
///  - `poke`: from `start` along the unit `direction`, travel `approach` (to the contact
///    plane) then `depth` further at `speed`, hold `hold` s, retract to `start` at `speed`.
///    With `force=F` (N, > 0) the press stops early where the hand first feels F pushing back
///    (the force written to the device, against `direction`), as a person presses to a force:
///    the poke then holds there and retracts (`depth` is the deepest it may go). Like a hand it
///    also gives way: whenever the force exceeds F (tissue swinging into it, a surface dragging
///    the proxy away) it moves with the force by the excess over the device's stiffness, at most
///    1 mm a reading.
///    The default approach is the distance from `start` to the plane through the origin
///    normal to `direction`, so the default poke presses 2 cm below y = 0.
///  - `press-and-slide`: the poke's press, hold, then slide `distance` along the tangent
///    `slide` (projected into the plane normal to `direction`) at `slide_speed`, slide back,
///    retract.
///  - `palpate`: a palpation sweep — `count` pokes, the k-th from `start` + k·`step`: press
///    (approach + depth along `direction`) at `speed`, hold `hold` s, retract, move to the next
///    start at `speed`; the last press retracts and stays (with `repeat`, travels back to the
///    first start). The clinician's raster over an organ to find a hard lump.
///  - `circle`: a circle of `radius` around `centre` in the plane normal to `normal`, one
///    turn per `period`, starting at centre + radius·u (u: first in-plane axis, see
///    plane_basis()).
///  - `hold`: stays at `start` for `hold` s (the spec string `scripted:hold` holds forever
///    unless given `hold=S`).
/// One cycle is the motion above; `repeat` cycles are played (0 = forever), then the motion
/// rests at its final position and the device reports DeviceHealth::kEnded.
/// Poke and press-and-slide are piecewise linear (constant speed per segment): positions
/// are continuous, velocities jump at the corners.

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>

#include "hof/haptics/device.h"

namespace hof::haptics {

/// The built-in motions (see the file comment).
enum class MotionKind : std::uint8_t { kPoke, kPressAndSlide, kCircle, kHold, kPalpate };

/// Most presses of one palpation sweep (keeps a motion a small value type).
inline constexpr std::uint32_t kMaxPalpationPresses = 16;

/// The typed description of a motion; validated by ScriptedMotion::make().
struct MotionConfig {
  MotionKind kind{MotionKind::kPoke};
  // poke / press-and-slide / hold
  Vec3 start_m{0.0, 0.05, 0.0};    ///< where the motion begins, device frame
  Vec3 direction{0.0, -1.0, 0.0};  ///< press direction (normalised by make())
  double approach_m{-1.0};         ///< < 0: distance from start to the origin plane
  double depth_m{0.02};            ///< travel past the approach, ≥ 0
  double speed_m_per_s{0.01};      ///< approach, press and retract speed, > 0
  double hold_s{1.0};              ///< pause at full depth (or the whole hold), ≥ 0
  /// poke: stop pressing at this force against the press, N; 0 = press to `depth` whatever the
  /// force. Only for one cycle (repeat 1).
  double stop_force_n{0.0};
  // press-and-slide
  Vec3 slide_direction{Vec3::Zero()};  ///< zero: first axis of plane_basis(direction)
  double slide_distance_m{0.02};
  double slide_speed_m_per_s{0.0};  ///< ≤ 0: same as speed
  // palpate
  Vec3 palpation_step_m{0.01, 0.0, 0.0};  ///< from one press's start to the next
  std::uint32_t palpation_count{5};       ///< presses, 1..kMaxPalpationPresses
  // circle
  Vec3 centre_m{Vec3::Zero()};
  Vec3 normal{0.0, 1.0, 0.0};  ///< plane normal (normalised by make())
  double radius_m{0.02};
  double period_s{2.0};
  /// Number of cycles; 0 = forever.
  std::uint32_t repeat{1};

  /// A poke: from `start` along `direction`, `approach` to the surface, then `depth` past it at
  /// `speed`, held for `hold` seconds, and back.
  static MotionConfig poke(const Vec3& start, const Vec3& direction, double approach, double depth, double speed,
                           double hold) {
    MotionConfig m;
    m.kind = MotionKind::kPoke;
    m.start_m = start;
    m.direction = direction;
    m.approach_m = approach;
    m.depth_m = depth;
    m.speed_m_per_s = speed;
    m.hold_s = hold;
    return m;
  }
};

/// Two unit vectors (u, w) spanning the plane normal to the unit vector `n`, with u × w = n.
/// u is the x axis projected into the plane unless n is close to x, then the y axis.
void plane_basis(const Vec3& n, Vec3& u, Vec3& w);

/// A motion as a pure function of time; a small value type (no heap), safe to copy and to
/// call from the haptic tick.
class ScriptedMotion {
 public:
  /// Validates `config` (finite values, positive speeds/period, non-zero directions,
  /// tangent slide). Errors are kInvalidArgument and name the field.
  [[nodiscard]] static Expected<ScriptedMotion> make(const MotionConfig& config);
  /// A target that stays at `position_m` forever.
  [[nodiscard]] static ScriptedMotion stationary(const Vec3& position_m);

  /// Position at time `t_s` (m, device frame). Before 0: the start; after duration(): the
  /// final position.
  [[nodiscard]] Vec3 position(double t_s) const;
  /// Analytic velocity (m/s); zero outside [0, duration()]. At a corner of a piecewise
  /// linear path it is the velocity of the segment that starts there.
  [[nodiscard]] Vec3 velocity(double t_s) const;
  /// Total duration (s): cycles × cycle_duration(); +infinity when it repeats forever.
  [[nodiscard]] double duration() const;
  /// Duration of one cycle (s); may be +infinity for `hold` without a time.
  [[nodiscard]] double cycle_duration() const { return cycle_s_; }
  [[nodiscard]] MotionKind kind() const { return kind_; }
  /// The deepest point of a poke / press-and-slide (start + (approach + depth)·direction).
  [[nodiscard]] Vec3 deepest_point() const { return deepest_m_; }
  /// Where the press meets the contact plane (start + approach·direction).
  [[nodiscard]] Vec3 contact_point() const { return contact_m_; }
  /// poke with a stop force: the force (N, against the press) at which it stops; 0 otherwise.
  [[nodiscard]] double stop_force() const { return stop_force_n_; }
  /// A poke's unit press direction.
  [[nodiscard]] const Vec3& press_direction() const { return direction_; }
  /// The same poke with its press ending `depth_m` past the contact plane (stop force off):
  /// equal to this motion up to the time that depth is reached, then held and retracted.
  [[nodiscard]] ScriptedMotion stopped_at_depth(double depth_m) const;
  /// Time (s, first cycle) at which a poke's press begins past the contact plane and ends.
  [[nodiscard]] double press_begin_s() const { return press_begin_s_; }
  [[nodiscard]] double press_end_s() const { return press_end_s_; }

 private:
  /// One straight piece of a piecewise linear path: from `from` at `velocity` for `duration_s`.
  struct Segment {
    Vec3 from{Vec3::Zero()};
    Vec3 velocity{Vec3::Zero()};
    double duration_s{0.0};
  };
  static constexpr int kMaxSegments = 4 * static_cast<int>(kMaxPalpationPresses);

  ScriptedMotion() = default;
  void add_segment(const Vec3& from, const Vec3& to, double speed_m_per_s);
  void add_hold(const Vec3& at, double duration_s);
  /// Time within the current cycle, or -1 before the start, or +inf after the end.
  [[nodiscard]] double cycle_time(double t_s) const;
  [[nodiscard]] Vec3 path_position(double tc_s) const;
  [[nodiscard]] Vec3 path_velocity(double tc_s) const;

  MotionKind kind_{MotionKind::kHold};
  std::array<Segment, kMaxSegments> segments_{};
  int segment_count_{0};
  Vec3 start_m_{Vec3::Zero()};
  Vec3 end_m_{Vec3::Zero()};
  Vec3 contact_m_{Vec3::Zero()};
  Vec3 deepest_m_{Vec3::Zero()};
  // circle
  Vec3 centre_m_{Vec3::Zero()};
  Vec3 u_{Vec3::UnitX()};
  Vec3 w_{Vec3::UnitZ()};
  double radius_m_{0.0};
  double omega_rad_per_s_{0.0};
  double cycle_s_{std::numeric_limits<double>::infinity()};
  std::uint32_t repeat_{0};
  // poke: what stopped_at_depth() needs to lay the same path out again
  Vec3 direction_{Vec3::UnitY()};
  double speed_m_per_s_{0.0};
  double hold_s_{0.0};
  double stop_force_n_{0.0};
  double press_begin_s_{0.0};
  double press_end_s_{0.0};
};

/// Spec `scripted:...`: plays a ScriptedMotion as a device. read(t) evaluates the motion at
/// t (identity orientation, no buttons); after duration() health is kEnded and the reading
/// invalid (position held at the end). The motion is kinematic: the force written moves
/// nothing, except that a poke with a stop force ends its press where the force written last
/// reaches it (the poke is then replaced by the same poke stopped at that depth: no allocation).
class ScriptedDevice final : public Device {
 public:
  explicit ScriptedDevice(const ScriptedMotion& motion, const DeviceSpec& spec = DeviceSpec{});

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "scripted"; }
  DeviceReading read(double time_s) override;
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override { return health_.load(std::memory_order_acquire); }
  [[nodiscard]] double script_duration_s() const override {
    return std::isfinite(motion_.duration()) ? motion_.duration() : 0.0;
  }

  [[nodiscard]] const ScriptedMotion& motion() const { return motion_; }
  /// The last force written (N), for tests.
  [[nodiscard]] const Vec3& last_force() const { return force_n_; }

 private:
  DeviceSpec spec_;
  ScriptedMotion motion_;
  Vec3 force_n_{Vec3::Zero()};
  Vec3 yielded_m_{Vec3::Zero()};  ///< how far a poke pressing to a force has given way (m, device frame)
  std::atomic<DeviceHealth> health_{DeviceHealth::kOk};
};

}  // namespace hof::haptics
