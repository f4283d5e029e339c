#pragma once
/// @file
/// A compliant "virtual hand" (spec `virtual-hand:MOTION[,key=value...]`): a point mass held
/// by the user's arm, modelled as a spring-damper toward a scripted target, on a device with
/// physical damping. It reacts to the force the renderer writes, so closed-loop effects
/// (wall stiffness vs. sampling period, Colgate & Schenkel's passivity bound b > K·T/2 + |B|)
/// show up in simulation:
///
///   m ẍ = k_h (x_target(t) − x) + b_h (ẋ_target(t) − ẋ) − b_dev ẋ + F_written
///
/// read(t) integrates from the previous read time to t at a fixed internal step
/// h = Δt / ceil(Δt / substep) ≤ substep (one substep per tick when Δt = substep = 1 ms),
/// holding the force last written constant over the interval (zero-order hold, as a real
/// device's amplifier does). The first read places the hand on the target, moving with it
/// (x = x_target, ẋ = ẋ_target). After the target motion's duration, health is kEnded and
/// readings are invalid, but the hand keeps integrating.
///
/// Two integrators (HandIntegrator):
///  - kSemiImplicitEuler (default): v ← v + h/m·f(x, v, t), x ← x + h·v. Cheap and stable,
///    but with one substep per sampling period T it is itself a sampled system whose force
///    gain per step is h²/m instead of the held force's true h²/2m: a sampled wall
///    F = −K x on it is passive for any b > 0, so Colgate's bound does NOT show up unless the
///    substep is much smaller than T (≈ T/10 shows it approximately).
///  - kExactZeroOrderHold: the exact discretisation of the linear hand over each substep,
///    [x; v] ← Φ(h) [x; v] + Γ(h) u with u = k_h x_target + b_h ẋ_target + F held over the
///    substep (target sampled mid-substep; Φ, Γ from the matrix exponential, recomputed
///    only when h changes). This is
///    the continuous device of Colgate & Schenkel's analysis, so a sampled wall is passive
///    exactly when b_dev + b_h > K·T/2 (with k_h ≪ K). Use it for passivity studies.

#include <atomic>
#include <cmath>
#include <cstdint>

#include "hof/haptics/device.h"
#include "hof/haptics/device_backends/scripted_device.h"

namespace hof::haptics {

/// How read() advances the hand between samples (see the file comment).
enum class HandIntegrator : std::uint8_t { kSemiImplicitEuler, kExactZeroOrderHold };

/// Physical parameters of the hand and device (SI units).
struct VirtualHandParams {
  double mass_kg{0.1};                   ///< hand + handle mass, > 0
  double stiffness_n_per_m{200.0};       ///< k_h, arm stiffness toward the target, ≥ 0
  double damping_n_s_per_m{5.0};         ///< b_h, arm damping relative to the target, ≥ 0
  double device_damping_n_s_per_m{0.0};  ///< b_dev, device friction against |ẋ|, ≥ 0
  double substep_s{1e-3};                ///< largest internal integration step, > 0
  HandIntegrator integrator{HandIntegrator::kSemiImplicitEuler};
};

/// Checks that the parameters are finite and in range (kInvalidArgument naming the field).
[[nodiscard]] Expected<void> validate(const VirtualHandParams& params);

/// The compliant hand as a device (see the file comment). Single-threaded: read(),
/// write_force() and the accessors belong to the haptic thread; health() to any thread.
class VirtualHandDevice final : public Device {
 public:
  /// @pre validate(params) succeeds (open_device() checks it; tests pass literal values).
  VirtualHandDevice(const ScriptedMotion& target, const VirtualHandParams& params,
                    const DeviceSpec& spec = DeviceSpec{});

  [[nodiscard]] const DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "virtual-hand"; }
  /// Integrates the hand to `time_s` (no-op if time_s is not after the previous read) and
  /// returns its state. Real-time safe; at most kMaxSubsteps substeps per call.
  DeviceReading read(double time_s) override;
  /// Force (N) applied to the hand from now until the next read (zero-order hold); a
  /// non-finite force is treated as zero. Torque is ignored (point hand).
  void write_force(const Vec3& force_n, const Vec3& torque_n_m) override;
  [[nodiscard]] DeviceHealth health() const override { return health_.load(std::memory_order_acquire); }
  [[nodiscard]] double script_duration_s() const override {
    return std::isfinite(target_.duration()) ? target_.duration() : 0.0;
  }

  /// Hand position (m, device frame) at the last read.
  [[nodiscard]] const Vec3& position() const { return x_m_; }
  /// Hand velocity (m/s) at the last read.
  [[nodiscard]] const Vec3& velocity() const { return v_m_per_s_; }
  /// ½ m |ẋ|² (J) at the last read.
  [[nodiscard]] double kinetic_energy() const { return 0.5 * params_.mass_kg * v_m_per_s_.squaredNorm(); }
  /// Force currently held (N).
  [[nodiscard]] const Vec3& applied_force() const { return force_n_; }
  [[nodiscard]] const VirtualHandParams& params() const { return params_; }
  [[nodiscard]] const ScriptedMotion& target() const { return target_; }
  /// Puts the hand at `position_m` with velocity `velocity_m_per_s` at time `time_s` (the
  /// next read integrates from there). For tests that start off the target.
  void reset(double time_s, const Vec3& position_m, const Vec3& velocity_m_per_s = Vec3::Zero());

  /// Bound on substeps per read(): a longer gap is integrated with a larger step.
  static constexpr long kMaxSubsteps = 100000;

 private:
  DeviceSpec spec_;
  ScriptedMotion target_;
  VirtualHandParams params_;
  /// Φ (2x2, columns 0–1) and Γ (column 2) of the exact discretisation for step `h`.
  void update_exact_step(double h);

  bool started_{false};
  double exact_h_s_{-1.0};
  Eigen::Matrix<double, 2, 3> exact_step_{Eigen::Matrix<double, 2, 3>::Zero()};
  double t_s_{0.0};
  Vec3 x_m_{Vec3::Zero()};
  Vec3 v_m_per_s_{Vec3::Zero()};
  Vec3 force_n_{Vec3::Zero()};
  std::atomic<DeviceHealth> health_{DeviceHealth::kOk};
};

}  // namespace hof::haptics
