#include "hof/haptics/device_backends/scripted_device.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

namespace hof::haptics {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool finite(const Vec3& v) { return v.allFinite(); }

std::unexpected<Error> invalid(std::string message) {
  return make_error(ErrorCode::kInvalidArgument, "scripted motion: " + std::move(message));
}

}  // namespace

void plane_basis(const Vec3& n, Vec3& u, Vec3& w) {
  const Vec3 axis = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  u = (axis - axis.dot(n) * n).normalized();
  w = n.cross(u);
}

// ---------------------------------------------------------------------------------------
// Construction: validate, then lay the path out as straight segments (poke, slide, hold) or
// keep the circle's centre, basis and angular rate.

Expected<ScriptedMotion> ScriptedMotion::make(const MotionConfig& c) {
  if (!finite(c.start_m)) return invalid("start is not finite");
  if (!finite(c.direction) || c.direction.norm() < 1e-12) return invalid("direction must be a non-zero vector");
  if (!std::isfinite(c.depth_m) || c.depth_m < 0.0)
    return invalid(fmt::format("depth must be >= 0 m (got {})", c.depth_m));
  if (!std::isfinite(c.approach_m)) return invalid("approach is not finite");
  if (!std::isfinite(c.speed_m_per_s) || c.speed_m_per_s <= 0.0)
    return invalid(fmt::format("speed must be > 0 m/s (got {})", c.speed_m_per_s));
  if (std::isnan(c.hold_s) || c.hold_s < 0.0) return invalid(fmt::format("hold must be >= 0 s (got {})", c.hold_s));
  if (!std::isfinite(c.stop_force_n) || c.stop_force_n < 0.0)
    return invalid(fmt::format("force must be >= 0 N (got {})", c.stop_force_n));
  if (c.stop_force_n > 0.0 && (c.kind != MotionKind::kPoke || c.repeat != 1))
    return invalid("force= stops one poke (motion poke, repeat=1)");

  ScriptedMotion m;
  m.kind_ = c.kind;
  m.repeat_ = c.repeat;
  m.start_m_ = c.start_m;
  const Vec3 d = c.direction.normalized();
  const double approach = c.approach_m >= 0.0 ? c.approach_m : std::max(0.0, -c.start_m.dot(d));
  m.contact_m_ = c.start_m + approach * d;
  m.deepest_m_ = m.contact_m_ + c.depth_m * d;

  switch (c.kind) {
    case MotionKind::kPoke:
      m.direction_ = d;
      m.speed_m_per_s_ = c.speed_m_per_s;
      m.hold_s_ = c.hold_s;
      m.stop_force_n_ = c.stop_force_n;
      m.press_begin_s_ = approach / c.speed_m_per_s;
      m.press_end_s_ = (approach + c.depth_m) / c.speed_m_per_s;
      m.add_segment(m.start_m_, m.contact_m_, c.speed_m_per_s);
      m.add_segment(m.contact_m_, m.deepest_m_, c.speed_m_per_s);
      m.add_hold(m.deepest_m_, c.hold_s);
      m.add_segment(m.deepest_m_, m.start_m_, c.speed_m_per_s);
      break;
    case MotionKind::kPressAndSlide: {
      Vec3 slide = c.slide_direction;
      if (!finite(slide)) return invalid("slide direction is not finite");
      if (slide.norm() < 1e-12) {
        Vec3 w;
        plane_basis(d, slide, w);
      }
      slide -= slide.dot(d) * d;  // keep it tangential to the pressed plane
      if (slide.norm() < 1e-9 * std::max(1.0, c.slide_direction.norm()))
        return invalid("slide direction must not be parallel to the press direction");
      slide.normalize();
      const double slide_speed = c.slide_speed_m_per_s > 0.0 ? c.slide_speed_m_per_s : c.speed_m_per_s;
      if (!std::isfinite(slide_speed)) return invalid("slide speed is not finite");
      if (!std::isfinite(c.slide_distance_m) || c.slide_distance_m < 0.0)
        return invalid(fmt::format("slide distance must be >= 0 m (got {})", c.slide_distance_m));
      const Vec3 far = m.deepest_m_ + c.slide_distance_m * slide;
      m.add_segment(m.start_m_, m.contact_m_, c.speed_m_per_s);
      m.add_segment(m.contact_m_, m.deepest_m_, c.speed_m_per_s);
      m.add_hold(m.deepest_m_, c.hold_s);
      m.add_segment(m.deepest_m_, far, slide_speed);
      m.add_segment(far, m.deepest_m_, slide_speed);
      m.add_segment(m.deepest_m_, m.start_m_, c.speed_m_per_s);
      break;
    }
    case MotionKind::kPalpate: {
      if (!finite(c.palpation_step_m)) return invalid("step is not finite");
      if (c.palpation_count < 1 || c.palpation_count > kMaxPalpationPresses)
        return invalid(fmt::format("count must be 1 to {} presses (got {})", kMaxPalpationPresses, c.palpation_count));
      const Vec3 press = m.deepest_m_ - m.start_m_;
      for (std::uint32_t k = 0; k < c.palpation_count; ++k) {
        const Vec3 start = m.start_m_ + static_cast<double>(k) * c.palpation_step_m;
        m.add_segment(start, start + press, c.speed_m_per_s);
        m.add_hold(start + press, c.hold_s);
        m.add_segment(start + press, start, c.speed_m_per_s);
        if (k + 1 < c.palpation_count) m.add_segment(start, start + c.palpation_step_m, c.speed_m_per_s);
      }
      // Repeated sweeps travel back to the first start rather than jump there.
      if (c.repeat != 1) {
        m.add_segment(m.start_m_ + static_cast<double>(c.palpation_count - 1) * c.palpation_step_m, m.start_m_,
                      c.speed_m_per_s);
      }
      break;
    }
    case MotionKind::kCircle:
      if (!finite(c.centre_m)) return invalid("centre is not finite");
      if (!finite(c.normal) || c.normal.norm() < 1e-12) return invalid("normal must be a non-zero vector");
      if (!std::isfinite(c.radius_m) || c.radius_m < 0.0)
        return invalid(fmt::format("radius must be >= 0 m (got {})", c.radius_m));
      if (!std::isfinite(c.period_s) || c.period_s <= 0.0)
        return invalid(fmt::format("period must be > 0 s (got {})", c.period_s));
      m.centre_m_ = c.centre_m;
      plane_basis(c.normal.normalized(), m.u_, m.w_);
      m.radius_m_ = c.radius_m;
      m.omega_rad_per_s_ = 2.0 * std::numbers::pi / c.period_s;
      m.cycle_s_ = c.period_s;
      m.start_m_ = m.end_m_ = c.centre_m + c.radius_m * m.u_;
      m.contact_m_ = m.deepest_m_ = m.start_m_;
      return m;
    case MotionKind::kHold:
      m.contact_m_ = m.deepest_m_ = m.start_m_;
      m.add_hold(m.start_m_, c.hold_s);
      break;
  }

  // Sum the segments; a cycle must take some time or repeating it is meaningless.
  m.cycle_s_ = 0.0;
  for (int i = 0; i < m.segment_count_; ++i) m.cycle_s_ += m.segments_[i].duration_s;
  m.end_m_ = m.start_m_;
  if (m.segment_count_ > 0) {
    const Segment& last = m.segments_[m.segment_count_ - 1];
    m.end_m_ = std::isinf(last.duration_s) ? last.from : Vec3(last.from + last.velocity * last.duration_s);
  }
  if (!(m.cycle_s_ > 0.0)) return invalid("the motion has zero duration (nothing to travel or hold)");
  return m;
}

