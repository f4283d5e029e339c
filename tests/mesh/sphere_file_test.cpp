// SOFA's sphere files (.sph): the anchors' liver spheres read whole, and each malformed file an
// error naming the file and the line.

#include <gtest/gtest.h>

#include <fstream>

#include "hof/mesh/sphere_file.h"

namespace hof::mesh {
namespace {

TEST(SphereFile, ReadsSofasLiverSpheres) {
  // mesh/liver.sph: 34 `sphe` lines (its "#nums 27" is a comment), radii 0.85 but one 0.35.
  auto s = read_sph(HOF_ANCHORS_DIR "/sofa/mesh/liver.sph");
  ASSERT_TRUE(s) << s.error().to_string();
  ASSERT_EQ(s->centers.size(), 34u);
  ASSERT_EQ(s->radii.size(), 34u);
  EXPECT_EQ(s->centers[0], Vec3(-4, 1.25, 0));
  EXPECT_DOUBLE_EQ(s->radii[0], 0.85);
  EXPECT_EQ(s->centers[2], Vec3(-3, 1.25, 2.5));
  EXPECT_DOUBLE_EQ(s->radii[2], 0.35);
  EXPECT_EQ(std::count(s->radii.begin(), s->radii.end(), 0.85), 33);
}

TEST(SphereFile, AnnouncedCountIsChecked) {
  auto ok = parse_sph("sph 1.0\nnums 2\nsphe 1 0 0 0 1\nsphe 2 1 0 0 0.5\n", "two.sph");
  ASSERT_TRUE(ok) << ok.error().to_string();
  EXPECT_EQ(ok->centers.size(), 2u);
  auto wrong = parse_sph("sph 1.0\nnums 3\nsphe 1 0 0 0 1\n", "three.sph");
  ASSERT_FALSE(wrong);
  EXPECT_EQ(wrong.error().line, 2);
  EXPECT_EQ(wrong.error().file, "three.sph");
  EXPECT_NE(wrong.error().message.find("'nums 3' but the file has 1 spheres"), std::string::npos)
      << wrong.error().message;
}

TEST(SphereFile, EachMalformedFileNamesItsLine) {
  struct Case {
    const char* text;
    std::int64_t line;
    const char* says;
  };
  for (const Case& c :
       {Case{"OFF\n", 1, "expected the header 'sph 1.0'"}, Case{"", 1, "empty"},
        Case{"sph 1.0\n# a comment\nsphe 1 0 0\n", 3, "needs 5 values"},
        Case{"sph 1.0\nsphe 1 0 x 0 1\n", 2, "'x' is not a finite number"},
        Case{"sph 1.0\nsphe 1 0 0 0 1\nsphe 2 0 0 0 -1\n", 3, "radius -1 is not positive"},
        Case{"sph 1.0\ncube 1 0 0 0 1\n", 2, "unknown keyword 'cube'"}, Case{"sph 1.0\n\n", 2, "no sphere"}}) {
    auto r = parse_sph(c.text, "bad.sph");
    ASSERT_FALSE(r) << c.text;
    EXPECT_EQ(r.error().file, "bad.sph");
    EXPECT_EQ(r.error().line, c.line) << c.text;
    EXPECT_NE(r.error().message.find(c.says), std::string::npos) << r.error().message;
  }
}

TEST(SphereFile, AMissingFileIsAnErrorNamingIt) {
  auto r = read_sph("/nonexistent/nowhere.sph");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().to_string().find("nowhere.sph"), std::string::npos) << r.error().to_string();
}

}  // namespace
}  // namespace hof::mesh
