#pragma once
/// @file
/// A rigid tool with a shape on the stylus — a sphere, a capsule (a shaft with rounded ends) or
/// a closed mesh sampled as small spheres — as a tool of the haptic loop (haptics/tool.h), and
/// its reaction on the tissue (coupling/tool_coupling.h).
///
/// Haptics (ShapedTool::tick), the god-object generalised to the shape (Zilles & Salisbury
/// 1995; with the virtual coupling of Colgate, Stanley & Brown 1995, as CHAI3D, iMSTK and
/// SOFA's LCPForceFeedback couple a constrained tool to the device):
///  - the tool's proxy has the device's orientation (the reading's, which a 3-DOF device leaves
///    at identity, times the project's fixed orientation) and a position of its own;
///  - each tick the proxy moves toward the device tip in sub-moves of at most half the smallest
///    radius (so it cannot pass through a surface between two tests), and after each sub-move
///    is pushed out of every triangle of every layer its shape overlaps (the deepest overlap
///    first, one at a time, a bounded number of pushes); a sub-move it cannot make free is not made (the
///    proxy stays at its last free pose): the tool never ends a tick inside a surface;
///  - the hand feels the coupling spring–damper F = k (p_proxy − x) + b (v_proxy − v) while in
///    contact (k ≤ the device's stable stiffness), and the torque of F shared over the contact
///    points (by how far the hand presses along each normal) about the device point;
///  - the point renderers' forces are replaced (set to zero): the shape renders every surface.
/// The tick allocates nothing and is bounded: candidate triangles are gathered once per tick
/// from each layer's bound tree into a fixed array (kMaxCandidates), sub-moves and passes are
/// capped (kMaxSubMoves, kMaxPushes).
///
/// Tissue (ShapedTissueCoupling): at each step of the body the tool touches most (ToolState::
/// body), the shape (ToolState: tip, orientation, radius, length) is placed on the body's
/// current surface; every triangle within the contact band (radius + the hand's depth) is a
/// contact, weighted by its depth in that band; the reaction −F (the averaged felt force) is
/// shared over the contacts by weight, over each triangle's vertices by the closest point's
/// barycentric weights, and over the nodes through the body's SurfaceMapping: the forces on the
/// tissue sum to −F exactly. A tool touching two bodies gives its whole reaction to the one it
/// touches most (the loop carries one body per tick).
///
/// Closest points: C. Ericson, "Real-Time Collision Detection", Morgan Kaufmann 2005, §5.1.5
/// (point–triangle), §5.1.9 (segment–segment) and §5.1.10 (segment–triangle: an intersection,
/// else the least of the endpoints against the triangle and the segment against its edges).

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/surface_mapping.h"
#include "hof/coupling/tool_coupling.h"
#include "hof/haptics/tool.h"
#include "hof/mesh/mesh.h"

namespace hof::procedures {

enum class ToolShape : std::uint8_t { kSphere, kCapsule, kMesh };
[[nodiscard]] std::string_view shape_name(ToolShape shape);  ///< "sphere", "capsule", "mesh"

/// A project's shaped tool (<tool> in <haptics>). Lengths SI (m).
struct ShapedToolConfig {
  ToolShape shape{ToolShape::kSphere};
  /// Sphere: its radius; capsule: the shaft's; mesh: the radius of the spheres it is sampled
  /// with (0: a hundredth of the mesh's bounding-box diagonal).
  double radius_m{0.005};
  /// Capsule: the shaft's length from the tip (the centre of the tip's cap) back along the
  /// stylus, m.
  double length_m{0.05};
  std::string mesh;  ///< mesh: the OBJ/STL file (closed), in the tool's frame (tip at the origin)
  /// Fixed orientation of the tool on the stylus, an X3D SFRotation (axis x y z, angle rad):
  /// at identity the tool points along −z (into the screen) and its shaft runs along +z.
  std::array<double, 4> orientation{0.0, 0.0, 1.0, 0.0};
  /// Coupling stiffness, N/m; 0 (default): the device's stable stiffness. Never above it.
  double stiffness_n_per_m{0.0};
  double damping_n_s_per_m{2.0};  ///< coupling damping, N·s/m
  std::string device;             ///< reserved: the device that carries it (two hands, later)
  bool operator==(const ShapedToolConfig&) const = default;
};
/// Checks the numbers (radius > 0 for a sphere or capsule, ≥ 0 for a mesh; length ≥ 0, finite;
/// a non-zero rotation axis; a mesh file named for a mesh tool). Errors name the attribute.
[[nodiscard]] Expected<void> validate(const ShapedToolConfig& config);

/// A mesh tool's surface from an OBJ/STL (any format mesh_io reads): its triangles, which must
/// form a closed, outward-oriented 2-manifold. Errors name the file and what is wrong.
[[nodiscard]] Expected<mesh::TriMesh> read_tool_mesh(const std::filesystem::path& path);

/// One part of a shape in the tool's frame: the points within `radius` of the segment a–b (a
/// sphere when a = b).
struct ToolPrimitive {
  Vec3 a{Vec3::Zero()};
  Vec3 b{Vec3::Zero()};
  double radius{0.0};
};

/// The closest points of segment a–b and triangle (p0, p1, p2) (Ericson §5.1.10). Writes the
/// point on the segment, the point on the triangle and its barycentric weights; returns their
/// distance (0 when they intersect). A degenerate triangle returns +∞.
double closest_segment_triangle(const Vec3& a, const Vec3& b, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                Vec3& on_segment, Vec3& on_triangle, Vec3& barycentric);

class ShapedTool final : public haptics::Tool {
 public:
  static constexpr int kMaxSubMoves = 8;
  static constexpr int kMaxPushes = 12;                // deepest-first push-outs per sub-move
  static constexpr std::size_t kMaxCandidates = 4096;  // triangles gathered per tick (all layers)
  static constexpr std::size_t kMaxContacts = 64;      // contact points kept for the torque
  static constexpr std::size_t kMaxPrimitives = 256;   // a mesh tool's spheres
  static constexpr std::size_t kMaxBodies = 64;        // bodies counted for "the body touched most"

