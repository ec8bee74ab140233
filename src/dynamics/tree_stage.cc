// The trees stage (src/dynamics/tree_stage.h, docs/architecture.md).
#include "dynamics/tree_stage.h"

#include <algorithm>
#include <cmath>

#include "dynamics/tree.h"

namespace rigidtouch::dynamics {
namespace {

void SetTreeInitialState(const ArticulatedTree& tree, TreeData& d) {
  for (int i = 0; i < tree.nq; ++i) d.qpos[i] = tree.initial_qpos[i];
  for (int i = 0; i < tree.nv; ++i) d.qvel[i] = tree.initial_qvel[i];
  TreeKinematics(*tree.dynamics, d);
}

// the world poses of tree t's link geoms from its kinematics
void PlaceLinkGeoms(const Model& model, int t, const TreeData& d,
                    geometry::CollisionScratch& collision) {
  for (std::size_t g = 0; g < model.geoms.size(); ++g) {
    const GeomModel& geom = model.geoms[g];
    if (geom.tree != t) continue;
    const Mat3& R = d.R_WB[geom.link];
    geometry::GeomPose& pose = collision.poses[g];
    pose.p_W = d.x_W[geom.link] + R * geom.pos_L;
    pose.R_WG = R * geom.quat_L.toRotationMatrix();
    const geometry::GeomCheck kind = collision.geom_kind[g];
    const bool finite = pose.p_W.allFinite() && pose.R_WG.allFinite();
    collision.geom_check[g] =
        kind == geometry::GeomCheck::kAccepted && !finite ? geometry::GeomCheck::kRejected : kind;
  }
}

// whether joint j of the tree is at or beyond a limit of its range
bool AtLimit(const JointModel& j, const TreeData& d) {
  if (!j.limited) return false;
  if (j.type == JointKind::kHinge || j.type == JointKind::kSlide) {
    const double q = d.qpos[j.qpos_adr];
    return q <= j.range_lo_rad_or_m || q >= j.range_hi_rad_or_m;
  }
  if (j.type == JointKind::kBall) {
    const double w = std::min(1.0, std::abs(d.qpos[j.qpos_adr]));
    return 2.0 * std::acos(w) >= j.range_hi_rad_or_m;
  }
  return false;
}

}  // namespace

void TreeStageScratch::Reserve(const Model& model) {
  joint_force.clear();
  for (const ArticulatedTree& tree : model.trees) {
    joint_force.push_back(Eigen::VectorXd::Zero(tree.nv));
  }
}

void MakeTreesData(const Model& model, Data& data) {
  data.trees.clear();
  data.joint_at_limit.clear();
  for (const ArticulatedTree& tree : model.trees) {
    data.trees.emplace_back(new TreeData(MakeTreeData(*tree.dynamics)));
    SetTreeInitialState(tree, *data.trees.back());
    data.joint_at_limit.emplace_back(tree.joints.size(), 0);
  }
  data.tree_window.assign(model.trees.size(), WindowState{});
}

void ResetTrees(const Model& model, Data& data, geometry::CollisionScratch& collision) {
  const int ntree = static_cast<int>(model.trees.size());
  for (int t = 0; t < ntree && t < static_cast<int>(data.trees.size()); ++t) {
    SetTreeInitialState(model.trees[t], *data.trees[t]);
    data.tree_window[t] = WindowState{};
    if (collision.poses.size() == model.geoms.size()) {
      PlaceLinkGeoms(model, t, *data.trees[t], collision);
    }
    const std::vector<JointModel>& joints = model.trees[t].joints;
    for (std::size_t j = 0; j < joints.size(); ++j) {
      data.joint_at_limit[t][j] = AtLimit(joints[j], *data.trees[t]) ? 1 : 0;
    }
  }
}

void ActuatorForces(const Model& model, int t, const Data& data,
                    Eigen::Ref<Eigen::VectorXd> force) {
  const ArticulatedTree& tree = model.trees[t];
  const TreeData& d = *data.trees[t];
  force.setZero();
  for (const ActuatorModel& a : tree.actuators) {
    const JointModel& j = tree.joints[a.joint];
    const double length = a.gear * d.qpos[j.qpos_adr];
    const double velocity = a.gear * d.qvel[j.dof_adr];
    const double gain = a.gain[0] + a.gain[1] * length + a.gain[2] * velocity;
    double f = gain * a.ctrl + a.bias[0] + a.bias[1] * length + a.bias[2] * velocity;
    if (a.force_limited) f = std::clamp(f, a.force_lo, a.force_hi);
    force[j.dof_adr] += a.gear * f;
  }
}

bool PrepareTreeStep(const Model& model, int t, Data& data, Eigen::Ref<Eigen::VectorXd> force) {
  const TreeModel& tm = *model.trees[t].dynamics;
  TreeData& d = *data.trees[t];
  ActuatorForces(model, t, data, force);
  // the poses StepTrees computed at these positions, unless qpos changed since
  TreeUpdateKinematics(tm, d);
  TreeMassMatrix(tm, d);
  TreeBiasForces(tm, d);
  TreePassiveForces(tm, d);
  return TreeFactor(tm, d, model.timestep_s);
}

void TreeFreeMotion(const Model& model, int t, Data& data,
                    const Eigen::Ref<const Eigen::VectorXd>& force) {
  // TreeStep's velocity update: the free velocity with the damper implicit, then the joints' dry
  // friction (frictionloss), before the contact and limit rows of the tree's group
  TreeFreeVelocity(*model.trees[t].dynamics, *data.trees[t], model.timestep_s, force);
}

void ResetTree(const Model& model, int t, Data& data) {
  SetTreeInitialState(model.trees[t], *data.trees[t]);
  data.trees[t]->factored = false;
}

Vec3 LinkPointVelocity(const TreeData& data, int link, const Vec3& p_W) {
  const Vec6& V = data.V[link];
  return V.tail<3>() + V.head<3>().cross(p_W);
}

void StepTrees(const Model& model, Data& data, TreeStageScratch& scratch,
               geometry::CollisionScratch& collision) {
  (void)scratch;
  if (!model.has_tool) data.bodies[model.tool] = model.initial[model.tool];
  const int ntree = static_cast<int>(model.trees.size());
  for (int t = 0; t < ntree; ++t) {
    const ArticulatedTree& tree = model.trees[t];
    TreeData& d = *data.trees[t];
    // a tree whose factor failed in stage 4 was not moved there; its velocities stay unused
    const bool stepped = d.factored;
    if (stepped) TreeIntegratePositions(*tree.dynamics, d, model.timestep_s);
    if (!stepped || !d.qpos.allFinite() || !d.qvel.allFinite()) {
      data.Warn(Warning::kNonFiniteState);
      SetTreeInitialState(tree, d);
    } else {
      TreeKinematics(*tree.dynamics, d);  // the poses at the new positions
    }
    PlaceLinkGeoms(model, t, d, collision);
    for (std::size_t j = 0; j < tree.joints.size(); ++j) {
      data.joint_at_limit[t][j] = AtLimit(tree.joints[j], d) ? 1 : 0;
    }
  }
}

}  // namespace rigidtouch::dynamics
