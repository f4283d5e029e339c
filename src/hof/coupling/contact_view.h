#pragma once
/// @file
/// Contact between bodies as a reader thread sees it (the window's contact debug view): the
/// last contact pass's contacts, each with its two points and the force the response gave it,
/// published by the simulation through a triple buffer (Session::graphics_contacts), so that
/// the reader never locks or waits on the simulation.

#include <cstdint>
#include <vector>

#include "hof/core/types.h"

namespace hof::coupling {

/// One contact between two bodies (or a body and itself).
struct BodyContactView {
  std::int32_t body_a{-1};  ///< world body index (Session::body)
  std::int32_t body_b{-1};
  Vec3 point_a{Vec3::Zero()};       ///< on a's surface, world frame
  Vec3 point_b{Vec3::Zero()};       ///< on b's surface, world frame
  Vec3 normal{Vec3::UnitZ()};       ///< unit, from b toward a
  double distance{0.0};             ///< signed gap along the normal (negative: interpenetrating), world units
  Vec3 force_on_a_n{Vec3::Zero()};  ///< the response's force on a (b receives its opposite), N
};

/// The contacts of the last pass.
struct BodyContactsView {
  bool enabled{false};  ///< the session has contact between bodies on
  double time_s{0.0};   ///< simulated time of the step that followed the pass, s
  std::vector<BodyContactView> contacts;
};

}  // namespace hof::coupling
