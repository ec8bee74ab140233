#include "view/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rigidtouch::view {

SceneFrame FrameScene(const Model& model) {
  const Vec3 start = model.initial[model.tool].x_W;
  Vec3 lo = start, hi = start;
  for (const GeomModel& g : model.geoms) {
    if (g.type == GeomType::kPlane) continue;
    const Vec3 c = g.body < 0
                       ? g.pos_B
                       : Vec3(model.initial[g.body].x_W + model.initial[g.body].q_WB * g.pos_B);
    lo = lo.cwiseMin(c - Vec3::Constant(g.rbound_m));
    hi = hi.cwiseMax(c + Vec3::Constant(g.rbound_m));
  }
  SceneFrame s;
  s.centre = 0.5 * (lo + hi);
  const double radius = 0.5 * (hi - lo).norm();
  s.distance_m = std::max(0.2, 3.0 * radius);
  s.grid_half_m = std::max(0.15, 1.5 * radius);
  // the grid's far corner is within distance + sqrt(2) grid_half of the eye
  s.far_m = s.distance_m + 2.0 * (s.grid_half_m + radius);
  return s;
}

Camera::Camera(const Vec3& target, double distance_m, double width, double height, double left_px)
    : width_px(std::max(width, 1.0)), height_px(std::max(height, 1.0)) {
  const double elevation = 25.0 * std::numbers::pi / 180.0;
  eye = target + distance_m * Vec3(0.0, -std::cos(elevation), std::sin(elevation));
  f = (target - eye).normalized();
  r = f.cross(Vec3::UnitZ()).normalized();
  u = r.cross(f);
  cx = 0.5 * (std::clamp(left_px, 0.0, width_px - 1.0) + width_px);
  cy = 0.5 * height_px;
  focal_px = cy / std::tan(0.5 * 45.0 * std::numbers::pi / 180.0);  // 45 degrees vertically
}

bool Camera::Project(const Vec3& p, double& x, double& y) const {
  const Vec3 v = p - eye;
  const double z = v.dot(f);
  if (z < kNear) return false;
  x = cx + focal_px * v.dot(r) / z;
  y = cy - focal_px * v.dot(u) / z;
  return true;
}

Vec3 Camera::Unproject(double x, double y, double z) const {
  return eye + z * f + ((x - cx) * z / focal_px) * r - ((y - cy) * z / focal_px) * u;
}

std::array<float, 16> Camera::ViewProjection(double far_m) const {
  // clip = P V p with V's rows (r, u, -f) about the eye and w = z: x_ndc = (2 focal / W) (v.r) /
  // z + 2 cx / W - 1 gives Project's x = W (1 + x_ndc) / 2 for a principal point cx anywhere in
  // the window, and y likewise (OpenGL's rows run bottom up, the pixel's y down)
  const double n = kNear, fa = std::max(far_m, 2.0 * kNear);
  const double a = (fa + n) / (fa - n), b = 2.0 * fa * n / (fa - n);
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = 2.0 * focal_px / width_px;
  P(0, 2) = 1.0 - 2.0 * cx / width_px;  // times the view's z (= -depth): the shifted centre
  P(1, 1) = 2.0 * focal_px / height_px;
  P(1, 2) = 2.0 * cy / height_px - 1.0;
  P(2, 2) = -a;
  P(2, 3) = -b;
  P(3, 2) = -1.0;
  Eigen::Matrix4d V = Eigen::Matrix4d::Identity();
  V.block<1, 3>(0, 0) = r.transpose();
  V.block<1, 3>(1, 0) = u.transpose();
  V.block<1, 3>(2, 0) = -f.transpose();
  V(0, 3) = -r.dot(eye);
  V(1, 3) = -u.dot(eye);
  V(2, 3) = f.dot(eye);
  const Eigen::Matrix4d M = P * V;
  std::array<float, 16> out{};
  for (int c = 0; c < 4; ++c) {
    for (int k = 0; k < 4; ++k) out[4 * c + k] = static_cast<float>(M(k, c));
  }
  return out;
}

Camera ViewerCamera(const SceneFrame& frame, double width_px, double height_px) {
  const double left = width_px >= 2.0 * kPanelRightPx ? kPanelRightPx : 0.0;
  return Camera(frame.centre, frame.distance_m, width_px, height_px, left);
}

}  // namespace rigidtouch::view
