// A panel's typed edit checked in memory (scene::check_edit) as the file's reader checks the
// same value given as text (parse_project_edit): the two accept and refuse alike, with the
// reader's words.

#include "hof/scene/project_edit.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace hof::scene {
namespace {

// A project with a needle (a common tissue set and one body's) and a spring effect.
HofProject project_with_needle_and_a_spring() {
  HofProject p;
  p.needle = procedures::NeedleConfig{};
  p.needle->bodies.emplace_back("Liver", procedures::TissueNeedleParameters{});
  p.effects.springs.emplace_back();
  return p;
}

struct Case {
  std::string element, attribute;
  double value;
  std::function<ProjectEdit(const HofProject&, double)> typed;  // the same change, made in memory
};

TEST(CheckEdit, AcceptsAndRefusesAsTheReaderDoesWithItsWords) {
  const HofProject p = project_with_needle_and_a_spring();
  const auto needle = [](auto change) {
    return [change](const HofProject& q, double v) -> ProjectEdit {
      procedures::NeedleConfig n = *q.needle;
      change(n, v);
      return project_edit::Needle{n};
    };
  };
  std::vector<Case> cases;
  for (const double v : {-0.1, 0.0, 0.5, 1.5}) {
    cases.push_back({"haptics/needle", "velocityFilter", v,
                     needle([](procedures::NeedleConfig& n, double x) { n.velocity_filter_s = x; })});
  }
  for (const double v : {-0.01, 0.02}) {
    cases.push_back({"haptics/needle/tissue", "capsule", v,
                     needle([](procedures::NeedleConfig& n, double x) { n.tissue.capsule_m = x; })});
    cases.push_back({"haptics/needle/tissue[2]", "punctureForce", v,
                     needle([](procedures::NeedleConfig& n, double x) { n.bodies[0].second.puncture_force_n = x; })});
  }
  for (const double v : {-1.0, 0.0, 3.0}) {
    cases.push_back({"haptics/safety", "maxForce", v,
                     [](const HofProject&, double x) -> ProjectEdit { return project_edit::ForceLimit{x}; }});
  }
  for (const double v : {-1.0, 0.5}) {
    cases.push_back({"haptics/surface", "stiffness", v, [](const HofProject& q, double x) -> ProjectEdit {
                       haptics::SurfaceMaterial s = q.surface;
                       s.stiffness = x;
                       return project_edit::Surface{s};
                     }});
    cases.push_back(
        {"haptics/effects/SpringEffect", "springConstant", 100.0 * v, [](const HofProject& q, double x) -> ProjectEdit {
           haptics::ForceEffects e = q.effects;
           e.springs[0].spring_constant_n_per_m = x;
           return project_edit::Effects{e};
         }});
  }
  std::vector<std::string> refused;
  for (const Case& c : cases) {
    const std::string text = fmt::format("{}", c.value);
    SCOPED_TRACE(fmt::format("{}@{} {}", c.element, c.attribute, text));
    const auto parsed = parse_project_edit(p, "memory.hof", c.element, c.attribute, text);
    const auto checked = check_edit(p, c.typed(p, c.value));
    ASSERT_EQ(parsed.has_value(), checked.has_value()) << (parsed ? checked.error().message : parsed.error().message);
    if (parsed) {
      // The typed edit is the one the text makes.
      HofProject from_text = p, typed = p;
      apply_edit(from_text, *parsed);
      apply_edit(typed, c.typed(p, c.value));
      EXPECT_EQ(to_xml(from_text), to_xml(typed));
      continue;
    }
    refused.push_back(fmt::format("{}@{} {}", c.element, c.attribute, text));
    EXPECT_EQ(checked.error().code, ErrorCode::kInvalidArgument);
    EXPECT_TRUE(parsed.error().message.ends_with(checked.error().message))
        << parsed.error().message << "\n vs " << checked.error().message;
  }
  // (The reader takes a spring effect's constant of either sign: both accept -100.)
  const std::vector<std::string> expected{
      "haptics/needle@velocityFilter -0.1",  "haptics/needle@velocityFilter 1.5",
      "haptics/needle/tissue@capsule -0.01", "haptics/needle/tissue[2]@punctureForce -0.01",
      "haptics/safety@maxForce -1",          "haptics/surface@stiffness -1"};
  EXPECT_EQ(refused, expected);
}

TEST(CheckEdit, ATissueSetForABodyMustNameIt) {
  HofProject p = project_with_needle_and_a_spring();
  procedures::NeedleConfig n = *p.needle;
  n.bodies[0].first.clear();
  const auto checked = check_edit(p, project_edit::Needle{n});
  ASSERT_FALSE(checked);
  EXPECT_NE(checked.error().message.find("name the body"), std::string::npos) << checked.error().message;
  EXPECT_TRUE(check_edit(p, project_edit::Needle{*p.needle})) << "the project's own needle is valid";
}

TEST(CheckEdit, AnEmptyDeviceIsRefusedAndTheProjectIsNotChanged) {
  const HofProject p = project_with_needle_and_a_spring();
  const std::string before = to_xml(p);
  EXPECT_FALSE(check_edit(p, project_edit::Device{""}));
  EXPECT_TRUE(check_edit(p, project_edit::Device{"mouse"}));
  EXPECT_EQ(to_xml(p), before);
}

TEST(CheckEdit, AToolIsCheckedAsTheReaderChecksItAndTakesTheNeedlesPlace) {
  HofProject p = project_with_needle_and_a_spring();
  procedures::ShapedToolConfig capsule;
  capsule.shape = procedures::ToolShape::kCapsule;
  capsule.radius_m = 0.006;
  capsule.length_m = 0.08;
  ASSERT_TRUE(check_edit(p, project_edit::Tool{capsule}));
  procedures::ShapedToolConfig bad = capsule;
  bad.radius_m = -0.001;
  const auto refused = check_edit(p, project_edit::Tool{bad});
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("radius"), std::string::npos) << refused.error().message;
  procedures::ShapedToolConfig no_file = capsule;
  no_file.shape = procedures::ToolShape::kMesh;
  EXPECT_FALSE(check_edit(p, project_edit::Tool{no_file})) << "a mesh tool names its file";
  // Mounted, it replaces the needle (one tool on the stylus); nullopt takes it off.
  apply_edit(p, project_edit::Tool{capsule});
  ASSERT_TRUE(p.tool);
  EXPECT_EQ(*p.tool, capsule);
  EXPECT_FALSE(p.needle);
  EXPECT_TRUE(check_edit(p, project_edit::Tool{std::nullopt}));
  apply_edit(p, project_edit::Tool{std::nullopt});
  EXPECT_FALSE(p.tool);
}

}  // namespace
}  // namespace hof::scene
