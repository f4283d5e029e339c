#pragma once
/// @file
/// Needle insertion: the needle stylus as a tool of the haptic loop (haptics/tool.h) and its
/// reaction on the tissue (coupling/tool_coupling.h).
///
/// Each tick (NeedleTool):
///  - free → touching: the proxy touches a body the needle can enter; the entry point (the
///    contact point) and the insertion axis are fixed there;
///  - the surface of that body gives no force from then on (the thesis' zero-force
///    LiverSurface): the tip passes, and the depth d = (tip − entry)·axis drives the model;
///  - pre-puncture (capsule intact): the pre-puncture law; punctured when d reaches the capsule
///    distance or the force the puncture threshold, whichever comes first (the post-puncture
///    law from that tick on);
///  - relaxation: still (|axial v| < Δv/2) after inserting: the force it had decays with time;
///  - extraction: withdrawing: Karnopp friction along the inserted shaft (it pulls the other way
///    and shrinks with the inserted length: not a replay of insertion);
///  - out: withdrawn past the entry after a puncture; the next contact starts again;
///  - inside (d > 0), a lateral spring holds the tip on the path (the tissue holds the shaft),
///    with the device's stable stiffness as its ceiling.
/// The hand feels −f·axis (f from needle_model.h, > 0 resisting) plus the lateral force; the
/// safety filter after the tool clamps the sum to the device's limit.
///
/// Each simulation step (NeedleTissueCoupling): the reaction (the opposite of what the hand
/// felt, averaged over the step) goes into the tissue along the inserted path: before puncture
/// at the tip (the capsule pushed ahead of it), after it over points spread along the shaft
/// from the entry to the tip; each point's share spreads over the nodes within the body's
/// `spread_radius` (weights (1 − r²/ρ²)², at least the four nearest nodes). The sum is the
/// reaction exactly. Withdrawing, the friction drags the tissue outward.

#include <atomic>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/triple_buffer.h"
#include "hof/coupling/tool_coupling.h"
#include "hof/haptics/tool.h"
#include "hof/procedures/needle_model.h"

namespace hof::procedures {

/// How the insertion axis is chosen at first contact.
enum class NeedleAxis : std::uint8_t {
  kMotion,  ///< the direction the tip was moving in (a 3-DOF device), else the inward normal
  kNormal,  ///< the inward surface normal at the entry point (the thesis)
  kStylus,  ///< the stylus' own direction, −z of the device orientation (a 6-DOF device)
};
[[nodiscard]] std::string_view axis_name(NeedleAxis axis);  ///< "motion", "normal", "stylus"

/// The needle stylus (Zamani et al. 2007, as the thesis' appendix draws it): 94 mm long, a
/// 0.25 mm tip section and a 1.25 mm shaft section of 47 mm each, on a syringe.
struct NeedleGeometry {
  double length_m{0.094};
  double shaft_diameter_m{0.00125};
  double tip_diameter_m{0.00025};
  double tip_length_m{0.047};
  double syringe_diameter_m{0.01};
  double syringe_length_m{0.06};
  bool operator==(const NeedleGeometry&) const = default;
};

/// A project's needle: the stylus, the axis rule, and the tissue parameters — one set for
/// every deformable body, and sets of its own for bodies named.
struct NeedleConfig {
  NeedleGeometry geometry;
  NeedleAxis axis{NeedleAxis::kMotion};
  /// Time constant of the low-pass filter on the tip's velocity that decides moving / still
  /// and feeds the friction (a real device's velocity estimate is noisy: unfiltered, a still
  /// needle would flicker between relaxation, insertion and extraction), s; 0: unfiltered.
  double velocity_filter_s{0.01};
  TissueNeedleParameters tissue;                                       ///< every deformable body without its own set
  std::vector<std::pair<std::string, TissueNeedleParameters>> bodies;  ///< by body name
  bool operator==(const NeedleConfig&) const = default;
};
/// Checks every set and the geometry; errors name the body.
[[nodiscard]] Expected<void> validate(const NeedleConfig& config);

/// The parameters of each world body (by index): its own set, else the common set for a
/// deformable body, else not pierceable (a rigid body the needle only touches).
[[nodiscard]] std::vector<TissueNeedleParameters> parameters_by_body(const NeedleConfig& config,
                                                                     const std::vector<std::string>& body_names,
                                                                     const std::vector<bool>& deformable);

class NeedleTool final : public haptics::Tool {
 public:
  /// `body_names` and `deformable` describe the world's bodies, by index. The parameters are
  /// SI; `metres_per_unit` is the world's length unit in metres (1e-3 for a scene in mm).
  static Expected<std::shared_ptr<NeedleTool>> make(const NeedleConfig& config, std::vector<std::string> body_names,
                                                    std::vector<bool> deformable, double metres_per_unit = 1.0);