ScriptedMotion ScriptedMotion::stopped_at_depth(double depth_m) const {
  ScriptedMotion m = *this;
  m.stop_force_n_ = 0.0;
  m.deepest_m_ = contact_m_ + std::max(0.0, depth_m) * direction_;
  m.press_end_s_ = press_begin_s_ + std::max(0.0, depth_m) / speed_m_per_s_;
  m.segment_count_ = 0;
  m.add_segment(start_m_, contact_m_, speed_m_per_s_);
  m.add_segment(contact_m_, m.deepest_m_, speed_m_per_s_);
  m.add_hold(m.deepest_m_, hold_s_);
  m.add_segment(m.deepest_m_, start_m_, speed_m_per_s_);
  m.cycle_s_ = 0.0;
  for (int i = 0; i < m.segment_count_; ++i) m.cycle_s_ += m.segments_[i].duration_s;
  m.end_m_ = start_m_;
  return m;
}

ScriptedMotion ScriptedMotion::stationary(const Vec3& position_m) {
  ScriptedMotion m;
  m.kind_ = MotionKind::kHold;
  m.start_m_ = m.end_m_ = m.contact_m_ = m.deepest_m_ = position_m;
  m.add_hold(position_m, kInf);
  m.cycle_s_ = kInf;
  m.repeat_ = 1;
  return m;
}

void ScriptedMotion::add_segment(const Vec3& from, const Vec3& to, double speed_m_per_s) {
  const double length = (to - from).norm();
  if (length <= 0.0 || segment_count_ >= kMaxSegments) return;
  const double duration = length / speed_m_per_s;
  segments_[segment_count_++] = Segment{from, (to - from) / duration, duration};
}

