// MuJoCo's compiled model to a kinematic tree (src/io/mjcf_tree.h).
#include "io/mjcf_tree.h"

#include <string>
#include <utility>
#include <vector>

namespace rigidtouch::io {
namespace {

Vec3 MjVec3(const mjtNum* v) {
  return Vec3(v[0], v[1], v[2]);
}
Quat MjUnitQuat(const mjtNum* q) {
  return Quat(q[0], q[1], q[2], q[3]).normalized();
}

dynamics::JointType ToJointType(int mj_type) {
  switch (mj_type) {
    case mjJNT_FREE:
      return dynamics::JointType::kFree;
    case mjJNT_BALL:
      return dynamics::JointType::kBall;
    case mjJNT_SLIDE:
      return dynamics::JointType::kSlide;
    default:
      return dynamics::JointType::kHinge;
  }
}

dynamics::TreeJoint ToJoint(const mjModel* m, int j) {
  const std::string name = "joint " + std::to_string(j);
  dynamics::TreeJoint jt;
  jt.type = ToJointType(m->jnt_type[j]);
  jt.axis = MjVec3(m->jnt_axis + 3 * j);
  jt.pos_m = MjVec3(m->jnt_pos + 3 * j);
  const int qa = m->jnt_qposadr[j];
  const int da = m->jnt_dofadr[j];
  const bool scalar =
      jt.type == dynamics::JointType::kHinge || jt.type == dynamics::JointType::kSlide;
  if (scalar) {
    jt.ref = m->qpos0[qa];
    jt.spring_ref = m->qpos_spring[qa];
  } else if (jt.type == dynamics::JointType::kBall) {
    jt.spring_quat = MjUnitQuat(m->qpos_spring + qa);
  } else if (m->jnt_stiffness[j] != 0.0) {
    throw Error(name + ": stiffness on a free joint is not modelled by the tree");
  }
  jt.stiffness = m->jnt_stiffness[j];
  jt.damping = m->dof_damping[da];
  jt.armature = m->dof_armature[da];
  jt.frictionloss = m->dof_frictionloss[da];
  const int ndof = jt.type == dynamics::JointType::kFree   ? 6
                   : jt.type == dynamics::JointType::kBall ? 3
                                                           : 1;
  for (int k = 1; k < ndof; ++k) {
    if (m->dof_damping[da + k] != jt.damping || m->dof_armature[da + k] != jt.armature ||
        m->dof_frictionloss[da + k] != jt.frictionloss) {
      throw Error(name + ": its dofs differ in damping, armature or frictionloss");
    }
  }
  return jt;
}

}  // namespace

dynamics::TreeModel TreeFromMjModel(const mjModel* m) {
  std::vector<dynamics::TreeBody> bodies(m->nbody - 1);
  for (int i = 1; i < m->nbody; ++i) {
    if (m->body_mocapid[i] >= 0) {
      throw Error("body " + std::to_string(i) + ": mocap bodies are not modelled by the tree");
    }
    dynamics::TreeBody& b = bodies[i - 1];
    b.parent = m->body_parentid[i] - 1;
    b.pos_m = MjVec3(m->body_pos + 3 * i);
    b.quat = MjUnitQuat(m->body_quat + 4 * i);
    b.mass_kg = m->body_mass[i];
    b.com_m = MjVec3(m->body_ipos + 3 * i);
    const Mat3 R = MjUnitQuat(m->body_iquat + 4 * i).toRotationMatrix();
    b.inertia_kgm2 = R * MjVec3(m->body_inertia + 3 * i).asDiagonal() * R.transpose();
    b.inertia_kgm2 = 0.5 * (b.inertia_kgm2 + b.inertia_kgm2.transpose()).eval();
    for (int k = 0; k < m->body_jntnum[i]; ++k) {
      b.joints.push_back(ToJoint(m, m->body_jntadr[i] + k));
    }
  }
  return dynamics::MakeTree(std::move(bodies), MjVec3(m->opt.gravity));
}

}  // namespace rigidtouch::io
