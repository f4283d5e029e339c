// Parameters by typed id: one name table, names mapped to ids once (an unknown name names the
// closest), and the id and name forms set and read the same slot.

#include "hof/mechanics/model_parameters.h"

#include <gtest/gtest.h>

#include <string>

namespace hof::mechanics {
namespace {

TEST(ModelParameters, EveryIdHasANameThatMapsBackToIt) {
  for (std::size_t i = 0; i < kParameterCount; ++i) {
    const auto id = static_cast<ParameterId>(i);
    const auto back = parameter_id(parameter_name(id));
    ASSERT_TRUE(back) << parameter_name(id);
    EXPECT_EQ(*back, id);
  }
  EXPECT_EQ(parameter_name(ParameterId::kYoungModulus), "youngModulus");
}

TEST(ModelParameters, AnUnknownNameIsAnErrorNamingTheClosest) {
  const auto id = parameter_id("youngsModulus");
  ASSERT_FALSE(id);
  EXPECT_NE(id.error().message.find("closest: youngModulus"), std::string::npos) << id.error().message;
  EXPECT_FALSE(parameter_id("x"));
}

TEST(ModelParameters, TheIdAndTheNameSetTheSameSlot) {
  ModelConfig config;
  config.dt_s = 0.01;
  ASSERT_TRUE(set_parameter(config, "", ParameterId::kDt, 0.002));
  EXPECT_EQ(config.dt_s, 0.002);
  ASSERT_TRUE(set_parameter(config, "", "dt", 0.004));
  EXPECT_EQ(*get_parameter(config, "", ParameterId::kDt), 0.004);
  auto refused = set_parameter(config, "", ParameterId::kDt, -1.0);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("dt = -1 is out of range"), std::string::npos) << refused.error().message;
  EXPECT_EQ(config.dt_s, 0.004) << "unchanged on an error";
  auto misspelt = set_parameter(config, "", "dT", 0.001);
  ASSERT_FALSE(misspelt);
  EXPECT_NE(misspelt.error().message.find("has no parameter 'dT' (closest: dt)"), std::string::npos) << misspelt.error().message;
  EXPECT_FALSE(set_parameter(config, "", ParameterId::kYoungModulus, 1000.0)) << "the model itself has no Young's modulus";
}

}  // namespace
}  // namespace hof::mechanics