void ScriptedMotion::add_hold(const Vec3& at, double duration_s) {
  if (duration_s <= 0.0 || segment_count_ >= kMaxSegments) return;
  segments_[segment_count_++] = Segment{at, Vec3::Zero(), duration_s};
}

// ---------------------------------------------------------------------------------------
// Evaluation: fold t into one cycle, then look the cycle time up.

double ScriptedMotion::duration() const {
  if (repeat_ == 0 || std::isinf(cycle_s_)) return kInf;
  return cycle_s_ * static_cast<double>(repeat_);
}

double ScriptedMotion::cycle_time(double t_s) const {
  if (!(t_s >= 0.0)) return -1.0;  // also NaN
  if (t_s >= duration()) return kInf;
  if (std::isinf(cycle_s_)) return t_s;
  return std::fmod(t_s, cycle_s_);
}

Vec3 ScriptedMotion::path_position(double tc_s) const {
  double t0 = 0.0;
  for (int i = 0; i < segment_count_; ++i) {
    const Segment& s = segments_[i];
    if (tc_s < t0 + s.duration_s) return s.from + s.velocity * (tc_s - t0);
    t0 += s.duration_s;
  }
  return end_m_;
}

Vec3 ScriptedMotion::path_velocity(double tc_s) const {
  double t0 = 0.0;
  for (int i = 0; i < segment_count_; ++i) {
    const Segment& s = segments_[i];
    if (tc_s < t0 + s.duration_s) return s.velocity;
    t0 += s.duration_s;
  }
  return Vec3::Zero();
}

Vec3 ScriptedMotion::position(double t_s) const {
  const double tc = cycle_time(t_s);
  if (tc < 0.0) return start_m_;
  if (std::isinf(tc)) return end_m_;
  if (kind_ == MotionKind::kCircle) {
    const double a = omega_rad_per_s_ * tc;
    return centre_m_ + radius_m_ * (std::cos(a) * u_ + std::sin(a) * w_);
  }
  return path_position(tc);
}

Vec3 ScriptedMotion::velocity(double t_s) const {
  const double tc = cycle_time(t_s);
  if (tc < 0.0 || std::isinf(tc)) return Vec3::Zero();
  if (kind_ == MotionKind::kCircle) {
    const double a = omega_rad_per_s_ * tc;
    return radius_m_ * omega_rad_per_s_ * (-std::sin(a) * u_ + std::cos(a) * w_);
  }
  return path_velocity(tc);
}

// ---------------------------------------------------------------------------------------
// ScriptedDevice

ScriptedDevice::ScriptedDevice(const ScriptedMotion& motion, const DeviceSpec& spec) : spec_(spec), motion_(motion) {}

DeviceReading ScriptedDevice::read(double time_s) {
  // A poke pressing to a force: once the force last written pushes back by the stop force
  // during the press, the press ends at the depth reached (the path so far is unchanged).
  const Vec3 press_direction = motion_.press_direction();
  const double stop_force = motion_.stop_force();
  const double pushback = -force_n_.dot(press_direction);
  if (stop_force > 0.0 && time_s > motion_.press_begin_s() && time_s < motion_.press_end_s() &&
      pushback >= stop_force) {
    motion_ = motion_.stopped_at_depth((motion_.position(time_s) - motion_.contact_point()).norm());
  }
  // Giving way, as a hand does to any force above F (tissue pushing back, or a surface that
  // drags the proxy away): move with the force by the excess over the device's stiffness (the
  // rendering spring is no stiffer, so the force falls to about F without overshoot), at most
  // 1 mm a reading.
  const double magnitude = force_n_.norm();
  if (stop_force > 0.0 && magnitude > stop_force) {
    const double stiffness = spec_.max_stiffness_n_per_m > 0.0 ? spec_.max_stiffness_n_per_m : 1000.0;
    yielded_m_ += std::min((magnitude - stop_force) / stiffness, 0.001) * (force_n_ / magnitude);
  }
  DeviceReading r;
  r.time_s = time_s;
  r.position_m = motion_.position(time_s) + yielded_m_;
  r.velocity_m_per_s = motion_.velocity(time_s);
  const bool ended = time_s > motion_.duration();
  r.valid = !ended;
  health_.store(ended ? DeviceHealth::kEnded : DeviceHealth::kOk, std::memory_order_release);
  return r;
}

void ScriptedDevice::write_force(const Vec3& force_n, const Vec3& /*torque_n_m*/) { force_n_ = force_n; }

}  // namespace hof::haptics
