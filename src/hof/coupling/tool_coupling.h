#pragma once
/// @file
/// The per-step half of the tool seam (haptics/tool.h): before a body steps, the simulation
/// hands the tool's latest state — its force averaged over the ticks since that body's last
/// step — to the tool's coupling, which turns the reaction into forces on the body's nodes
/// (a needle spreads it along its inserted path). The surface contacts of the other bodies
/// keep their own coupling (session.h).

#include <cstdint>
#include <span>
#include <vector>

#include "hof/haptics/tool.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mechanics/mechanical_state.h"

namespace hof::coupling {

class ToolTissueCoupling {
 public:
  ToolTissueCoupling() = default;
  ToolTissueCoupling(const ToolTissueCoupling&) = delete;
  ToolTissueCoupling& operator=(const ToolTissueCoupling&) = delete;
  virtual ~ToolTissueCoupling() = default;

  /// Adds the tissue's share of the tool's reaction (−`tool.force`, the force on the hand
  /// averaged over the step) to `forces` (3N, the body's nodes), from the body's current state.
  /// Called on the simulation thread, only while the tool is in or on body `tool.body`.
  virtual void add_tissue_forces(const haptics::ToolState& tool, const mechanics::MechanicalModel& model,
                                 const mechanics::MechanicalState& state, std::span<double> forces) = 0;
};

}  // namespace hof::coupling
