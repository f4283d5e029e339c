#pragma once
/// @file
/// Contact between bodies, as the scene asks for it (typed: the strings of a SOFA collision
/// pipeline or a `.hof` `<contact>` element end in scene/). SessionConfig::contacts holds the
/// world's settings, SessionBody::collision each body's collision models.
///
/// Interface agreed before the implementation (issue 37).

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::coupling {

/// SOFA's contact responses (CollisionResponse `response`).
enum class ContactResponse : std::uint8_t {
  kPenalty,             ///< PenalityContactForceField: springs at the contact points, in the implicit solve
  kFrictionConstraint,  ///< FrictionContactConstraint: Coulomb friction, solved over the bodies' compliance
};

/// The world's contact settings (SOFA: CollisionPipeline + intersection method + response).
struct ContactSettings {
  bool enabled{false};  ///< false: bodies pass through each other (only the tools touch them)
  ContactResponse response{ContactResponse::kPenalty};
  double alarm_distance_m{0.0};    ///< SOFA alarmDistance: closer pairs are detected, m (≥ contact distance)
  double contact_distance_m{0.0};  ///< SOFA contactDistance: the gap the response keeps, m
  double stiffness_n_per_m{0.0};   ///< penalty stiffness per contact (a body's own overrides), N/m
  double friction{0.0};            ///< Coulomb μ (SOFA responseParams "mu=…"), ≥ 0
  bool self_collision{false};      ///< default for bodies that do not say
  /// Pairs of bodies (indices into the session's bodies, smaller first) switched off.
  std::vector<std::pair<std::int32_t, std::int32_t>> disabled_pairs;
};

/// One body's collision models (a SOFA node's Triangle/Line/Point/SphereCollisionModel).
struct BodyCollision {
  bool enabled{false};  ///< the body takes part in contact between bodies
  bool triangles{true};
  bool lines{true};
  bool points{true};
  /// SphereCollisionModel: centres at rest (world frame, m) and radii (m). The coupling maps
  /// the centres through the body's volume (barycentric, as SOFA's `BarycentricMapping`).
  std::vector<Vec3> sphere_centers;
  std::vector<double> sphere_radii;
  bool moving{true};
  bool simulated{true};
  std::int32_t group{-1};                   ///< SOFA `group`; −1: none
  std::optional<bool> self_collision;       ///< unset: ContactSettings::self_collision
  std::optional<double> stiffness_n_per_m;  ///< SOFA `contactStiffness` on the model
};

}  // namespace hof::coupling
