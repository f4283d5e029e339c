#pragma once
/// @file
/// A non-owning view of a triangle surface (vertex positions in metres, triangles as vertex
/// indices), the input of every collision query. Triangles wind counter-clockwise seen from
/// the front (outside); the front normal is (b−a)×(c−a).

#include <cstdint>
#include <span>

#include "hof/core/types.h"
#include "hof/mesh/mesh.h"

namespace hof::collision {

struct TriangleMeshView {
  std::span<const Vec3> vertices;        ///< (V) m
  std::span<const mesh::Tri> triangles;  ///< (F)
};

/// Which sides of a triangle can be touched (H3D HapticsOptions.touchableFace).
enum class TouchableFace : std::uint8_t {
  kFront,         ///< only from the side the normal points to
  kBack,          ///< only from behind
  kFrontAndBack,  ///< both
};

/// Nearest point of the surface to a query point.
struct ClosestPoint {
  std::int32_t triangle{-1};       ///< −1 when nothing lies within the search distance
  Vec3 point{Vec3::Zero()};        ///< on the triangle, m
  Vec3 barycentric{Vec3::Zero()};  ///< weights of the triangle's vertices a, b, c (sum 1)
  double distance{0.0};            ///< m
};

/// First contact along a motion (segment a→b, or a sphere swept along it).
struct SweepHit {
  std::int32_t triangle{-1};       ///< −1 when the motion is free
  double t{1.0};                   ///< fraction of the motion at first contact, in [0, 1]
  Vec3 point{Vec3::Zero()};        ///< contact point on the triangle, m
  Vec3 barycentric{Vec3::Zero()};  ///< of `point` in the triangle
  Vec3 normal{Vec3::Zero()};       ///< unit contact normal, pointing toward the moving point/sphere
  bool front{true};                ///< whether the front face was hit
};

}  // namespace hof::collision
