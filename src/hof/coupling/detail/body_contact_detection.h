#pragma once
/// @file
/// What the two responses to contact between bodies share (body_contact_pass.h, penalty;
/// body_contact_constraints.h, friction constraints): the bodies that take part, their views
/// for collision::ContactDetector (surfaces, sphere models mapped through the volume, the
/// previous surfaces for continuous detection), the switched-off pairs, and the map from a
/// contact point to the nodes that carry it (surface weights → nodes through the body's
/// SurfaceMapping, or through the sphere centres' own mapping).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "hof/collision/body_contacts.h"
#include "hof/coupling/session.h"
#include "hof/coupling/surface_mapping.h"

namespace hof::coupling::detail {

struct World;

/// Room the contact passes keep for contacts at the start (their lists grow past it only when
/// a pass finds more).
inline constexpr std::size_t kInitialContactCapacity = 4096;

class BodyContactDetection {
 public:
  /// Sets detection up for the world's bodies taking part (their detector trees, the sphere
  /// centres' mappings): allocates.
  void init(World& world);

  /// Before a pass: a body whose state went back (a reset, another model) forgets its previous
  /// surface (a jump back to rest is not a crossing), and the sphere centres follow the nodes.
  void begin_pass(World& world);
  /// Detection over the bodies' current surfaces: fills `contacts` (cleared first) with the
  /// contacts closer than `within` (m; +∞: every contact within the alarm distance), body
  /// indices the world's, switched-off pairs left out. No allocation once `contacts` and the
  /// detector's list have grown.
  void detect(World& world, double within, std::vector<collision::BodyContact>& contacts);
  /// After a pass: the surfaces as they are now are the next pass's previous ones.
  void end_pass(World& world);

  /// The nodes (and weights, summing to 1) of the world body `side.body` that carry the
  /// point; 0 when it has none (a rigid body, a sphere that could not be mapped). At most
  /// SurfaceMapping::kMaxPointWeights.
  std::size_t point_weights(const World& world, const collision::ContactPoint& side, std::span<std::int32_t> nodes,
                            std::span<double> weights) const;

  /// The world indices of the bodies taking part.
  template <typename F>
  void for_each_body(F&& f) const {
    for (const Member& m : members_) f(m.body);
  }

  /// Puts one pass's figures in the reports: each body taking part gets its contact count and
  /// total force (`contact_count`, `force_sum` by world body index) and its largest so far;
  /// the session's report the pass's `contacts` and its largest. The penalty and the
  /// constraint pass report alike.
  void report_pass(World& world, std::span<const std::int64_t> contact_count, std::span<const Vec3> force_sum,
                   std::size_t contacts, SessionReport& report) const;

  /// Switches the contact of bodies `a` and `b` (world indices) off or on from the next pass
  /// (command::SetContactPair). Nothing for indices outside the world set up by init().
  void set_pair_enabled(std::size_t a, std::size_t b, bool enabled) {
    const std::size_t n = bodies_;
    if (a >= n || b >= n) return;
    pair_disabled_[a * n + b] = pair_disabled_[b * n + a] = enabled ? 0 : 1;
  }

 private:
  struct Member {
    std::size_t body{0};            // index into World::bodies
    std::vector<Vec3> previous;     // its surface at the last pass (continuous detection)
    std::vector<Vec3> spheres;      // its sphere centres now
    SurfaceMapping sphere_mapping;  // deformable bodies with spheres: volume → centres
    bool spheres_mapped{false};
    std::int64_t steps_seen{0};  // its state's step count at the last pass (a drop: a reset)
  };

  std::vector<Member> members_;
  std::vector<std::int32_t> member_of_;  // (bodies) member index of each world body, −1: none
  std::vector<collision::CollisionBody> views_;
  collision::ContactDetector detector_;
  std::vector<collision::BodyContact> detected_;
  std::size_t bodies_{0};                    // the world's bodies at init()
  std::vector<std::uint8_t> pair_disabled_;  // (bodies²) the settings' disabled pairs
};

}  // namespace hof::coupling::detail
