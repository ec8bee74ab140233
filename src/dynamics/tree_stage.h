// The trees' part of the tick. A tree's step (dynamics::TreeStep) is split around the contact
// stages: stage 4 prepares it (PrepareTreeStep: kinematics, mass matrix, bias, passive and
// actuator forces, the factor of M + h D) and moves its velocity freely (TreeFreeMotion) before
// its contact group's implicit solve adds the contact and limit forces; stage 5 may add an
// impulse; the trees stage (StepTrees, stage 7) moves the positions with the final velocities,
// writes the joints' limit flags and the world poses of the links' geoms for the next collision
// stage. Without contacts and limits the operations are TreeStep's, in its order.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dynamics/tree.h"
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

/// Stage 4, tree t: TreeStep's first half at the current positions and velocities (kinematics;
/// mass matrix; bias, which leaves the links' velocities at qvel in TreeData::V; passive forces;
/// the factor of M + h D) and the actuators' forces into `force`. False when the factor fails.
bool PrepareTreeStep(const Model& model, int t, Data& data, Eigen::Ref<Eigen::VectorXd> force);

/// Stage 4, tree t after PrepareTreeStep: qvel += h (M + h D)^-1 (force - bias + passive), then
/// the dry friction impulse of its joints' frictionloss (dynamics::TreeFreeVelocity).
void TreeFreeMotion(const Model& model, int t, Data& data,
                    const Eigen::Ref<const Eigen::VectorXd>& force);

/// Tree t back at its initial state with its kinematics (nothing counted).
void ResetTree(const Model& model, int t, Data& data);

/// Velocity [m/s] of the world point p_W moving with body `link` of a tree, from the links'
/// velocities TreeData::V (PrepareTreeStep's, at the velocities before this step's update).
Vec3 LinkPointVelocity(const TreeData& data, int link, const Vec3& p_W);

/// Stage 7: moves every tree's positions by h with its velocities (TreeIntegratePositions),
/// writes the joints' limit flags and the link
/// geoms' world poses into `collision` (the poses the collision stage reads for static geoms);
/// holds a placeholder tool (Model::has_tool false) at its initial state. A tree whose step fails
/// or leaves a non-finite state goes back to its initial state with Warning::kNonFiniteState.
/// Never allocates or throws.
void StepTrees(const Model& model, Data& data, TreeStageScratch& scratch,
               geometry::CollisionScratch& collision);

}  // namespace rigidtouch::dynamics
