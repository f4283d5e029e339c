#pragma once
/// @file
/// The linear systems of the implicit and static solvers: assembly of A = αM + βK into the
/// model's block pattern (fixed nodes' rows and columns replaced by the identity, so their
/// unknowns stay zero), and its solution by conjugate gradients or a sparse LDLᵀ.

#include <Eigen/Core>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// What assemble_system must fill.
enum class AssemblyTarget : std::uint8_t {
  kSolver,  ///< what the model's linear solver reads (only the single-precision copy, when
            ///< the mixed-precision CG allows it: the double values are then stale)
  kDouble,  ///< the double values (and the single copy when the solver uses it)
};

/// A = mass_coeff·M + stiffness_coeff·K into state.work.system, K linearised where the force
/// fields last evaluated forces.
void assemble_system(const MechanicalModel& model, MechanicalState& state, double mass_coeff, double stiffness_coeff,
                     AssemblyTarget target = AssemblyTarget::kSolver);

/// Whether the CG product uses the single-precision copy of A (made by assemble_system).
bool uses_single_precision(const MechanicalModel& model);

/// Solves A·x = b with the model's linear solver (x starts from zero). b's fixed entries must
/// be zero. Fills state.stats.linear_iterations and linear_residual. Returns false when the
/// solve broke down (non-finite values, a failed factorisation).
bool solve_system(const MechanicalModel& model, MechanicalState& state, const Eigen::VectorXd& b, Eigen::VectorXd& x);

/// Sets up the solver scratch that depends on the pattern (CSC map, LDLᵀ symbolic analysis,
/// the CG's exchange between `threads` threads).
void prepare_linear_solver(const MechanicalModel& model, MechanicalState& state, int threads);

// Deterministic parallel vector kernels (results independent of the thread count).
double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::vector<double>& partials);
/// y += alpha·x
void axpy(double alpha, const Eigen::VectorXd& x, Eigen::VectorXd& y);
/// Zeroes the entries of fixed nodes.
void project(const MechanicalModel& model, Eigen::VectorXd& vector);

}  // namespace hof::mechanics::detail
