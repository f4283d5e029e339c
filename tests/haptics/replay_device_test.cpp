// Tests of the replay backend (device_backends/replay_device.cpp): exact interpolation at and
// between samples, optional columns, malformed files named by file and line, the end and the
// loop.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "hof/haptics/device_backends/replay_device.h"
#include "hof/haptics/device_config.h"
#include "support/temp_dir.h"

namespace hof::haptics {
namespace {

using hof::testing::TempDir;
namespace fs = std::filesystem;

TEST(ReplayDevice, InterpolatesExactlyAtSamplesAndMidpoints) {
  TempDir dir;
  const auto path = dir.write("a.csv",
                              "# recorded by hand\n"
                              "t,x,y,z\n"
                              "0.0, 0.0, 0.0, 0.0\n"
                              "\n"
                              "0.5, 0.01, -0.02, 0.03   # a trailing comment\n"
                              "1.0, 0.02, 0.0, 0.03\n");
  auto device = ReplayDevice::open(path, false);
  ASSERT_TRUE(device) << device.error().to_string();
  ReplayDevice& d = **device;
  ASSERT_EQ(d.samples().size(), 3U);
  for (const auto& s : d.samples()) {
    const DeviceReading r = d.read(s.t_s);
    EXPECT_TRUE(r.valid);
    EXPECT_EQ(r.position_m, s.position_m) << "at t = " << s.t_s;
  }
  const DeviceReading mid = d.read(0.25);
  EXPECT_NEAR((mid.position_m - Vec3(0.005, -0.01, 0.015)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((mid.velocity_m_per_s - Vec3(0.02, -0.04, 0.06)).norm(), 0.0, 1e-14);
  const DeviceReading mid2 = d.read(0.75);
  EXPECT_NEAR((mid2.position_m - Vec3(0.015, -0.01, 0.03)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((mid2.velocity_m_per_s - Vec3(0.02, 0.04, 0.0)).norm(), 0.0, 1e-14);
  EXPECT_EQ(d.health(), DeviceHealth::kOk);
  // Before the first sample: the first sample, at rest.
  const DeviceReading before = d.read(-1.0);
  EXPECT_TRUE(before.valid);
  EXPECT_EQ(before.position_m, Vec3::Zero());
  EXPECT_EQ(before.velocity_m_per_s, Vec3::Zero());
}

TEST(ReplayDevice, OptionalColumnsInAnyOrder) {
  TempDir dir;
  const double h = std::sqrt(0.5);  // 90° about z: (w, z) = (√½, √½)
  const auto path = dir.write("b.csv",
                              "t,button,qz,x,qw,z,qy,y,qx\n"
                              "0,1,0,0.0,1,0,0,0,0\n"
                              "2,3," +
                                  std::to_string(h) + ",0.02," + std::to_string(h) + ",0,0,0,0\n");
  auto device = ReplayDevice::open(path, false);
  ASSERT_TRUE(device) << device.error().to_string();
  const DeviceReading r = (*device)->read(1.0);
  EXPECT_NEAR(r.position_m.x(), 0.01, 1e-15);
  EXPECT_EQ(r.buttons, 1U);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(std::numbers::pi / 4, Vec3::UnitZ()));
  EXPECT_NEAR(r.orientation.angularDistance(expected), 0.0, 1e-6);
  EXPECT_EQ((*device)->read(2.0).buttons, 3U);
}

struct BadFile {
  const char* text;
  std::int64_t line;
  const char* message;
};

TEST(ReplayDevice, MalformedFilesNameFileAndLine) {
  const BadFile cases[] = {
      {"t,x,y,z\n0,0,0,0\n0.1,0,abc,0\n", 3, "bad number 'abc' in column 'y'"},
      {"t,x,y,z\n0,0,0,0\n# comment\n0.1,0,0\n", 4, "expected 4 columns, found 3"},
      {"t,x,y,z\n0,0,0,0\n0.1,0,0,0,5\n", 3, "expected 4 columns, found 5"},
      {"t,x,y,z\n0,0,0,0\n0.1,0,0,0\n0.1,0,0,0\n", 4, "is not after the previous sample's time"},
      {"t,x,y,z\n0.5,0,0,0\n0.2,0,0,0\n", 3, "is not after the previous sample's time"},
      {"t,x,y,z\n0,0,0,0\n0.1,nan,0,0\n", 3, "non-finite value 'nan'"},
      {"t,x,y,z\n0,0,inf,0\n", 2, "non-finite value 'inf'"},
      {"\n# header next\nt,x,y,w\n", 3, "unknown column 'w'"},
      {"x,t,y,z\n", 1, "must start with column 't'"},
      {"t,x,y\n", 1, "missing column 'z'"},
      {"t,x,y,z,qw,qx\n", 1, "all four columns qw, qx, qy, qz"},
      {"t,x,y,z,x\n", 1, "duplicate column 'x'"},
      {"t,x,y,z,qw,qx,qy,qz\n0,0,0,0,0,0,0,0\n", 2, "quaternion has zero length"},
      {"t,x,y,z,button\n0,0,0,0,-1\n", 2, "bad button mask '-1'"},
      {"t,x,y,z\n", 0, "no samples"},
      {"# nothing\n", 0, "no header line"},
  };
  TempDir dir;
  int i = 0;
  for (const BadFile& c : cases) {
    const auto path = dir.write("bad" + std::to_string(i++) + ".csv", c.text);
    auto loaded = load_replay(path);
    ASSERT_FALSE(loaded) << c.text;
    const Error& e = loaded.error();
    EXPECT_EQ(e.code, ErrorCode::kParse);
    EXPECT_EQ(e.file, path.string());
    EXPECT_EQ(e.line, c.line) << e.to_string();
    EXPECT_NE(e.message.find(c.message), std::string::npos) << e.to_string();
    if (c.line > 0) {
      EXPECT_NE(e.to_string().find(path.string() + ":" + std::to_string(c.line) + ": "), std::string::npos);
    }
  }
  auto missing = load_replay(dir.path() / "absent.csv");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
  EXPECT_NE(missing.error().to_string().find("absent.csv"), std::string::npos);
}

TEST(ReplayDevice, EndsAfterTheLastSample) {
  TempDir dir;
  const auto path = dir.write("c.csv", "t,x,y,z\n1,0,0,0\n2,0.01,0,0\n");
  auto device = ReplayDevice::open(path, false);
  ASSERT_TRUE(device);
  EXPECT_TRUE((*device)->read(2.0).valid);
  EXPECT_EQ((*device)->health(), DeviceHealth::kOk);
  const DeviceReading after = (*device)->read(2.001);
  EXPECT_FALSE(after.valid);
  EXPECT_EQ((*device)->health(), DeviceHealth::kEnded);
  EXPECT_EQ(after.position_m, Vec3(0.01, 0, 0));
}

TEST(ReplayDevice, LoopWrapsAround) {
  TempDir dir;
  const auto path = dir.write("d.csv", "t,x,y,z\n1,0,0,0\n2,0.01,0,0\n3,0.01,0.01,0\n");
  auto device = ReplayDevice::open(path, true);
  ASSERT_TRUE(device);
  ReplayDevice& d = **device;
  for (const double t : {1.25, 1.5, 2.0, 2.75}) {
    const DeviceReading once = d.read(t);
    for (const int k : {1, 2, 7}) {
      const DeviceReading again = d.read(t + 2.0 * k);  // period = 3 − 1 = 2 s
      EXPECT_TRUE(again.valid);
      EXPECT_NEAR((again.position_m - once.position_m).norm(), 0.0, 1e-12) << t << " + " << 2 * k;
    }
  }
  EXPECT_EQ(d.health(), DeviceHealth::kOk);
}

TEST(ReplayDevice, OpensFromItsTypedConfig) {
  TempDir dir;
  const auto path = dir.write("r.csv", "t,x,y,z\n0,0,0,0\n1,0.01,0,0\n");
  auto d = open_device(ReplayConfig{path, true, {}});
  ASSERT_TRUE(d) << d.error().to_string();
  EXPECT_EQ((*d)->backend(), "replay");
  EXPECT_TRUE((*d)->read(5.5).valid);
  EXPECT_NEAR((*d)->read(5.5).position_m.x(), 0.005, 1e-15);

  const std::string missing = (dir.path() / "missing.csv").string();
  auto absent = open_device(ReplayConfig{missing, false, {}});
  ASSERT_FALSE(absent);
  EXPECT_EQ(absent.error().code, ErrorCode::kIo);
  EXPECT_NE(absent.error().to_string().find(missing + ": replay: no such file"), std::string::npos)
      << absent.error().to_string();
}

}  // namespace
}  // namespace hof::haptics
