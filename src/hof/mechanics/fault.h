#pragma once
/// @file
/// Why a model stopped, as data: the kind of fault and the node or element it was found at.
/// The stepping code records a Fault and nothing else; the text a person reads (the component
/// and the sentence of Divergence) is made from it in one place, describe_fault(), when the
/// fault is reported.

#include <cstdint>
#include <string>

namespace hof::mechanics {

struct MechanicalModel;

enum class FaultKind : std::uint8_t {
  kNone,
  kLinearSolveFailed,  ///< the linear solve broke down (singular or non-finite system)
  kNonFiniteNode,      ///< node `index` has a non-finite position or velocity
  kInvertedElement,    ///< element `index` of force field `field` is inverted (linear FEM)
  kRunawayNode,        ///< node `index` moves at `value` m/s, above the model's limit
};

struct Fault {
  FaultKind kind{FaultKind::kNone};
  std::int64_t index{-1};  ///< the node or element (−1: none)
  std::int32_t field{-1};  ///< kInvertedElement: the force field (index into model.force_fields)
  double value{0.0};       ///< kRunawayNode: the speed, m/s
};

/// The component a fault names (e.g. "TetrahedronFEMForceField 'FEM'") and the sentence that
/// says what happened: the text of the divergence report.
struct FaultText {
  std::string component;
  std::string reason;
};

/// The fault in words. Allocates: call it when reporting, never on a good step.
[[nodiscard]] FaultText describe_fault(const MechanicalModel& model, const Fault& fault);

}  // namespace hof::mechanics
