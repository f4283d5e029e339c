// The mouse stylus: a left drag moves it on a plane facing the camera (set just in front of
// the surface under the cursor), the wheel or W/S push it in depth; Alt + left drag (or the
// arrow keys) turn the tool it carries, R turns it back; the right and middle buttons orbit,
// pan and zoom the camera.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>

#include <cmath>

#include "hof/app/gui/detail/gui_window.h"

namespace hof::app::gui {

std::optional<Vec3> GuiWindow::pick(double x_px, double y_px) const {
  const auto [origin, direction] = camera_.ray(x_px, y_px, view_w_, view_h_);
  const Vec3 far = origin + direction * (camera_.distance() * 20.0);
  std::optional<Vec3> best;
  double best_t = 2.0;
  for (const LayerView& l : layers_) {
    if (!l.latest || l.latest->triangles.empty()) continue;
    const collision::SweepHit hit =
        l.latest->tree.first_hit_segment(l.latest->view(), origin, far, collision::TouchableFace::kFrontAndBack);
    if (hit.triangle >= 0 && hit.t < best_t) {
      best_t = hit.t;
      best = hit.point;
    }
  }
  return best;
}

void GuiWindow::set_mouse_target(const Vec3& world) {
  mouse_world_ = world;
  if (mouse_) mouse_->set_target((mouse_calibration().position.inverse() * world.homogeneous()).head<3>());
}

void GuiWindow::mouse_to(double window_x, double window_y, double depth_m, bool new_plane) {
  const double x = window_x - view_x_, y = window_y;
  if (new_plane) {
    // The plane faces the camera and passes just in front of the surface under the cursor
    // (by the proxy's radius), or through the current stylus when there is none.
    const double clearance = std::max(project_.proxy_radius_m, 0.002 * scene_size()) * 1.5;
    if (const auto hit = pick(x, y)) {
      plane_point_ = *hit - camera_.forward() * clearance;
    } else {
      plane_point_ = mouse_world_;
    }
  }
  mouse_depth_m_ = depth_m;
  const auto [origin, direction] = camera_.ray(x, y, view_w_, view_h_);
  const Vec3 f = camera_.forward();
  const double plane_depth = (plane_point_ - origin).dot(f) + mouse_depth_m_;
  const double along = direction.dot(f);
  if (!(along > 1e-9)) return;
  set_mouse_target(origin + direction * (plane_depth / along));
}

void GuiWindow::set_mouse_orientation(const Eigen::Quaterniond& world) {
  mouse_orientation_ = world.normalized();
  // The haptic loop turns a reading by the calibration's orientation: the device is given the
  // turn that comes out as `world`.
  if (mouse_) mouse_->set_orientation(mouse_calibration().orientation.inverse() * mouse_orientation_);
}

void GuiWindow::turn_mouse_stylus(const Eigen::Quaterniond& rotation) {
  set_mouse_orientation(rotation * mouse_orientation_);
}

void GuiWindow::handle_input() {
  ImGuiIO& io = ImGui::GetIO();
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(window_, &x, &y);
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x;
  last_y_ = y;
  // Depth: the wheel while the stylus is held, or W/S at any time.
  const double depth_step = 0.01 * scene_size();
  double push = 0.0;
  if (!io.WantCaptureKeyboard && !io.KeyCtrl) {
    if (ImGui::IsKeyPressed(GLFW_KEY_W)) push += depth_step;
    if (ImGui::IsKeyPressed(GLFW_KEY_S)) push -= depth_step;
  }
  // Turning the tool (a 6-DOF hand on a 2-D mouse): the arrow keys by 15° about the screen's
  // vertical and horizontal axes, R back to the project's orientation.
  const Vec3 screen_up = camera_.up_on_screen();
  const Vec3 screen_right = camera_.right();
  if (mouse_ && shaped_tool_ && !io.WantCaptureKeyboard && !io.KeyCtrl) {
    constexpr double kStep = 15.0 * 3.14159265358979323846 / 180.0;
    const auto turn = [&](const Vec3& axis, double angle) {
      turn_mouse_stylus(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)));
    };
    if (ImGui::IsKeyPressed(GLFW_KEY_LEFT)) turn(screen_up, -kStep);
    if (ImGui::IsKeyPressed(GLFW_KEY_RIGHT)) turn(screen_up, kStep);
    if (ImGui::IsKeyPressed(GLFW_KEY_UP)) turn(screen_right, -kStep);
    if (ImGui::IsKeyPressed(GLFW_KEY_DOWN)) turn(screen_right, kStep);
    if (ImGui::IsKeyPressed(GLFW_KEY_R)) set_mouse_orientation(Eigen::Quaterniond::Identity());
  }
  if (io.WantCaptureMouse && !dragging_stylus_ && !turning_stylus_) {
    if (push != 0.0 && mouse_) {
      mouse_depth_m_ += push;
      set_mouse_target(mouse_world_ + camera_.forward() * push);
    }
    return;
  }
  const bool left = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  const bool right = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool middle = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  const bool shift = io.KeyShift;
  // Left: the stylus follows the cursor on a plane facing the camera (set where the drag
  // starts, just in front of the surface under the cursor). Right: orbit; middle or
  // shift+right: pan; wheel: zoom (while the stylus is held: depth).
  // Alt + left drag turns the tool about the screen's axes (a trackball: 0.5° a pixel; the
  // surface nearest the eye follows the cursor).
  if (left && mouse_ && shaped_tool_ && (io.KeyAlt || turning_stylus_) && !dragging_stylus_) {
    turning_stylus_ = true;
    constexpr double kRadiansPerPixel = 0.5 * 3.14159265358979323846 / 180.0;
    if (dx != 0.0 || dy != 0.0) {
      const Vec3 axis = (screen_up * dx + screen_right * dy).normalized();
      turn_mouse_stylus(Eigen::Quaterniond(Eigen::AngleAxisd(kRadiansPerPixel * std::hypot(dx, dy), axis)));
    }
    return;
  }
  turning_stylus_ = false;
  if (left && mouse_) {
    if (!dragging_stylus_) {
      mouse_to(x, y, 0.0, true);
      dragging_stylus_ = true;
    }
    mouse_to(x, y, mouse_depth_m_ + push + depth_step * io.MouseWheel, false);
    return;
  }
  dragging_stylus_ = false;
  if (push != 0.0 && mouse_) {
    mouse_depth_m_ += push;
    set_mouse_target(mouse_world_ + camera_.forward() * push);
  }
  if ((right && shift) || middle) {
    camera_.pan(dx, dy, view_h_);
  } else if (right) {
    camera_.orbit(dx, dy);
  }
  if (io.MouseWheel != 0.0f) camera_.zoom(std::pow(0.9, io.MouseWheel));
}

}  // namespace hof::app::gui
