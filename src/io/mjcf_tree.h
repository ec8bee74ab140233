// A kinematic tree (src/dynamics/tree.h) from a model compiled by MuJoCo: MuJoCo is read at load
// time only; the tree's coordinates are then the model's own qpos and qvel, in the same order.
#pragma once

#include <mujoco/mujoco.h>

#include "dynamics/tree.h"

namespace rigidtouch::io {

/// The tree of every body but the world: body i of the tree is MuJoCo's body i + 1, joint and dof
/// orders and qpos / qvel addresses are MuJoCo's. Copies offsets, masses, inertial frames (turned
/// into full inertias in the body frame), joint types, axes, anchors, ref (qpos0), spring_ref
/// (qpos_spring, a ball's spring quaternion), stiffness, damping, armature, frictionloss and
/// gravity. Refuses (Error) what the tree does not model: mocap bodies, free joints with
/// stiffness, and joints whose dofs differ in damping, armature or frictionloss.
dynamics::TreeModel TreeFromMjModel(const mjModel* m);

}  // namespace rigidtouch::io
