#pragma once
/// @file
/// An orbit camera (as runSofa's and H3DViewer's examine mode): it turns about a target
/// point; the viewpoint is target + distance · direction(yaw, pitch) in a frame whose up axis
/// is the scene's (z for HoF's organs, −gravity for a SOFA scene that has gravity).

#include <Eigen/Geometry>

#include "hof/core/types.h"

namespace hof::render {

class OrbitCamera {
 public:
  /// Up axis of the scene (unit; need not be an axis).
  void set_up(const Vec3& up);
  /// Looks from `eye` at `target` (a project's viewpoint and lookAt).
  void look(const Vec3& eye, const Vec3& target);
  /// Frames an axis-aligned box: the whole of it in view, seen from the front and above.
  void fit(const Vec3& box_min, const Vec3& box_max);

  /// Mouse-drag gestures, in window pixels (positive x right, positive y down).
  void orbit(double dx_px, double dy_px);
  void pan(double dx_px, double dy_px, double viewport_height_px);
  /// factor < 1 moves closer.
  void zoom(double factor);

  [[nodiscard]] Vec3 eye() const;
  [[nodiscard]] const Vec3& target() const { return target_; }
  [[nodiscard]] double distance() const { return distance_; }
  /// Unit vector from the eye toward the target.
  [[nodiscard]] Vec3 forward() const;
  [[nodiscard]] Vec3 right() const;
  [[nodiscard]] Vec3 up_on_screen() const;
  [[nodiscard]] double fov_y_rad() const { return fov_y_rad_; }

  [[nodiscard]] Eigen::Matrix4d view() const;
  /// Perspective with near and far planes around the target (depth precision where it matters).
  [[nodiscard]] Eigen::Matrix4d projection(double aspect) const;
  /// The ray through pixel (x, y) of a viewport w × h: origin (the eye) and unit direction.
  [[nodiscard]] std::pair<Vec3, Vec3> ray(double x_px, double y_px, double w_px, double h_px) const;
  /// The pixel (x right, y down) and depth (along forward, m) of a world point.
  [[nodiscard]] Vec3 to_pixel(const Vec3& p, double w_px, double h_px) const;

 private:
  Vec3 up_{0.0, 0.0, 1.0};
  Vec3 target_{Vec3::Zero()};
  double distance_{0.5};
  double yaw_{-1.5707963267948966};       // direction from target to eye, about up
  double pitch_{0.5};                     // elevation of the eye above the target's horizon
  double fov_y_rad_{0.6981317007977318};  // 40°
  // A frame whose third axis is up: direction = cos(pitch)(cos(yaw) e1 + sin(yaw) e2) + sin(pitch) up.
  Vec3 e1_{1.0, 0.0, 0.0}, e2_{0.0, 1.0, 0.0};
};

}  // namespace hof::render
