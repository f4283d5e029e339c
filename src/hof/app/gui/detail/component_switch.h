#pragma once
/// @file
/// The scene tree's components: each body's rows as a SOFA scene lists them, the types a
/// component can be switched to, and the edit that switches it (with the values that carry
/// over: E, ν, masses).

#include <string>
#include <utility>
#include <vector>

#include "hof/core/error.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/scene/sofa_scene_edit.h"

namespace hof::app::gui {

/// The types a component of each role can be switched to.
extern const std::vector<std::string> kOdeSolvers;
extern const std::vector<std::string> kLinearSolvers;
extern const std::vector<std::string> kMasses;
extern const std::vector<std::string> kForceFields;

/// E (Pa) and ν of a model's first FEM force field (SOFA's defaults otherwise).
[[nodiscard]] std::pair<double, double> elastic_moduli(const mechanics::ModelConfig& c);
/// The mean edge of the model's tetrahedra (m; 0.01 without any).
[[nodiscard]] double mean_edge_length(const mechanics::ModelConfig& c);
/// The scene-tree rows of a model: each component with its SOFA type, in the order a scene
/// lists them ("" is the node itself: dt, gravity, ...).
[[nodiscard]] std::vector<std::pair<std::string, std::string>> components_of(const mechanics::ModelConfig& c);
/// The edit that makes `component` of body `body` (model `c`) a `choice` (one of the lists
/// above).
[[nodiscard]] Expected<scene::SceneEdit> switch_edit(const mechanics::ModelConfig& c, const std::string& body,
                                                     const std::string& component, const std::string& choice);

}  // namespace hof::app::gui
