#include "hof/scene/project.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace hof::scene {
namespace {

std::string bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Project, SaveLoadSaveIsByteIdentical) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_test";
  std::filesystem::create_directories(dir);
  HofProject p;
  p.name = "round trip";
  p.mechanics_scene = "liver.scn";
  p.device = "scripted:circle,radius=0.02";
  p.renderer = haptics::RendererKind::kGodObject;
  p.proxy_radius_m = 0.003;
  p.surface.kind = haptics::SurfaceKind::kMagnetic;
  p.surface.stiffness = 0.1 + 0.2;  // not exactly representable: shortest round trip must hold
  p.position_calibration[0] = 3.0;
  p.graphics.viewpoint_m = Vec3(0.1, -0.4, 1.0 / 3.0);
  ASSERT_TRUE(write_project(p, dir / "a.hof"));
  auto loaded = read_project(dir / "a.hof");
  ASSERT_TRUE(loaded) << loaded.error().to_string();
  ASSERT_TRUE(write_project(*loaded, dir / "b.hof"));
  EXPECT_EQ(bytes(dir / "a.hof"), bytes(dir / "b.hof"));
  EXPECT_EQ(loaded->surface.stiffness, 0.1 + 0.2);
  EXPECT_EQ(loaded->graphics.viewpoint_m, p.graphics.viewpoint_m);
  EXPECT_EQ(loaded->renderer, haptics::RendererKind::kGodObject);
  std::filesystem::remove_all(dir);
}

TEST(Project, BundledExamplesRoundTrip) {
  for (const auto& entry : std::filesystem::directory_iterator(HOF_SOURCE_DIR "/examples")) {
    if (entry.path().extension() != ".hof") continue;
    auto p = read_project(entry.path());
    ASSERT_TRUE(p) << p.error().to_string();
    EXPECT_EQ(to_xml(*p), bytes(entry.path())) << entry.path() << " is not in canonical form";
  }
}

TEST(Project, ErrorsNameTheFileLineAndAttribute) {
  const auto dir = std::filesystem::temp_directory_path() / "hof_project_errors";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "bad.hof") << "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <haptics hapticRate=\"fast\"/>\n</hof>\n";
  auto p = read_project(dir / "bad.hof");
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().to_string().find("bad.hof:3"), std::string::npos) << p.error().to_string();
  EXPECT_NE(p.error().message.find("hapticRate"), std::string::npos);
  std::ofstream(dir / "broken.hof") << "<hof>\n  <mechanics scene=\"x.scn\">\n</hof>\n";
  p = read_project(dir / "broken.hof");
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("malformed XML"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hof::scene
