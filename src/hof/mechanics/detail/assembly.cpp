#include "hof/mechanics/detail/assembly.h"
#include "hof/mechanics/detail/solver_workspace.h"

#include <algorithm>

#include "hof/mechanics/detail/linear_solve.h"

namespace hof::mechanics::detail {

namespace {

// The single-precision copy alone, when one field's stiffness covers the whole pattern.
bool assemble_single_only(const MechanicalModel& model, MechanicalState& state, double mass_coeff,
                          double stiffness_coeff) {
  const ForceField* only = nullptr;
  std::size_t only_index = 0;
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    if (!model.force_fields[k]->has_stiffness()) continue;
    if (only != nullptr) return false;
    only = model.force_fields[k].get();
    only_index = k;
  }
  BlockSparseMatrix& a = state.work->system;
  if (only == nullptr || !only->set_stiffness_single(state.field_states[only_index], stiffness_coeff, a)) return false;
  constexpr std::int64_t kColumn = BlockSparseMatrix::kSingleColumnStride;
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    float* block = a.single_block(a.diagonal_slot(static_cast<std::int32_t>(n)));
    const auto mass = static_cast<float>(mass_coeff * model.node_mass_kg[n]);
    for (int q = 0; q < 3; ++q) block[kColumn * q + q] += mass;
  }
  // Fixed degrees of freedom: identity rows and columns (projection P A P + (I − P)).
  const auto& row_start = a.row_start();
  const std::vector<std::int32_t>& fixed = model.fixed_dofs;  // sorted
  for (std::size_t k = 0; k < fixed.size();) {
    const std::int32_t d = fixed[k];
    const std::int32_t n = d / 3;
    if (d % 3 == 0 && k + 2 < fixed.size() && fixed[k + 2] == d + 2) {
      // A node held on every axis (the usual case: hundreds of them on a liver): its row and
      // column blocks cleared whole, in one pass over the row rather than one per axis.
      for (std::int64_t s = row_start[n]; s < row_start[n + 1]; ++s) {
        for (float* block : {a.single_block(s), a.single_block(a.mirror_slot(s))}) {
          for (int q = 0; q < 3; ++q) std::fill_n(block + kColumn * q, 3, 0.0f);
        }
      }
      float* diagonal = a.single_block(a.diagonal_slot(n));
      for (int q = 0; q < 3; ++q) diagonal[kColumn * q + q] = 1.0f;
      k += 3;
      continue;
    }
    const int axis = d % 3;
    for (std::int64_t s = row_start[n]; s < row_start[n + 1]; ++s) {
      float* row_block = a.single_block(s);
      for (int q = 0; q < 3; ++q) row_block[kColumn * q + axis] = 0.0f;
      float* column_block = a.single_block(a.mirror_slot(s));
      for (int i = 0; i < 3; ++i) column_block[kColumn * axis + i] = 0.0f;
    }
    a.single_block(a.diagonal_slot(n))[kColumn * axis + axis] = 1.0f;
    ++k;
  }
  return true;
}

}  // namespace

void assemble_system(const MechanicalModel& model, MechanicalState& state, double mass_coeff, double stiffness_coeff,
                     AssemblyTarget target) {
  state.work->system_assembled_step = -1;  // the caller says whether this is implicit Euler's own A
  ++state.work->system_assemblies;
  if (target == AssemblyTarget::kSolver && uses_single_precision(model) &&
      assemble_single_only(model, state, mass_coeff, stiffness_coeff)) {
    return;
  }
  BlockSparseMatrix& a = state.work->system;
  // The first field that covers the whole pattern sets the values (no clearing pass).
  bool initialised = false;
  for (std::size_t k = 0; k < model.force_fields.size(); ++k) {
    const ForceField& field = *model.force_fields[k];
    if (!field.has_stiffness()) continue;
    if (!initialised) {
      initialised = true;
      if (field.set_stiffness(state.field_states[k], stiffness_coeff, a)) continue;
      a.set_zero();
    }
    field.add_stiffness(state.field_states[k], stiffness_coeff, a);
  }
  if (!initialised) a.set_zero();
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    a.block(a.diagonal_slot(static_cast<std::int32_t>(n))).diagonal().array() += mass_coeff * model.node_mass_kg[n];
  }
  // Fixed degrees of freedom: identity rows and columns (projection P A P + (I − P)).
  const auto& row_start = a.row_start();
  for (std::int32_t d : model.fixed_dofs) {
    const std::int32_t n = d / 3;
    const int axis = d % 3;
    for (std::int64_t s = row_start[n]; s < row_start[n + 1]; ++s) {
      a.block(s).row(axis).setZero();
      a.block(a.mirror_slot(s)).col(axis).setZero();
    }
    a.block(a.diagonal_slot(n))(axis, axis) = 1.0;
  }
  if (uses_single_precision(model)) a.update_single_precision();
}

}  // namespace hof::mechanics::detail
