// The tick's trees stage: each articulated tree (Model::trees) advanced one step in joint space
// with its actuators' forces (dynamics::TreeStep), the joints' limit flags, and the world poses of
// the links' geoms for the next collision stage. No contact forces act on links yet.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "geometry/collision.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// Scratch of the trees stage, sized by Reserve.
struct TreeStageScratch {
  std::vector<Eigen::VectorXd> joint_force;  // (ntree) x (nv): actuator forces of this step
  /// Sizes every buffer for `model`.
  void Reserve(const Model& model);
};

/// Makes the state of every tree of `model` in data.trees and data.joint_at_limit (MakeData).
void MakeTreesData(const Model& model, Data& data);

/// Puts every tree back to its initial state (qpos, qvel, kinematics) and the link geoms'
/// poses in `collision` to theirs (ResetState).
void ResetTrees(const Model& model, Data& data, geometry::CollisionScratch& collision);

/// The joint forces of tree t's actuators at the current state into `force` (nv): each at the
/// model's constant control, force-clamped, times its gear.
void ActuatorForces(const Model& model, int t, const Data& data, Eigen::Ref<Eigen::VectorXd> force);

/// Steps every tree by h with its actuator forces, writes the joints' limit flags and the link
/// geoms' world poses into `collision` (the poses the collision stage reads for static geoms);
/// holds a placeholder tool (Model::has_tool false) at its initial state. A tree whose step fails
/// or leaves a non-finite state goes back to its initial state with Warning::kNonFiniteState.
/// Never allocates or throws.
void StepTrees(const Model& model, Data& data, TreeStageScratch& scratch,
               geometry::CollisionScratch& collision);

}  // namespace rigidtouch::dynamics
