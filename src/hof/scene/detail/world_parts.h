#pragma once
/// @file
/// The builder's parts shared by its files (world.cpp, world_x3d.cpp,
/// world_contact.cpp): naming bodies, making a
/// deformable body from a model configuration, reading an X3D scene into a world.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/session.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/mesh.h"
#include "hof/scene/world.h"

namespace hof::scene::detail {

/// Nodes on the border of an open triangle surface (edges used by one triangle only).
[[nodiscard]] std::vector<std::int32_t> border_nodes(const std::vector<mesh::Tri>& triangles);

/// `name`, or `name#2`, `name#3`, ... : names are unique within a world (commands, projects
/// and reports address bodies by name; a USE'd shape or two nodes may share one).
[[nodiscard]] std::string unique_name(const std::vector<coupling::SessionBody>& bodies, const std::string& name);

/// A model as a deformable body: its visual mesh (barycentric) as the touchable surface when
/// it has one, else a hexahedral grid's fine surface, else the boundary of its volume elements,
/// else (a surface model) itself.
[[nodiscard]] Expected<coupling::SessionBody> make_deformable(
    const mechanics::ModelConfig& config, const std::optional<std::filesystem::path>& visual_mesh,
    bool visual_barycentric, const std::optional<mesh::TriMesh>& fine_surface = std::nullopt);

/// An X3D scene's shapes, effects, device settings and viewpoint added to `w`; a scene with
/// nothing to touch opens and says why (World::nothing_to_touch).
[[nodiscard]] Expected<void> add_x3d(World& w, const std::filesystem::path& file);

/// Contact between bodies (world_contact.cpp): the project's <contact> over the scene's settings
/// (w.config.contacts), each body's contact="…", the pairs switched off (by index). Errors name
/// the project file: a pair or a body that is not in the world, a body asked to collide that
/// has no surface.
[[nodiscard]] Expected<void> apply_contact(World& w);

}  // namespace hof::scene::detail