  Vec3 tick(const haptics::ToolTickInput& input, std::span<Vec3> layer_forces, haptics::ToolState& state) override;
  void restart() override;

  /// Changes the parameters while the loop runs (one producer thread: the window); validated
  /// here, taken by the next tick. The needle keeps its place and phase.
  Expected<void> configure(const NeedleConfig& config);
  /// The configuration last given (producer side).
  [[nodiscard]] const NeedleConfig& config() const { return config_; }
  /// The parameters in force for body `i` (producer side).
  [[nodiscard]] const TissueNeedleParameters& parameters(std::size_t body) const;
  /// Body i's reach of the reaction in the tissue, in world units (any thread).
  [[nodiscard]] double spread_radius(std::size_t body) const;
  [[nodiscard]] double metres_per_unit() const { return metres_per_unit_; }

 private:
  NeedleTool(const NeedleConfig& config, std::vector<std::string> body_names, std::vector<bool> deformable,
             double metres_per_unit);
  struct Resolved {
    NeedleAxis axis{NeedleAxis::kMotion};
    double velocity_filter_s{0.01};
    std::vector<TissueNeedleParameters> bodies;
  };
  void disengage(NeedlePhase phase);
  void resolve();
  // The stages of tick().
  void filter_velocity(const haptics::ToolTickInput& in, const Resolved& settings);
  void reenter_or_rearm(const haptics::ToolTickInput& in, std::span<Vec3> layer_forces);
  void engage(const haptics::ToolTickInput& in, const Resolved& settings);
  double capsule_force(const TissueNeedleParameters& p, double d, double v);
  double inserted_force(const TissueNeedleParameters& p, double d, double v, double time_s);
  Vec3 publish(const haptics::ToolTickInput& in, haptics::ToolState& st, double depth_m, double v_m, double f,
               const Vec3& force) const;

  NeedleConfig config_;  // producer side
  std::vector<std::string> body_names_;
  std::vector<bool> deformable_;
  double metres_per_unit_{1.0};
  Resolved producer_resolved_;
  TripleBuffer<Resolved> settings_;                       // producer → tick
  std::unique_ptr<std::atomic<double>[]> spread_radius_;  // producer → the simulation's coupling
  // Tick state.
  bool engaged_{false};
  bool broken_{false};
  // After a withdrawal the hole stays until the stylus has left the surface: pushed back in
  // there, the needle re-enters its path.
  bool rearmed_{true};
  std::int32_t withdrawn_from_{-1};
  std::int32_t withdrawn_layer_{-1};
  double max_depth_m_{0.0};  // the deepest point of the path cut so far
  bool have_velocity_{false};
  Vec3 velocity_{Vec3::Zero()};  // the tip's filtered velocity, world units/s
  NeedlePhase phase_{NeedlePhase::kFree};
  std::int32_t body_{-1};
  std::int32_t layer_{-1};
  Vec3 entry_{Vec3::Zero()}, axis_{Vec3::Zero()}, normal_{Vec3::Zero()};
  double held_n_{0.0};         // the axial force of the last tick (Karnopp's stuck force)
  double relax_start_s_{0.0};  // when relaxation began
  double relax_force_n_{0.0};  // the force it began with
};

class NeedleTissueCoupling final : public coupling::ToolTissueCoupling {
 public:
  /// The reach of each body is the tool's (NeedleTool::spread_radius).
  explicit NeedleTissueCoupling(std::shared_ptr<const NeedleTool> tool) : tool_(std::move(tool)) {}
  void add_tissue_forces(const haptics::ToolState& tool, const mechanics::MechanicalModel& model,
                         const mechanics::MechanicalState& state, std::span<double> forces) override;

 private:
  // Adds `force` spread over the nodes around `point`.
  void spread(const Vec3& point, const Vec3& force, double radius, const mechanics::MechanicalState& state,
              std::size_t nodes, std::span<double> forces);
  std::shared_ptr<const NeedleTool> tool_;
  std::vector<std::pair<double, std::int32_t>> near_;  // scratch: (squared distance, node)
};

}  // namespace hof::procedures
