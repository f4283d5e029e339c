// The default probe: where it goes when a world has force effects only.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hof/coupling/session.h"
#include "hof/scene/device_config.h"
#include "hof/scene/world.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "hof_default_probe_test";
  fs::create_directories(dir);
  const fs::path file = dir / name;
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

// The largest force the default probe feels in `seconds` of the world of `file`, N.
double largest_force(const fs::path& file, double seconds) {
  auto world = build_world(file);
  EXPECT_TRUE(world) << world.error().to_string();
  if (!world) return 0.0;
  EXPECT_TRUE(world->default_probe);
  auto device = open_device(world->device);
  EXPECT_TRUE(device) << device.error().to_string();
  if (!device) return 0.0;
  coupling::SessionConfig config = world->config;
  config.haptics.realtime_priority = false;
  auto session = coupling::Session::make(std::move(world->bodies), std::move(*device), config);
  EXPECT_TRUE(session) << session.error().to_string();
  if (!session) return 0.0;
  double largest = 0.0;
  (*session)->run_virtual(seconds,
                          [&](const haptics::HapticSample& s) { largest = std::max(largest, s.force.norm()); });
  return largest;
}

TEST(DefaultProbe, EffectsCentreIsASpringsAnchorThenAboveAMagnetThenTheOrigin) {
  haptics::ForceEffects effects;
  EXPECT_EQ(default_probe_effects_centre(effects), Vec3::Zero());
  haptics::MagneticGeometryEffect magnet;
  auto surface = std::make_shared<mesh::TriMesh>();
  surface->vertices = {Vec3(1, 0, 0), Vec3(1, 0.3, 0), Vec3(1.2, 0.1, 0)};
  surface->triangles = {{0, 1, 2}};
  magnet.surface = surface;
  effects.magnets.push_back(magnet);
  EXPECT_EQ(default_probe_effects_centre(effects), Vec3(1, 0.305, 0));
  effects.springs.push_back(haptics::SpringEffect{.position_m = Vec3(0, 0, 2)});
  EXPECT_EQ(default_probe_effects_centre(effects), Vec3(0, 0, 2));
}

// Before, the probe circled around the origin and never came near a magnet placed elsewhere:
// a first run of such a scene felt nothing.
TEST(DefaultProbe, AMagnetAwayFromTheOriginIsFelt) {
  const fs::path file = write("magnet.x3d", R"(<X3D profile='H3DAPI' version='1.4'><Scene>
<Transform translation='0.3 0.1 -0.2'>
  <MagneticGeometryEffect springConstant='200'><Sphere radius='0.04'/></MagneticGeometryEffect>
</Transform>
</Scene></X3D>
)");
  // About k · 5 mm = 1 N (the circle 5 mm above the sphere's top); the origin is 0.36 m away.
  EXPECT_GT(largest_force(file, 2.0), 0.5);
}

}  // namespace
}  // namespace hof::scene
