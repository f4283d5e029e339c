#pragma once
/// @file
/// Sizing a state's solver workspace for a model (make_state, topology changes).

#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::mechanics::detail {

/// Sizes every scratch vector of state.work for `model` and, when the model solves a linear
/// system, copies its pattern and prepares the linear solver (ordering, symbolic analysis, the
/// CG's thread plan) for the threads of state.arena, which must be set.
void size_workspace(const MechanicalModel& model, MechanicalState& state);

}  // namespace hof::mechanics::detail
