#pragma once
/// @file
/// A deformable body as SOFA models it in one node: a state (positions, velocities), a
/// topology, a mass, force fields, projective constraints and an ODE solver with its linear
/// solver. MechanicalModel is built once from a validated ModelConfig and is then immutable;
/// everything that changes lives in a MechanicalState (see mechanical_state.h), made by
/// make_state() and advanced by step() (see step.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/block_sparse_matrix.h"
#include "hof/mechanics/force_field.h"
#include "hof/mechanics/force_field_config.h"
#include "hof/mesh/hex_grid.h"
#include "hof/mesh/mesh.h"

namespace hof::mechanics {

// ---- configuration (validated by build_model) ---------------------------------------------

enum class MassKind : std::uint8_t {
  kUniform,   ///< SOFA UniformMass: totalMass/N per node, or vertexMass
  kDiagonal,  ///< SOFA DiagonalMass: lumped ρV/4 per tetrahedron node (ρV/8 per hexahedron node without tets)
};

struct MassConfig {
  MassKind kind{MassKind::kDiagonal};
  std::string name{"mass"};
  double total_mass_kg{1.0};                     ///< UniformMass totalMass (SOFA default 1)
  std::optional<double> vertex_mass_kg;          ///< UniformMass vertexMass (overrides totalMass)
  double mass_density_kg_per_m3{1.0};            ///< DiagonalMass massDensity (SOFA default 1)
  std::optional<double> diagonal_total_mass_kg;  ///< DiagonalMass totalMass: rescales the lumped masses
  /// DiagonalMass: per volume element (tetrahedron, or hexahedron in a hexahedral model),
  /// kg/m³; 0 = massDensity. Empty: massDensity everywhere (tissue regions fill it).
  std::vector<double> element_mass_density_kg_per_m3;
};

/// SOFA's Neo-Hookean counterpart; see neo_hookean_force_field.h.
struct NeoHookeanConfig {
  double young_modulus_pa{5000.0};
  double poisson_ratio{0.45};
  /// Per tetrahedron (Pa; 0: youngModulus), or empty: material regions.
  std::vector<double> element_young_modulus_pa;
  /// Per tetrahedron (0: poissonRatio), or empty (split into one field per ratio, as the FEM).
  std::vector<double> element_poisson_ratio;
};

/// One force field of the model; exactly one member is set.
struct ForceFieldConfig {
  std::string name;
  std::optional<MeshSpringConfig> mesh_springs;
  std::optional<TetrahedronFemConfig> tetrahedron_fem;
  std::optional<NeoHookeanConfig> neo_hookean;
  std::optional<ConstantForceConfig> constant_force;
  std::optional<TriangleFemConfig> triangle_fem;      ///< membrane FEM on `triangles`
  std::optional<HexahedronFemConfig> hexahedron_fem;  ///< hexahedral FEM on `hexahedra`
};

/// SOFA FixedProjectiveConstraint (FixedConstraint): nodes by index, or every node whose rest
/// position lies inside an axis-aligned box. With `directions` other than all three it is
/// SOFA's PartialFixedProjectiveConstraint (`fixedDirections`): only those axes are held.
struct FixedConstraintConfig {
  std::string name{"fixed"};
  std::vector<std::int32_t> indices;
  std::optional<std::pair<Vec3, Vec3>> box;  ///< (min, max) corners, m
  bool fix_all{false};
  std::array<bool, 3> directions{true, true, true};  ///< which of x, y, z are held
};

enum class OdeSolverKind : std::uint8_t {
  kEulerExplicit,  ///< SOFA EulerExplicitSolver (`symplectic`)
  kRungeKutta4,    ///< SOFA RungeKutta4Solver
  kStatic,         ///< SOFA StaticSolver: Newton iterations on f(x) = 0
  kEulerImplicit,  ///< SOFA EulerImplicitSolver (Baraff–Witkin), Rayleigh damping
};

struct OdeSolverConfig {
  OdeSolverKind kind{OdeSolverKind::kEulerImplicit};
  std::string name{"odesolver"};
  bool symplectic{true};                      ///< explicit Euler: update v first, then x with the new v
  double rayleigh_stiffness{0.0};             ///< implicit Euler r_K (SOFA default 0; liver.scn 0.1)
  double rayleigh_mass{0.0};                  ///< implicit Euler r_M (SOFA default 0; liver.scn 0.1)
  int newton_iterations{10};                  ///< static solver
  double newton_residual_tolerance_n{1e-6};   ///< static solver: stop when |f| (N) is below
  double newton_correction_tolerance{1e-10};  ///< static solver: stop when |Δx| / |x| is below
  /// Implicit Euler: assemble A = αM + βK every this many steps and reuse it in between. The
  /// forces are evaluated afresh every step, so the step still converges to the right
  /// motion and equilibria are exact; only the linearisation lags by up to N−1 steps, which at
  /// the haptic period (1 ms) is a small change of rotations. 1 (SOFA's behaviour): every step.
  int matrix_reuse_steps{1};
};

enum class LinearSolverKind : std::uint8_t {
  kConjugateGradient,  ///< SOFA CGLinearSolver
  kSparseLdlt,         ///< sparse direct: CHOLMOD's supernodal LLᵀ (simplicial LDLᵀ if A is not positive definite)
};

struct LinearSolverConfig {
  LinearSolverKind kind{LinearSolverKind::kConjugateGradient};
  std::string name{"linearsolver"};
  int iterations{25};        ///< CG maximum iterations (SOFA default 25)
  double tolerance{1e-5};    ///< CG stops when |r|²/|b|² is below (SOFA semantics)
  double threshold{1e-5};    ///< CG stops when pᵀAp falls below threshold × its first value
  bool block_jacobi{false};  ///< precondition CG with the inverse 3x3 diagonal blocks
  /// CG multiplies with a single-precision copy of the matrix (vectors and sums stay double):
  /// half the memory traffic. The solution then solves a system perturbed by ~1e-7 relative,
  /// far below what 25 iterations resolve; equilibria are unaffected (they do not depend on
  /// the matrix). Off for exact-arithmetic studies.
  bool mixed_precision{true};
  /// CG starts from the previous step's solution instead of zero (SOFA's `warmStart`). In
  /// implicit Euler the unknown is the velocity change, which changes little from one step
  /// to the next when the motion is smooth: the iterations then refine an answer that is
  /// nearly right instead of building one from nothing. One extra product per step.
  bool warm_start{false};
  /// CG with a two-level preconditioner: block Jacobi plus an exact solve on the rigid
  /// motions of a few dozen pieces of the body (coarse_correction.h). It removes the smooth
  /// errors that plain CG leaves at the haptic period; each iteration costs about a third
  /// more. A HoF extension (SOFA's CGLinearSolver is unpreconditioned); off by default.
  bool coarse_correction{false};
  /// Steps one coarse matrix serves before it is formed again from the current matrix and
  /// shape (a stale one only slows the convergence).
  int coarse_refresh_steps{100};
};

/// CG iterations of the haptic-rate mode: warm-started, with the two-level preconditioner
/// (coarse_correction.h), two iterations solve a 1 ms step of the medium liver (co-rotational
/// FEM, 5 kPa) three times more accurately than SOFA's default of 25 plain iterations from
/// zero, measured against an exact LDLᵀ solve of the same step
/// (tests/mechanics/haptic_rate_fem_test.cpp, a press: 0.13 against 0.41; `hof bench`: 0.12
/// against 0.37).
inline constexpr int kHapticRateCgIterations = 2;
/// Below this many nodes the haptic-rate mode makes one iteration more: 25 plain iterations
/// all but solve so small a system (the simple liver, 201 nodes: 0.028), two-level ones
/// need three to do better (0.021; two leave 0.060), and an iteration costs little there.
inline constexpr std::size_t kHapticRateSmallBodyNodes = 1000;

/// The haptic-rate mode's CG iterations for a body of `node_count` nodes.
[[nodiscard]] constexpr int haptic_rate_cg_iterations(std::size_t node_count) {
  return node_count < kHapticRateSmallBodyNodes ? kHapticRateCgIterations + 1 : kHapticRateCgIterations;
}

/// The haptic-rate mode's solver settings for a body of `node_count` nodes: few warm-started
/// CG iterations with the two-level preconditioner, the matrix assembled every step. Why not
/// reuse the matrix (matrixReuseSteps > 1): once the solve is this accurate, the reused
/// matrix's lag is the larger error. Implicit Euler's right-hand side holds the damping term
/// −h (h + r_K) K v; with K a few steps old its error is proportional to the velocity rather
/// than to the (much smaller) change of velocity: the press test's error grows from 0.13 to
/// 0.44 with the matrix of every second step and to 0.72 with every third, whatever the
/// iterations.
inline void use_haptic_rate_solver(LinearSolverConfig& linear, OdeSolverConfig& ode, std::size_t node_count) {
  linear.iterations = haptic_rate_cg_iterations(node_count);
  linear.warm_start = true;
  linear.coarse_correction = true;
  ode.matrix_reuse_steps = 1;
}

struct ModelConfig {
  std::string name{"model"};
  std::vector<Vec3> positions;       ///< (N) rest positions, m
  std::vector<mesh::Tet> tets;       ///< topology (may be empty for spring-only surfaces)
  std::vector<mesh::Hex> hexahedra;  ///< hexahedral topology (SOFA corner order; grids)
  std::vector<mesh::Tri> triangles;  ///< surface triangles (springs or membrane FEM on surfaces)
  /// Empty, or a tag per volume element (Gmsh physical group): what tissue regions select by.
  std::vector<std::int32_t> element_regions;
  /// Empty, or per hexahedron the fraction of the cell the body fills (SOFA's sparse grid
  /// `fillWeighted`: 0.5 where the surface passes through, else 1). It scales that element's
  /// stiffness whatever the modulus is set to (a <set>, a region), as SOFA's
  /// HexahedronFEMForceField scales its element matrix by the grid's stiffness coefficient.
  /// It scales the mass too when fill_scales_mass (HoF's own bodies: the organ's mass is that
  /// of the volume it fills); a SOFA scene clears it, as SOFA's DiagonalMass lumps every cell's
  /// full volume.
  std::vector<double> element_fill;
  bool fill_scales_mass{true};
  MassConfig mass;
  std::vector<ForceFieldConfig> force_fields;
  std::vector<FixedConstraintConfig> fixed;
  OdeSolverConfig ode;
  LinearSolverConfig linear;
  Vec3 gravity_m_per_s2{0.0, -9.81, 0.0};  ///< SOFA default
  double dt_s{0.01};                       ///< SOFA default
  double max_speed_m_per_s{100.0};         ///< a node faster than this means divergence
  int threads{0};                          ///< 0 = all cores
};

// ---- the model --------------------------------------------------------------------------------

struct MechanicalModel {
  std::string name;
  std::vector<Vec3> rest_positions;  ///< (N) m
  std::vector<mesh::Tet> tets;
  std::vector<mesh::Hex> hexahedra;
  std::vector<mesh::Tri> triangles;
  std::vector<double> node_mass_kg;  ///< (N) lumped mass per node
  std::string mass_name;
  std::vector<std::unique_ptr<ForceField>> force_fields;
  std::vector<std::int32_t> fixed_dofs;      ///< sorted, unique degrees of freedom (3·node + axis)
  std::vector<std::uint8_t> fixed_dof_mask;  ///< (3N) 1 where the dof is held
  OdeSolverConfig ode;
  LinearSolverConfig linear;
  Vec3 gravity_m_per_s2{Vec3::Zero()};
  double dt_s{0.01};
  double max_speed_m_per_s{100.0};
  int threads{0};
  BlockSparseMatrix pattern;  ///< system-matrix pattern (values unused)
  bool needs_matrix{false};   ///< implicit or static solver

  [[nodiscard]] std::size_t node_count() const { return rest_positions.size(); }
  /// What the model is made of, for reports: "N hexahedra", "N tetrahedra" or, for a surface
  /// model, "N triangles".
  [[nodiscard]] std::string element_summary() const;
  [[nodiscard]] double total_mass_kg() const;
};

/// Validates `config` and builds the model. Errors name the component (type and name) and the
/// offending value, node or element.
[[nodiscard]] Expected<MechanicalModel> build_model(const ModelConfig& config);

}  // namespace hof::mechanics
