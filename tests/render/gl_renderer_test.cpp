// OpenGL drawing (src/hof/render/gl_renderer.cpp) in a hidden window of a virtual X server
// (Xvfb, Mesa's software OpenGL), as the window test runs it: buffers report what they hold,
// a cleared viewport reads back as the background, a mesh lands where the camera puts it, rows
// read from the top, and lines and points leave marks.

#include "hof/render/gl_renderer.h"

#include <GLFW/glfw3.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace hof::render {
namespace {

constexpr int kSize = 64;

// A hidden window with an OpenGL 3.3 core context, current on this thread.
class GlRendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!glfwInit()) GTEST_SKIP() << "no display for OpenGL (run under xvfb-run)";
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    window_ = glfwCreateWindow(kSize, kSize, "gl_renderer_test", nullptr, nullptr);
    ASSERT_NE(window_, nullptr) << "no OpenGL 3.3 context";
    glfwMakeContextCurrent(window_);
    renderer_.emplace();
    const auto ready = renderer_->init();
    ASSERT_TRUE(ready) << ready.error().to_string();
    camera_.look(Vec3(0, -2, 0), Vec3::Zero());  // looking along +y, z up on screen
  }
  void TearDown() override {
    renderer_.reset();  // its buffers are freed in the context, before the context goes
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
  }

  // The pixel (x right, y down from the top) of what was read.
  static std::array<int, 3> pixel(const std::vector<std::uint8_t>& rgb, int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * kSize + static_cast<std::size_t>(x)) * 3;
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }

  GLFWwindow* window_{nullptr};
  std::optional<GlRenderer> renderer_;
  OrbitCamera camera_;
};

const Rgba kBackground(0.2f, 0.4f, 0.6f, 1.0f);

TEST_F(GlRendererTest, MeshBuffersReportWhatTheyHold) {
  MeshBuffer buffer;
  const std::vector<Vec3> positions{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 1), Vec3(0, 0, 1)};
  const std::vector<mesh::Tri> triangles{{0, 1, 2}, {0, 2, 3}};
  buffer.set_triangles(triangles);
  buffer.set_positions(positions);
  EXPECT_NE(buffer.vao(), 0u);
  EXPECT_EQ(buffer.index_count(), 6u);
  EXPECT_EQ(buffer.vertex_count(), 4u);
  EXPECT_FALSE(buffer.has_colours());
  buffer.set_colours(std::vector<Rgba>(4, Rgba(1, 0, 0, 1)));
  EXPECT_TRUE(buffer.has_colours());
  buffer.set_colours({});
  EXPECT_FALSE(buffer.has_colours());
  MeshBuffer moved(std::move(buffer));
  EXPECT_EQ(moved.index_count(), 6u);
  EXPECT_EQ(buffer.vao(), 0u);  // NOLINT(bugprone-use-after-move): the moved-from buffer owns nothing
}

TEST_F(GlRendererTest, AClearedViewportReadsBackAsTheBackground) {
  renderer_->begin(camera_, 0, 0, kSize, kSize, kBackground);
  const auto rgb = renderer_->read_pixels(kSize, kSize);
  ASSERT_EQ(rgb.size(), static_cast<std::size_t>(kSize * kSize * 3));
  for (const int y : {0, kSize / 2, kSize - 1}) {
    for (const int x : {0, kSize / 2, kSize - 1}) {
      const auto p = pixel(rgb, x, y);
      EXPECT_NEAR(p[0], 51, 1);
      EXPECT_NEAR(p[1], 102, 1);
      EXPECT_NEAR(p[2], 153, 1);
    }
  }
}

TEST_F(GlRendererTest, AMeshAboveTheTargetIsDrawnInTheTopRowsInItsColour) {
  // A red quad in the plane y = 0 facing the camera, from z = 0.1 up: the upper part of the view.
  MeshBuffer quad;
  const std::vector<Vec3> positions{Vec3(-2, 0, 0.1), Vec3(2, 0, 0.1), Vec3(2, 0, 2), Vec3(-2, 0, 2)};
  const std::vector<Vec3> normals(4, Vec3(0, -1, 0));
  const std::vector<mesh::Tri> triangles{{0, 1, 2}, {0, 2, 3}};
  quad.set_triangles(triangles);
  quad.set_positions(positions);
  quad.set_normals(normals);
  Material red;
  red.diffuse = Rgba(1.0f, 0.0f, 0.0f, 1.0f);
  renderer_->begin(camera_, 0, 0, kSize, kSize, kBackground);
  renderer_->draw(quad, red, RenderMode::kShaded);
  const auto rgb = renderer_->read_pixels(kSize, kSize);
  const auto top = pixel(rgb, kSize / 2, 2);
  const auto bottom = pixel(rgb, kSize / 2, kSize - 3);
  EXPECT_GT(top[0], top[1] + 40) << "top " << top[0] << " " << top[1] << " " << top[2];
  EXPECT_GT(top[0], top[2] + 40);
  EXPECT_NEAR(bottom[0], 51, 1);  // below the quad: background
  EXPECT_NEAR(bottom[2], 153, 1);
}

TEST_F(GlRendererTest, LinesAndPointsLeaveMarks) {
  renderer_->begin(camera_, 0, 0, kSize, kSize, kBackground);
  const std::vector<Vec3> line{Vec3(-2, 0, 0), Vec3(2, 0, 0)};  // across the middle
  renderer_->draw_lines(line, Rgba(1, 1, 1, 1));
  const std::vector<Vec3> point{Vec3(0, 0, 0.5)};
  renderer_->draw_points(point, Rgba(1, 1, 0, 1), 6.0f);
  const auto rgb = renderer_->read_pixels(kSize, kSize);
  int white = 0;
  for (int y = kSize / 2 - 2; y <= kSize / 2 + 2; ++y) {
    const auto p = pixel(rgb, 5, y);
    white += p[0] > 200 && p[1] > 200 && p[2] > 200;
  }
  EXPECT_GE(white, 1) << "no line across the middle";
  const Vec3 at = camera_.to_pixel(point[0], kSize, kSize);
  const auto p = pixel(rgb, static_cast<int>(std::lround(at.x())), static_cast<int>(std::lround(at.y())));
  EXPECT_GT(p[0], 200);
  EXPECT_GT(p[1], 200);
  EXPECT_LT(p[2], 100);
}

}  // namespace
}  // namespace hof::render

// Without a display, the tests run again under xvfb-run (as tests/app/gui_test.cpp runs the
// window); listing them (ctest's discovery) needs none.
int main(int argc, char** argv) {
  bool listing = false;
  for (int i = 1; i < argc; ++i) listing = listing || std::strncmp(argv[i], "--gtest_list_tests", 18) == 0;
  const char* display = std::getenv("DISPLAY");
  if (!listing && (!display || !*display) && !std::getenv("HOF_GL_TEST_UNDER_XVFB")) {
    ::setenv("HOF_GL_TEST_UNDER_XVFB", "1", 1);
    std::vector<char*> args{const_cast<char*>("xvfb-run"), const_cast<char*>("-a"), const_cast<char*>("-s"),
                            const_cast<char*>("-screen 0 640x480x24")};
    for (int i = 0; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    ::execvp("xvfb-run", args.data());  // returns only when there is no xvfb-run: the tests skip
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
