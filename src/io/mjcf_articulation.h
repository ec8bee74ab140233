// Articulated trees from a compiled MJCF scene (Model::trees, docs/scenes.md): which MuJoCo
// bodies form trees, their joints, limits, actuators at a constant control, and the initial state.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "rigidtouch/model.h"

namespace rigidtouch::io {

/// Where a MuJoCo body goes: a link of a tree, or not (a free body, or static).
struct LinkOf {
  int tree = -1;
  int link = -1;
};

/// Whether MuJoCo body b is a free body of rigidtouch's: one <freejoint/> in a child of the
/// world, and no joint in any body below it.
bool IsLoneFreeBody(const mjModel* m, int b);

/// Builds model.trees from every jointed subtree of the world that is not a lone free body
/// (IsLoneFreeBody), with the state of keyframe 'initial' (else qpos0, zero qvel, zero ctrl).
/// Returns, per MuJoCo body, its tree and link (welded bodies their jointed ancestor's). Throws
/// Error naming the element for what a tree cannot simulate: frictionloss, ball stiffness, a range
/// with min > max, a keyframe outside a range, actuators with activation state, muscles, other
/// transmissions than a hinge or slide joint, user gains or biases; warns for the limits' softness
/// (solref, solimp, margin), which the contact stages replace.
std::vector<LinkOf> CopyTrees(const mjModel* m, const std::string& path, Model& model);

/// Sets every link geom's world pose at the initial state (GeomModel::pos_B, quat_B) from its
/// pose on the link (pos_L, quat_L) and the trees' initial kinematics.
void PlaceLinkGeomsAtStart(Model& model);

}  // namespace rigidtouch::io
