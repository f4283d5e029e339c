#pragma once
/// @file
/// Palpation measured: the presses of a session (each time the stylus comes into contact after
/// being clear of the tissue), with the tissue's indentation at the contact and the force, so
/// that presses at different places can be compared — a stiffer spot (a tumour) gives more
/// force at the same indentation. Fed one haptic sample at a time (hof run, tests); no
/// allocation per sample once a press has started.

#include <array>
#include <cstdint>
#include <vector>

#include "hof/core/types.h"
#include "hof/haptics/haptic_loop.h"

namespace hof::coupling {

class Session;

/// One press: contact from its first sample to its last.
struct Press {
  std::int32_t index{0};  ///< 1-based, in order
  std::int32_t body{-1};  ///< body pressed (session index), −1 unknown
  double start_s{0.0}, end_s{0.0};
  Vec3 first_contact{Vec3::Zero()};  ///< where the surface was first touched (world, scene units)
  double max_force_n{0.0};
  double max_indentation_m{0.0};
  /// Least-squares stiffness through the origin, F ≈ k·d, over the loading curve (bin means)
  /// from kFitFrom up to the peak force (N per scene unit); 0 when there is none.
  double stiffness{0.0};
  double max_loading_force_n{0.0};
  double indentation_at_max_force{0.0};
  /// Mean force of the loading samples (indentation growing) in bins of kBinWidth: bin b holds
  /// indentations in [b·w, (b+1)·w). Count 0: no sample.
  std::array<double, 64> loading_force_sum{};
  std::array<std::int32_t, 64> loading_count{};
};

class PressRecorder {
 public:
  /// Bins of the loading curve and the fit's threshold, in scene units (m for SI scenes;
  /// `unit_scale` = metres per scene unit converts).
  explicit PressRecorder(const Session& session, double unit_scale = 1.0);

  /// Adds one sample; returns the tissue's indentation at the contact (scene units): how far
  /// the surface at the contact has moved inward since this press began (0 out of contact).
  double add(const haptics::HapticSample& s);

  /// The press in progress (1-based), or 0 between presses.
  [[nodiscard]] std::int32_t current() const { return in_press_ ? static_cast<std::int32_t>(presses_.size()) : 0; }
  [[nodiscard]] const std::vector<Press>& presses() const { return presses_; }

  /// Mean loading force of `press` at `indentation` (scene units), by its bin; −1 when the
  /// press has no loading sample there.
  [[nodiscard]] double force_at(const Press& press, double indentation) const;

  /// Width of a loading bin and where the stiffness fit starts, metres.
  static constexpr double kBinWidthM = 0.0005;
  static constexpr double kFitFromM = 0.001;
  /// Contact lost for less than this does not end a press (a sliding probe flickers; tissue springing back catches a
  /// retracting probe), s.
  static constexpr double kGapS = 0.3;

 private:
  void update_stiffness(Press& p) const;

  const Session& session_;
  double bin_width_;
  double fit_from_;
  std::vector<Press> presses_;
  bool in_press_{false};
  double last_contact_s_{-1.0};
  double displaced_at_start_{0.0};
  double last_indentation_{0.0};
};

}  // namespace hof::coupling
