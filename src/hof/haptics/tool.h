#pragma once
/// @file
/// The tool seam of the haptic loop: a tool (a needle, later forceps or a scalpel) is a stylus
/// with more than a point. Each tick, after the surfaces are rendered and before the force
/// effects and the safety filter, the loop hands the tool the device's reading and every
/// layer's contact; the tool may take over the surface force of what it pierces (a zero-force
/// surface, as the thesis' LiverSurface) and adds its own force. What it did is a small,
/// fixed-size ToolState, published with the tick's sample (telemetry, the window) and its
/// contact (the simulation, whose per-step hook turns it into forces on the tissue: see
/// coupling/tool_coupling.h). The loop knows no tool in particular.

#include <Eigen/Geometry>
#include <cstdint>
#include <span>

#include "hof/core/types.h"
#include "hof/haptics/haptic_renderer.h"
#include "hof/haptics/surface_snapshot.h"

namespace hof::haptics {

/// What a tool did in one tick (world frame, SI). A plain value: copied into samples and
/// contacts, never allocated.
struct ToolState {
  bool active{false};                  ///< a tool is mounted (false: the columns below mean nothing)
  std::uint8_t phase{0};               ///< the tool's own phase number (procedures::NeedlePhase for the needle)
  bool touched{false};                 ///< the tool is in contact with a body it can enter
  bool broken{false};                  ///< the body's capsule (its outer layer) is broken
  std::int32_t body{-1};               ///< the world's body index the tool is in (or touches), -1: none
  std::int32_t layer{-1};              ///< the haptic layer of that body
  double depth_m{0.0};                 ///< tip depth along the axis below the entry point, m
  double axial_force_n{0.0};           ///< the model's force along the axis; > 0 resists insertion
  double axial_velocity_m_per_s{0.0};  ///< the tool's (filtered) velocity along the axis, > 0 inward
  Vec3 tip{Vec3::Zero()};              ///< the tool's tip
  Vec3 entry{Vec3::Zero()};            ///< where it entered the body (fixed at first contact)
  Vec3 axis{Vec3::Zero()};             ///< unit insertion direction (into the body)
  Vec3 normal{Vec3::Zero()};           ///< the surface's outward normal at the entry point
  Vec3 force{Vec3::Zero()};            ///< the tool's force on the hand (axial and lateral), N
  // A tool with a shape (procedures/shaped_tool.h): its pose and dimensions, so that the
  // simulation can place it on the tissue, and what it touched.
  Vec3 torque{Vec3::Zero()};                                       ///< about the device point, N·(world unit)
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};  ///< the tool's orientation (world)
  double radius{0.0};                                              ///< the shape's radius, world units
  double length{0.0};                                              ///< a capsule's shaft, world units
  std::int32_t contact_count{0};                                   ///< contact points this tick
};

/// What the loop gives a tool each tick.
struct ToolTickInput {
  double time_s{0.0};
  double dt_s{0.001};
  Vec3 position{Vec3::Zero()};  ///< the device's position in the world (the tool's tip)
  Vec3 velocity{Vec3::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};  ///< device orientation, world
  std::span<const ContactState> contacts;                          ///< each layer's contact this tick
  std::span<const SurfaceSnapshot* const> surfaces;                ///< each layer's snapshot (null: none yet)
  double max_stiffness_n_per_m{3000.0};                            ///< the device's stable stiffness, N per world unit
};

class Tool {
 public:
  Tool() = default;
  Tool(const Tool&) = delete;
  Tool& operator=(const Tool&) = delete;
  virtual ~Tool() = default;

  /// One tick, on the haptic thread: no allocation, no lock, no I/O. `layer_forces` holds each
  /// layer's surface force; the tool may change it (zero for a body it pierces). Returns the
  /// tool's own force on the hand (world frame, N) and fills `state`.
  virtual Vec3 tick(const ToolTickInput& input, std::span<Vec3> layer_forces, ToolState& state) = 0;
  /// The stylus jumped (a device switch, a new calibration): forget any contact.
  virtual void restart() = 0;
};

}  // namespace hof::haptics
