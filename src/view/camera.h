// The viewer's fixed camera: a perspective view of the scene from the front (-y) and 25 degrees
// above, far enough to frame every geom. One camera serves both passes of a frame: the shaded
// geoms (OpenGL, with a depth buffer) and the overlays (Dear ImGui's draw lists: contacts, the
// force arrow), so the two line up to the pixel; the screenshot tests project with it too.
#pragma once

#include <array>

#include "rigidtouch/model.h"

namespace rigidtouch::view {

/// Where the camera looks and from how far: the box around every geom but planes (their bounding
/// spheres, in the initial pose) and the tool's start.
struct SceneFrame {
  Vec3 centre = Vec3::Zero();
  double distance_m = 0.2;    // at least 0.2 m, 3 scene radii
  double grid_half_m = 0.15;  // half the floor grid's extent
  double far_m = 1.0;         // the far clipping plane, past everything framed
};
SceneFrame FrameScene(const Model& model);

struct Camera {
  Vec3 eye, f, r, u;  // position, forward, right, up
  double focal_px = 1.0, cx = 0.0, cy = 0.0;

  double width_px = 1.0, height_px = 1.0;
  static constexpr double kNear = 0.01;  // m, the near clipping plane

  /// Looks at `target` from `distance_m`; the target lands in the middle of the part of the
  /// window right of `left_px` (0: the whole window).
  Camera(const Vec3& target, double distance_m, double width_px, double height_px,
         double left_px = 0.0);
  double Depth(const Vec3& p) const { return (p - eye).dot(f); }
  /// The pixel (x right, y down from the top left corner) of `p`; false behind the near plane.
  bool Project(const Vec3& p, double& x, double& y) const;
  /// The point at depth `z` under pixel (x, y).
  Vec3 Unproject(double x, double y, double z) const;
  /// OpenGL's view-projection matrix (column-major) that maps a point to the same pixel as
  /// Project, with depth from kNear to `far_m`.
  std::array<float, 16> ViewProjection(double far_m) const;
};

/// The right edge of the viewer's panel [px]: the panel is 470 px wide, 10 px from the left.
inline constexpr double kPanelRightPx = 490.0;

/// The viewer's camera for a window of this size: the scene framed right of the panel when the
/// window is at least twice as wide as the panel, else in the middle of the window.
Camera ViewerCamera(const SceneFrame& frame, double width_px, double height_px);

}  // namespace rigidtouch::view
