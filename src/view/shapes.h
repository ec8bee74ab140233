// Triangles of every geom type the viewer draws, in the geom's own frame (MuJoCo's: a capsule's
// and a cylinder's axis along z, a box's and an ellipsoid's half-extents along x, y, z), as
// (x, y, z, nx, ny, nz) per vertex, three vertices a triangle. The viewer uploads them once and
// draws each with its geom's pose.
#pragma once

#include <vector>

#include "rigidtouch/model.h"

namespace rigidtouch::view {

/// Floats per vertex: position [m] and unit normal.
inline constexpr int kVertexFloats = 6;

/// Appends the triangles of geom `g` of `model` to `out`; a plane adds none (the viewer draws it
/// as a grid). A mesh is drawn from the compiled model's vertices and faces: the faces the MJCF
/// gave, or the convex hull MuJoCo built when it gave vertices only.
void AppendGeomTriangles(const Model& model, const GeomModel& g, std::vector<float>& out);

}  // namespace rigidtouch::view
