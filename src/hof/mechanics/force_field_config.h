#pragma once
/// @file
/// What a model's force fields are configured with (one member of ForceFieldConfig each, see
/// mechanical_model.h): the public half of the force fields. The fields themselves — their
/// element precomputation, colouring, SIMD groups and stiffness writers — are the mechanics'
/// own (detail/*_force_field.h) and are not installed; force_field.h is the interface a new
/// field implements.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/types.h"

namespace hof::mechanics {

/// How the element rotation is obtained.
enum class FemMethod : std::uint8_t {
  kSmall,  ///< no rotation: linear FEM (not invariant to rotations)
  kLarge,  ///< co-rotational, rotation from the QR frame of the first edges
  kPolar,  ///< co-rotational, rotation from the polar decomposition of F
};

struct TetrahedronFemConfig {
  double young_modulus_pa{5000.0};  ///< SOFA default 5000
  double poisson_ratio{0.45};       ///< SOFA default 0.45; must be in (−1, 0.5)
  FemMethod method{FemMethod::kLarge};
  /// Per tetrahedron (Pa; 0: youngModulus), or empty: material regions, SOFA's vector form.
  std::vector<double> element_young_modulus_pa;
  /// Per tetrahedron (0: poissonRatio), or empty. build_model gives each distinct ratio its own
  /// field over its elements (the assembly shares one λ/μ ratio per field).
  std::vector<double> element_poisson_ratio;
};

struct HexahedronFemConfig {
  double young_modulus_pa{5000.0};  ///< SOFA default 5000
  double poisson_ratio{0.45};       ///< SOFA default 0.45; must be in (−1, 0.5)
  FemMethod method{FemMethod::kLarge};
  /// Per hexahedron (Pa; 0: youngModulus), or empty: material regions, SOFA's vector form.
  std::vector<double> element_young_modulus_pa;
  /// Per hexahedron (0: poissonRatio; others in (−1, 0.5)), or empty.
  std::vector<double> element_poisson_ratio;
};

struct TriangleFemConfig {
  /// SOFA component type this field stands for: "TriangleFEMForceField" (defaults E = 1000 Pa,
  /// ν = 0.3) or "TriangularFEMForceField" (E = 5000 Pa, ν = 0.45); both: method large,
  /// thickness 1.
  std::string sofa_type{"TriangleFEMForceField"};
  double young_modulus_pa{1000.0};
  double poisson_ratio{0.3};            ///< must be in (−1, 0.5)
  double thickness_m{1.0};              ///< SOFA default 1: stiffness per area is E·thickness
  bool plane_strain{false};             ///< SOFA `planeStrain`: plane strain instead of plane stress
  FemMethod method{FemMethod::kLarge};  ///< small or large (polar is taken as large)
  /// Rest shape as a fraction of the given one (SOFA TriangularFEMForceFieldOptim `restScale`):
  /// below 1 the membrane starts in tension — a drum skin, which a flat sheet needs to resist
  /// a press across its plane.
  double rest_scale{1.0};
  /// Per triangle (0 = the uniform value), or empty: SOFA's vector forms; tissue regions fill them.
  std::vector<double> element_young_modulus_pa;
  std::vector<double> element_poisson_ratio;
};

/// How a spring's own stiffness and damping follow from the configured values.
enum class SpringStiffnessRule {
  /// Every spring gets the configured values: k in N/m, c in N·s/m (the thesis' surface
  /// springs, an X3D DeformableShape).
  kSameForEverySpring,
  /// SOFA's MeshSpringForceField: the configured values are per unit strain, each spring gets
  /// k/l0 (N/m) and c/l0 (N·s/m) with l0 its rest length — a short edge is stiffer, as a short
  /// bar of the same section is (MeshSpringForceField::addSpring, which passes `stiffness / l`
  /// and `damping / l` to the spring it adds).
  kDividedByRestLength,
};

/// The stiffness matrix a spring adds to the implicit system (its force is the same either way).
/// With f the spring's tension, l its length and u its direction, −∂f_i/∂x_i =
/// k u uᵀ + (f/l)(I − u uᵀ): the transverse term f/l is negative for a compressed spring.
enum class SpringTangent {
  /// The transverse term without the damper's tension, clamped at zero (Choi & Ko, "Stable but
  /// responsive cloth", SIGGRAPH 2002): the matrix stays positive semi-definite for CG.
  kClampedTransverse,
  /// SOFA's (SpringForceField::computeSpringForce, StiffSpringForceField): (k − f/l) u uᵀ +
  /// (f/l) I with f including the damper's tension, never clamped. An implicit step with it
  /// is SOFA's step; a strongly compressed mesh can make the system indefinite.
  kExact,
};

/// Stiffness and damping of the springs of one element kind (SOFA's `trianglesStiffness`
/// `trianglesDamping`, `tetrahedraStiffness` `tetrahedraDamping`). Units as MeshSpringConfig's.
struct SpringValues {
  double stiffness{0.0};
  double damping{0.0};
};

struct MeshSpringConfig {
  /// SOFA `stiffness` (all element kinds). N/m per spring (kSameForEverySpring) or N per unit
  /// strain (kDividedByRestLength).
  double stiffness_n_per_m{0.0};
  double damping_n_s_per_m{0.0};  ///< SOFA `damping`; N·s/m, or N·s per unit strain rate
  /// Rest length of each spring as a fraction of its length in the given shape: below 1 the
  /// springs start in tension (a drum skin, whose tension gives a flat sheet the stiffness
  /// across its plane that untensioned springs lack). 1 = SOFA's behaviour.
  double rest_length_scale{1.0};
  /// kSameForEverySpring keeps HoF's own models as they were; a SOFA scene's springs are
  /// kDividedByRestLength.
  SpringStiffnessRule rule{SpringStiffnessRule::kSameForEverySpring};
  /// kClampedTransverse keeps HoF's own models as they were; a SOFA scene's springs are kExact.
  SpringTangent tangent{SpringTangent::kClampedTransverse};
  /// Per element kind, replacing (stiffness, damping) for the edges of that kind. As SOFA's
  /// MeshSpringForceField::init, the kinds are taken in the order triangles, tetrahedra; an
  /// edge shared by both gets one spring, with the values of the first kind that has it; a
  /// kind whose stiffness and damping are both 0 adds no springs (its edges take the next
  /// kind's values).
  std::optional<SpringValues> triangles{};
  std::optional<SpringValues> tetrahedra{};
};

struct ConstantForceConfig {
  std::vector<std::int32_t> indices;  ///< nodes the forces act on
  std::vector<Vec3> forces;           ///< N, one per index (or one for all)
  std::optional<Vec3> total_force;    ///< N, split equally over `indices` (overrides `forces`)
};

}  // namespace hof::mechanics
