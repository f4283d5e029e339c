// A scene's parameter names become typed references once, here: every name maps to its id
// and back, components are found in the documented order, and each way a name can be wrong
// is an error that says what there is instead.

#include "hof/scene/model_parameters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace hof::scene {
namespace {

using mechanics::ComponentKind;
using mechanics::ParameterId;
using mechanics::ParameterRef;

// A model with named components: springs and a membrane, an ODE solver, a linear solver, a mass.
mechanics::ModelConfig named_model() {
  mechanics::ModelConfig c;
  c.name = "Liver";
  mechanics::ForceFieldConfig springs;
  springs.name = "springs";
  springs.mesh_springs = mechanics::MeshSpringConfig{};
  mechanics::ForceFieldConfig membrane;
  membrane.name = "skin";
  membrane.triangle_fem = mechanics::TriangleFemConfig{};
  c.force_fields = {springs, membrane};
  c.ode.name = "odesolver";
  c.linear.name = "cg";
  c.mass.name = "mass";
  return c;
}

TEST(SceneParameters, EveryIdHasANameThatMapsBackToIt) {
  for (std::size_t i = 0; i < mechanics::kParameterCount; ++i) {
    const auto id = static_cast<ParameterId>(i);
    const auto back = parameter_id(mechanics::parameter_name(id));
    ASSERT_TRUE(back) << mechanics::parameter_name(id);
    EXPECT_EQ(*back, id);
  }
}

TEST(SceneParameters, AnUnknownNameIsAnErrorNamingTheClosest) {
  const auto id = parameter_id("youngsModulus");
  ASSERT_FALSE(id);
  EXPECT_NE(id.error().message.find("closest: youngModulus"), std::string::npos) << id.error().message;
  EXPECT_FALSE(parameter_id("x"));
}

TEST(SceneParameters, NamesResolveToTheComponentAndTheParameter) {
  const mechanics::ModelConfig c = named_model();
  EXPECT_EQ(*resolve_parameter(c, "", "dt"), (ParameterRef{{ComponentKind::kModel, 0}, ParameterId::kDt}));
  EXPECT_EQ(*resolve_parameter(c, "skin", "thickness"),
            (ParameterRef{{ComponentKind::kForceField, 1}, ParameterId::kThickness}));
  EXPECT_EQ(*resolve_parameter(c, "odesolver", "rayleighMass"),
            (ParameterRef{{ComponentKind::kOdeSolver, 0}, ParameterId::kRayleighMass}));
  EXPECT_EQ(*resolve_parameter(c, "cg", "iterations"),
            (ParameterRef{{ComponentKind::kLinearSolver, 0}, ParameterId::kIterations}));
  EXPECT_EQ(*resolve_parameter(c, "mass", "totalMass"),
            (ParameterRef{{ComponentKind::kMass, 0}, ParameterId::kTotalMass}));
  const auto ref = *resolve_parameter(c, "springs", "damping");
  EXPECT_EQ(parameter_path(c, ref), "springs/damping");
  EXPECT_EQ(parameter_path(c, *resolve_parameter(c, "", "gravityZ")), "/gravityZ");
}

TEST(SceneParameters, AForceFieldIsFoundBeforeASolverOfTheSameName) {
  mechanics::ModelConfig c = named_model();
  c.ode.name = "springs";
  EXPECT_EQ(resolve_parameter(c, "springs", "stiffness")->component.kind, ComponentKind::kForceField);
  // The force field has no Rayleigh damping: the solver of the same name is not tried.
  EXPECT_FALSE(resolve_parameter(c, "springs", "rayleighMass"));
}

TEST(SceneParameters, NoSuchComponentNamesTheModelsParameters) {
  const auto refused = resolve_parameter(named_model(), "nope", "youngModulus");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("no component 'nope' (parameters: dt, maxSpeed"), std::string::npos)
      << refused.error().message;
  EXPECT_NE(refused.error().message.find("skin/thickness"), std::string::npos) << refused.error().message;
}

TEST(SceneParameters, AnUnknownParameterNameNamesTheComponentAndTheClosest) {
  const auto refused = resolve_parameter(named_model(), "skin", "youngsModulus");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("force field 'skin' has no parameter 'youngsModulus' (closest: youngModulus)"),
            std::string::npos)
      << refused.error().message;
  const auto own = resolve_parameter(named_model(), "", "dT");
  ASSERT_FALSE(own);
  EXPECT_NE(own.error().message.find("has no parameter 'dT' (closest: dt)"), std::string::npos) << own.error().message;
}

TEST(SceneParameters, AParameterTheComponentDoesNotHaveIsAnError) {
  const auto refused = resolve_parameter(named_model(), "springs", "youngModulus");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("force field 'springs' has no parameter 'youngModulus'"), std::string::npos)
      << refused.error().message;
  EXPECT_FALSE(resolve_parameter(named_model(), "cg", "totalMass"));
  EXPECT_FALSE(resolve_parameter(named_model(), "", "youngModulus"));
}

TEST(SceneParameters, TheNamesListedAreTheNamesAccepted) {
  mechanics::ModelConfig c = named_model();
  const auto names = parameter_names(c);
  EXPECT_EQ(names.front(), "dt");
  EXPECT_EQ(names.back(), "/gravityZ");
  EXPECT_NE(std::ranges::find(names, "cg/coarseRefreshSteps"), names.end());
  for (const std::string& name : names) {
    const auto slash = name.find('/');
    const std::string component = slash == std::string::npos ? std::string() : name.substr(0, slash);
    const std::string parameter = slash == std::string::npos ? name : name.substr(slash + 1);
    EXPECT_TRUE(resolve_parameter(c, component, parameter)) << name;
  }
  ASSERT_TRUE(set_parameter(c, "springs", "stiffness", 80.0));
  EXPECT_EQ(*get_parameter(c, "springs", "stiffness"), 80.0);
  EXPECT_FALSE(set_parameter(c, "springs", "stiffness", -1.0));
}

}  // namespace
}  // namespace hof::scene
