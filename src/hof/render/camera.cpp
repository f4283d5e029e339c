#include "hof/render/camera.h"

#include <algorithm>
#include <cmath>

namespace hof::render {

namespace {
constexpr double kMaxPitch = 1.55;  // just short of straight up/down: the frame stays defined
}

void OrbitCamera::set_up(const Vec3& up) {
  if (!(up.norm() > 0.0)) return;
  up_ = up.normalized();
  // e1: the world axis least aligned with up, made orthogonal to it.
  Vec3 a = std::abs(up_.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  if (std::abs(up_.z()) < 0.5 && std::abs(up_.y()) > 0.9) a = Vec3::UnitZ();
  e1_ = (a - a.dot(up_) * up_).normalized();
  e2_ = up_.cross(e1_);
}

void OrbitCamera::look(const Vec3& eye, const Vec3& target) {
  target_ = target;
  Vec3 d = eye - target;
  distance_ = d.norm();
  if (!(distance_ > 1e-12)) {
    distance_ = 1.0;
    d = -Vec3::UnitY() + Vec3::UnitZ();
  }
  d.normalize();
  pitch_ = std::clamp(std::asin(std::clamp(d.dot(up_), -1.0, 1.0)), -kMaxPitch, kMaxPitch);
  yaw_ = std::atan2(d.dot(e2_), d.dot(e1_));
}

void OrbitCamera::fit(const Vec3& box_min, const Vec3& box_max) {
  target_ = 0.5 * (box_min + box_max);
  const double radius = std::max(0.5 * (box_max - box_min).norm(), 1e-6);
  // The bounding sphere fills the vertical field of view with a margin.
  distance_ = 1.15 * radius / std::sin(0.5 * fov_y_rad_);
  // From the front and 30° above: −y for a z-up scene (the standard liver), +z for a y-up
  // one (X3D's viewer looks along −z).
  const Vec3 front = std::abs(up_.y()) > 0.9 ? Vec3::UnitZ() : Vec3(-Vec3::UnitY());
  yaw_ = std::atan2(front.dot(e2_), front.dot(e1_));
  pitch_ = 0.52;
}

void OrbitCamera::orbit(double dx_px, double dy_px) {
  yaw_ -= 0.008 * dx_px;
  pitch_ = std::clamp(pitch_ + 0.008 * dy_px, -kMaxPitch, kMaxPitch);
}

void OrbitCamera::pan(double dx_px, double dy_px, double viewport_height_px) {
  // One pixel at the target's depth.
  const double metres_per_px = 2.0 * distance_ * std::tan(0.5 * fov_y_rad_) / std::max(viewport_height_px, 1.0);
  target_ += metres_per_px * (-dx_px * right() + dy_px * up_on_screen());
}

void OrbitCamera::zoom(double factor) { distance_ = std::clamp(distance_ * factor, 1e-5, 1e5); }

Vec3 OrbitCamera::eye() const {
  const Vec3 d = std::cos(pitch_) * (std::cos(yaw_) * e1_ + std::sin(yaw_) * e2_) + std::sin(pitch_) * up_;
  return target_ + distance_ * d;
}

Vec3 OrbitCamera::forward() const { return (target_ - eye()).normalized(); }
Vec3 OrbitCamera::right() const { return forward().cross(up_).normalized(); }
Vec3 OrbitCamera::up_on_screen() const { return right().cross(forward()); }

Eigen::Matrix4d OrbitCamera::view() const {
  const Vec3 f = forward(), r = right(), u = up_on_screen(), e = eye();
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = r.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -r.dot(e);
  m(1, 3) = -u.dot(e);
  m(2, 3) = f.dot(e);
  return m;
}

Eigen::Matrix4d OrbitCamera::projection(double aspect) const {
  // gluPerspective. Near/far bracket the scene around the target.
  const double n = std::max(distance_ * 0.01, 1e-6), f = distance_ * 20.0;
  const double t = 1.0 / std::tan(0.5 * fov_y_rad_);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = t / std::max(aspect, 1e-6);
  p(1, 1) = t;
  p(2, 2) = (f + n) / (n - f);
  p(2, 3) = 2.0 * f * n / (n - f);
  p(3, 2) = -1.0;
  return p;
}

std::pair<Vec3, Vec3> OrbitCamera::ray(double x_px, double y_px, double w_px, double h_px) const {
  const double t = std::tan(0.5 * fov_y_rad_);
  const double aspect = w_px / std::max(h_px, 1.0);
  const double nx = (2.0 * (x_px + 0.5) / std::max(w_px, 1.0) - 1.0) * t * aspect;
  const double ny = (1.0 - 2.0 * (y_px + 0.5) / std::max(h_px, 1.0)) * t;
  return {eye(), (forward() + nx * right() + ny * up_on_screen()).normalized()};
}

Vec3 OrbitCamera::to_pixel(const Vec3& p, double w_px, double h_px) const {
  const Vec3 d = p - eye();
  const double depth = d.dot(forward());
  const double t = std::tan(0.5 * fov_y_rad_);
  const double aspect = w_px / std::max(h_px, 1.0);
  const double nx = d.dot(right()) / (depth * t * aspect);
  const double ny = d.dot(up_on_screen()) / (depth * t);
  return {(nx + 1.0) * 0.5 * w_px - 0.5, (1.0 - ny) * 0.5 * h_px - 0.5, depth};
}

}  // namespace hof::render
