// The 3D pass of a viewer frame: every geom shaded with OpenGL 3.3 and a depth buffer, so nearer
// surfaces hide farther ones whatever the order they are drawn in, and the floor as a grid of
// lines. Needs a current OpenGL 3.3 context with a depth buffer.
#pragma once

#include <array>
#include <vector>

#include "rigidtouch/model.h"
#include "view/camera.h"

namespace rigidtouch::view {

/// A geom's colour, 0..1 per channel.
using Rgb = std::array<float, 3>;

class SceneRenderer {
 public:
  /// Uploads every geom's triangles and the floor grid (around `frame`'s centre). Throws Error
  /// when the shaders do not compile.
  SceneRenderer(const Model& model, const SceneFrame& frame);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  /// Draws geom `g` with the pose (pos, R) of its centre, in colour `c`, into the bound
  /// framebuffer with depth testing; Begin first, once a frame.
  void Begin(const Camera& cam, double far_m);
  void DrawGeom(int g, const Vec3& pos, const Mat3& R, const Rgb& c);
  /// The floor grid (unlit lines in `c`), then the GL state Dear ImGui expects back.
  void End(const Rgb& c);

 private:
  struct Range {
    int first = 0, count = 0;
  };
  unsigned program_ = 0, vao_ = 0, vbo_ = 0;
  int u_mvp_ = -1, u_rot_ = -1, u_color_ = -1, u_lit_ = -1, u_light_ = -1;
  std::vector<Range> geoms_;        // triangles of each geom
  Range thin_lines_, thick_lines_;  // the grid: 1 px lines, and every fifth 2 px
  std::array<float, 16> view_projection_{};
};

}  // namespace rigidtouch::view
