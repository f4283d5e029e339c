#include "hof/haptics/device_backends/virtual_hand_device.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace hof::haptics {

Expected<void> validate(const VirtualHandParams& p) {
  const auto check = [](double value, bool strictly_positive, const char* name) -> Expected<void> {
    if (!std::isfinite(value) || value < 0.0 || (strictly_positive && value == 0.0)) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("virtual hand: {} must be {} (got {})", name,
                                                                 strictly_positive ? "> 0" : ">= 0", value));
    }
    return {};
  };
  if (auto r = check(p.mass_kg, true, "mass"); !r) return r;
  if (auto r = check(p.stiffness_n_per_m, false, "stiffness"); !r) return r;
  if (auto r = check(p.damping_n_s_per_m, false, "damping"); !r) return r;
  if (auto r = check(p.device_damping_n_s_per_m, false, "device_damping"); !r) return r;
  return check(p.substep_s, true, "substep");
}

VirtualHandDevice::VirtualHandDevice(const ScriptedMotion& target, const VirtualHandParams& params,
                                     const DeviceSpec& spec)
    : spec_(spec), target_(target), params_(params) {}

void VirtualHandDevice::reset(double time_s, const Vec3& position_m, const Vec3& velocity_m_per_s) {
  started_ = true;
  t_s_ = time_s;
  x_m_ = position_m;
  v_m_per_s_ = velocity_m_per_s;
}

DeviceReading VirtualHandDevice::read(double time_s) {
  if (!started_) {
    // The hand starts where the scripted arm puts it, moving with it.
    reset(time_s, target_.position(time_s), target_.velocity(time_s));
  } else if (time_s > t_s_) {
    // Fixed substeps no longer than params_.substep_s covering (t_s_, time_s]; the small
    // tolerance keeps Δt = substep at one step despite rounding in the subtraction.
    const double interval = time_s - t_s_;
    const double steps = std::ceil(interval / params_.substep_s - 1e-6);
    const long n = std::clamp(static_cast<long>(steps), 1L, kMaxSubsteps);
    const double h = interval / static_cast<double>(n);
    const double m = params_.mass_kg;
    const double k = params_.stiffness_n_per_m;
    const double b = params_.damping_n_s_per_m;
    const double b_dev = params_.device_damping_n_s_per_m;
    if (params_.integrator == HandIntegrator::kSemiImplicitEuler) {
      // Velocity from the forces at the start of the substep, then position from the new
      // velocity. The written force is held constant (ZOH).
      for (long i = 0; i < n; ++i) {
        const double t = t_s_ + h * static_cast<double>(i);
        const Vec3 arm = k * (target_.position(t) - x_m_) + b * (target_.velocity(t) - v_m_per_s_);
        const Vec3 total = arm - b_dev * v_m_per_s_ + force_n_;
        v_m_per_s_ += (h / m) * total;
        x_m_ += h * v_m_per_s_;
      }
    } else {
      // Exact solution of the linear hand over the substep with its input held; the target
      // is sampled mid-substep, the held-input approximation closest to a moving arm.
      if (h != exact_h_s_) update_exact_step(h);
      for (long i = 0; i < n; ++i) {
        const double t = t_s_ + h * (static_cast<double>(i) + 0.5);
        const Vec3 u = k * target_.position(t) + b * target_.velocity(t) + force_n_;
        const Vec3 x = x_m_;
        x_m_ = exact_step_(0, 0) * x + exact_step_(0, 1) * v_m_per_s_ + exact_step_(0, 2) * u;
        v_m_per_s_ = exact_step_(1, 0) * x + exact_step_(1, 1) * v_m_per_s_ + exact_step_(1, 2) * u;
      }
    }
    t_s_ = time_s;
  }

  const bool ended = time_s > target_.duration();
  health_.store(ended ? DeviceHealth::kEnded : DeviceHealth::kOk, std::memory_order_release);
  DeviceReading r;
  r.time_s = time_s;
  r.position_m = x_m_;
  r.velocity_m_per_s = v_m_per_s_;
  r.valid = !ended;
  return r;
}

// exp(h·M) for M = [[0, 1, 0], [−k/m, −(b_h + b_dev)/m, 1/m], [0, 0, 0]] (state x, v and the
// held input u): its top two rows are [Φ | Γ]. Taylor series with scaling and squaring;
// fixed-size, no allocation.
void VirtualHandDevice::update_exact_step(double h) {
  const double m = params_.mass_kg;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  a(0, 1) = 1.0;
  a(1, 0) = -params_.stiffness_n_per_m / m;
  a(1, 1) = -(params_.damping_n_s_per_m + params_.device_damping_n_s_per_m) / m;
  a(1, 2) = 1.0 / m;
  a *= h;
  int squarings = 0;
  for (double norm = a.cwiseAbs().rowwise().sum().maxCoeff(); norm > 0.25 && squarings < 60; norm *= 0.5) {
    ++squarings;
  }
  a /= std::ldexp(1.0, squarings);
  Eigen::Matrix3d e = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d term = Eigen::Matrix3d::Identity();
  for (int i = 1; i <= 16; ++i) {
    term = (term * a) / static_cast<double>(i);
    e += term;
  }
  for (int i = 0; i < squarings; ++i) e = (e * e).eval();
  exact_step_ = e.topRows<2>();
  exact_h_s_ = h;
}

void VirtualHandDevice::write_force(const Vec3& force_n, const Vec3& /*torque_n_m*/) {
  force_n_ = force_n.allFinite() ? force_n : Vec3::Zero();
}

}  // namespace hof::haptics
