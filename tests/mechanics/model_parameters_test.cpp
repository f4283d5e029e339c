// Parameters by typed reference (component kind and index, parameter id): one name table for
// messages, the reference sets and reads its slot, a component without the parameter and a
// force field that is not there are errors, and the model lists what it accepts.

#include "hof/mechanics/model_parameters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace hof::mechanics {
namespace {

constexpr ComponentRef kModel{ComponentKind::kModel, 0};

TEST(ModelParameters, EveryIdHasAName) {
  for (std::size_t i = 0; i < kParameterCount; ++i) EXPECT_NE(parameter_name(static_cast<ParameterId>(i)), "?") << i;
  EXPECT_EQ(parameter_name(ParameterId::kYoungModulus), "youngModulus");
}

TEST(ModelParameters, AReferenceSetsAndReadsItsSlot) {
  ModelConfig config;
  config.dt_s = 0.01;
  ASSERT_TRUE(set_parameter(config, {kModel, ParameterId::kDt}, 0.002));
  EXPECT_EQ(config.dt_s, 0.002);
  EXPECT_EQ(*get_parameter(config, {kModel, ParameterId::kDt}), 0.002);
  auto refused = set_parameter(config, {kModel, ParameterId::kDt}, -1.0);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("dt = -1 is out of range"), std::string::npos) << refused.error().message;
  EXPECT_EQ(config.dt_s, 0.002) << "unchanged on an error";
  EXPECT_FALSE(set_parameter(config, {kModel, ParameterId::kYoungModulus}, 1000.0))
      << "the model itself has no Young's modulus";
}

TEST(ModelParameters, AComponentWithoutTheParameterOrAMissingForceFieldIsAnError) {
  ModelConfig config;
  config.force_fields.push_back(ForceFieldConfig{});
  config.force_fields[0].name = "springs";
  config.force_fields[0].mesh_springs = MeshSpringConfig{};
  const ComponentRef springs{ComponentKind::kForceField, 0};
  ASSERT_TRUE(set_parameter(config, {springs, ParameterId::kStiffness}, 80.0));
  EXPECT_EQ(config.force_fields[0].mesh_springs->stiffness_n_per_m, 80.0);
  auto wrong = set_parameter(config, {springs, ParameterId::kYoungModulus}, 1000.0);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("force field 'springs' has no parameter 'youngModulus'"), std::string::npos)
      << wrong.error().message;
  auto missing = get_parameter(config, {{ComponentKind::kForceField, 1}, ParameterId::kStiffness});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no force field #1"), std::string::npos) << missing.error().message;
  const auto refs = parameter_refs(config);
  EXPECT_NE(std::ranges::find(refs, ParameterRef{springs, ParameterId::kDamping}), refs.end());
  EXPECT_EQ(std::ranges::find(refs, ParameterRef{springs, ParameterId::kYoungModulus}), refs.end());
  for (const ParameterRef& ref : refs) EXPECT_TRUE(get_parameter(config, ref)) << parameter_name(ref.id);
}

}  // namespace
}  // namespace hof::mechanics