  /// `mesh` is the tool's surface for a mesh tool (read and checked by the caller), in metres.
  /// `metres_per_unit` is the world's length unit in metres (1e-3 for a scene in mm).
  static Expected<std::shared_ptr<ShapedTool>> make(const ShapedToolConfig& config, const mesh::TriMesh* mesh = nullptr,
                                                    double metres_per_unit = 1.0);

  Vec3 tick(const haptics::ToolTickInput& input, std::span<Vec3> layer_forces, haptics::ToolState& state) override;
  void restart() override;

  [[nodiscard]] const ShapedToolConfig& config() const { return config_; }
  /// The shape in the tool's frame, world units.
  [[nodiscard]] std::span<const ToolPrimitive> primitives() const { return primitives_; }
  [[nodiscard]] double metres_per_unit() const { return metres_per_unit_; }
  /// The proxy's tip (world), for tests and drawing.
  [[nodiscard]] const Vec3& proxy() const { return proxy_; }

 private:
  ShapedTool(const ShapedToolConfig& config, std::vector<ToolPrimitive> primitives, double metres_per_unit);
  struct Candidate {
    const haptics::SurfaceSnapshot* surface{nullptr};
    std::int32_t triangle{-1};
    Vec3 centre{Vec3::Zero()};  // of the triangle's bounding sphere
    double radius{0.0};
    Vec3 normal{Vec3::Zero()};  // unit face normal (zero: degenerate)
    double offset{0.0};         // normal · a vertex
  };
  // The constraint normals met by this tick's pushes (the god-object's planes).
  static constexpr std::size_t kMaxPlanes = 4;
  struct Planes {
    std::array<Vec3, kMaxPlanes> normal{};
    std::size_t count{0};
    void add(const Vec3& n);
  };
  void gather(const haptics::ToolTickInput& in, const Mat3& r, const Vec3& from, const Vec3& to);
  // A primitive's axis placed in the world, for many distance tests in a row.
  struct Segment {
    Segment(const Vec3& from, const Vec3& to);
    [[nodiscard]] double distance_squared(const Vec3& p) const;
    Vec3 a, b, d;
    double inv_length_squared;  // 0 for a point
  };
  // Whether segment s of `radius` may come closer than `radius − slack` to the candidate
  // (cheap: the triangle's plane, then its bounding sphere; no division, no root).
  [[nodiscard]] static bool may_reach(const Candidate& c, const Segment& s, double radius, double slack);
  // Pushes `position` out of every candidate (shape at rotation `r`), the deepest overlap
  // first; the push directions go to `planes`. False when it cannot.
  bool resolve(Vec3& position, const Mat3& r, const Vec3& reference, Planes& planes) const;
  // The deepest overlap of the shape at (position, r) with any candidate.
  [[nodiscard]] double deepest(const Vec3& position, const Mat3& r) const;

  ShapedToolConfig config_;
  std::vector<ToolPrimitive> primitives_;
  double metres_per_unit_{1.0};
  Eigen::Quaterniond fixed_{Eigen::Quaterniond::Identity()};
  Vec3 bound_centre_{Vec3::Zero()};    // of the shape's bounding sphere, tool frame
  double bound_radius_{0.0};           // its radius, world units
  double max_step_{0.0};               // sub-move length, world units
  double tolerance_{0.0};              // overlap accepted as touching, world units
  std::vector<Candidate> candidates_;  // sized at make(): kMaxCandidates
  std::size_t candidate_count_{0};
  // Tick state.
  bool initialised_{false};
  Vec3 proxy_{Vec3::Zero()};
  Vec3 last_proxy_{Vec3::Zero()};
  Vec3 proxy_velocity_{Vec3::Zero()};  // low-passed (see kProxyVelocityTimeConstant_s), world units/s
};

/// A body's surface as the coupling needs it: triangles over surface vertices, and how those
/// vertices follow the body's nodes.
struct ToolBodySurface {
  std::vector<mesh::Tri> triangles;
  std::size_t vertex_count{0};
  coupling::SurfaceMapping mapping;
};

class ShapedTissueCoupling final : public coupling::ToolTissueCoupling {
 public:
  /// `bodies` by world body index (a body without triangles receives nothing).
  ShapedTissueCoupling(std::shared_ptr<const ShapedTool> tool, std::vector<ToolBodySurface> bodies);
  void add_tissue_forces(const haptics::ToolState& tool, const mechanics::MechanicalModel& model,
                         const mechanics::MechanicalState& state, std::span<double> forces) override;
  /// One contact of the last call, for tests.
  struct Contact {
    std::int32_t triangle{-1};
    Vec3 barycentric{Vec3::Zero()};
    Vec3 point{Vec3::Zero()};
    double weight{0.0};
  };
  [[nodiscard]] const std::vector<Contact>& last_contacts() const { return contacts_; }

 private:
  std::shared_ptr<const ShapedTool> tool_;
  std::vector<ToolBodySurface> bodies_;
  std::vector<Vec3> positions_;    // scratch: the body's surface now
  std::vector<Contact> contacts_;  // scratch
};

}  // namespace hof::procedures
