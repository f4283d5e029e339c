#pragma once
/// @file
/// Stage 2 of an implicit or static step: the assembly of A = αM + βK into the model's block
/// pattern (fixed nodes' rows and columns replaced by the identity, so their unknowns stay
/// zero), from the element data the force stage left in the field states.

#include "hof/mechanics/detail/solver_workspace.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// What assemble_system must fill.
enum class AssemblyTarget : std::uint8_t {
  kSolver,  ///< what the model's linear solver reads (only the single-precision copy, when
            ///< the mixed-precision CG allows it: the double values are then stale)
  kDouble,  ///< the double values (and the single copy when the solver uses it)
};

/// A = mass_coeff·M + stiffness_coeff·K into state.work->system, K linearised where the force
/// fields last evaluated forces. Marks the matrix as not implicit Euler's own
/// (state.work->system_assembled_step = −1): the caller that owns it says so.
void assemble_system(const MechanicalModel& model, MechanicalState& state, double mass_coeff, double stiffness_coeff,
                     AssemblyTarget target = AssemblyTarget::kSolver);

}  // namespace hof::mechanics::detail
