#include "bench/bullet_tree.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <tuple>

namespace rigidtouch::bench {
namespace {

bool FiniteScalar(btScalar value) {
  return std::isfinite(static_cast<double>(value));
}

Vec3 MjVec(const mjtNum* v) {
  return Vec3(v[0], v[1], v[2]);
}

btVector3 ToBt(const Vec3& v) {
  return btVector3(v.x(), v.y(), v.z());
}

// a link's frame: its centre of mass, axes along the principal axes of its inertia plus the
// joint's armature (a rotor inertia about the joint axis, which Bullet does not have)
struct LinkFrame {
  Eigen::Isometry3d T_world_link = Eigen::Isometry3d::Identity();
  Vec3 moments = Vec3::Zero();
};

// `dummy`: a massless link for a body's joint other than its last one (a btMultiBody link has
// one joint; MuJoCo composes a body's joints in order), at the joint's anchor in the body's
// orientation, with only the joint's armature as inertia; otherwise the link of the body and the
// bodies welded below it, `merged`
LinkFrame MakeLinkFrame(const mjModel& model, const mjData& reference, int body, int joint,
                        bool dummy, const MergedInertia& merged) {
  LinkFrame frame;
  if (dummy) {
    frame.T_world_link = MjPose(reference.xanchor + 3 * joint, reference.xmat + 9 * body);
  } else {
    frame.T_world_link = merged.T_world_inertial;
    frame.moments = merged.moments;
  }
  const double armature = model.dof_armature[model.jnt_dofadr[joint]];
  if (armature > 0.0 && model.jnt_type[joint] == mjJNT_HINGE) {
    const Mat3 R_world_inertial = frame.T_world_link.linear();
    const Vec3 axis = R_world_inertial.transpose() * MjVec(reference.xaxis + 3 * joint);
    const Mat3 inertia = Mat3(frame.moments.asDiagonal()) + armature * axis * axis.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(inertia);
    Mat3 axes = solver.eigenvectors();
    if (axes.determinant() < 0) axes.col(2) *= -1.0;
    frame.T_world_link.linear() = R_world_inertial * axes;
    frame.moments = solver.eigenvalues().cwiseMax(0.0);
  }
  return frame;
}

// sets up link i of `multibody` for MuJoCo joint j (hinge or slide) between the parent's frame
// and the link's, both at the reference configuration
void SetupLink(btMultiBody& multibody, int i, int parent, const Eigen::Isometry3d& T_world_parent,
               const LinkFrame& frame, double mass, const mjModel& model, const mjData& reference,
               int j) {
  const Mat3 R_link_world = frame.T_world_link.linear().transpose();
  const Eigen::Quaterniond rotation(R_link_world * T_world_parent.linear());
  const Vec3 axis = R_link_world * MjVec(reference.xaxis + 3 * j);
  const Vec3 anchor_W = MjVec(reference.xanchor + 3 * j);
  const Vec3 parent_to_pivot =
      T_world_parent.linear().transpose() * (anchor_W - T_world_parent.translation());
  const Vec3 pivot_to_com = R_link_world * (frame.T_world_link.translation() - anchor_W);
  const btQuaternion bt_rotation(rotation.x(), rotation.y(), rotation.z(), rotation.w());
  if (model.jnt_type[j] == mjJNT_HINGE) {
    multibody.setupRevolute(i, mass, ToBt(frame.moments), parent, bt_rotation, ToBt(axis),
                            ToBt(parent_to_pivot), ToBt(pivot_to_com), true);
  } else {
    multibody.setupPrismatic(i, mass, ToBt(frame.moments), parent, bt_rotation, ToBt(axis),
                             ToBt(parent_to_pivot), ToBt(pivot_to_com), true);
  }
}

}  // namespace

Eigen::Isometry3d MjPose(const mjtNum* position, const mjtNum* rotation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Vec3(position[0], position[1], position[2]);
  pose.linear() = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rotation);
  return pose;
}

btTransform ToBullet(const Eigen::Isometry3d& pose) {
  const Mat3& r = pose.linear();
  const Vec3& p = pose.translation();
  return btTransform(
      btMatrix3x3(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
      btVector3(p.x(), p.y(), p.z()));
}

Eigen::Isometry3d FromBullet(const btTransform& transform) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const btMatrix3x3& r = transform.getBasis();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) pose.linear()(i, j) = r[i][j];
  }
  const btVector3& p = transform.getOrigin();
  pose.translation() = Vec3(p.x(), p.y(), p.z());
  return pose;
}

std::string ElementName(const mjModel& model, mjtObj type, int id) {
  const char* name = mj_id2name(&model, type, id);
  if (name != nullptr) return name;
  std::string unnamed = "#";
  unnamed.append(std::to_string(id));
  return unnamed;
}

std::unique_ptr<btCollisionShape> MakeBulletShape(const mjModel& model, int geom,
                                                  const std::string& path) {
  const mjtNum* size = model.geom_size + 3 * geom;
  switch (model.geom_type[geom]) {
    case mjGEOM_PLANE:
      return std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0);
    case mjGEOM_SPHERE:
      return std::make_unique<btSphereShape>(size[0]);
    case mjGEOM_BOX:
      return std::make_unique<btBoxShape>(btVector3(size[0], size[1], size[2]));
    case mjGEOM_CAPSULE:
      return std::make_unique<btCapsuleShapeZ>(size[0], 2 * size[1]);
    case mjGEOM_CYLINDER:
      return std::make_unique<btCylinderShapeZ>(btVector3(size[0], size[0], size[1]));
    default:
      throw Error("scene " + path + ": geom '" + ElementName(model, mjOBJ_GEOM, geom) +
                  "' has type " + std::to_string(model.geom_type[geom]) +
                  "; the Bullet peer supports plane, sphere, box, capsule and cylinder");
  }
}

double BulletFriction(double mu) {
  return std::sqrt(std::max(mu, 0.0));
}

bool IsTreeBody(const mjModel& model, int body) {
  if (body <= 0) return false;
  const int root = model.body_rootid[body];
  for (int b = root; b < model.nbody; ++b) {
    const int n = model.body_jntnum[b];
    if (model.body_rootid[b] != root || n == 0) continue;
    const bool lone_free =
        b == root && n == 1 && model.jnt_type[model.body_jntadr[b]] == mjJNT_FREE;
    if (!lone_free) return true;
  }
  return false;
}

MergedInertia MergeInertia(const mjModel& model, const mjData& data,
                           const std::vector<int>& bodies) {
  const int first = bodies.front();
  MergedInertia merged;
  merged.mass = model.body_mass[first];
  merged.T_world_inertial = MjPose(data.xipos + 3 * first, data.ximat + 9 * first);
  merged.moments = MjVec(model.body_inertia + 3 * first);
  double mass = 0.0;
  Vec3 moment = Vec3::Zero();
  for (const int b : bodies) {
    mass += model.body_mass[b];
    moment += model.body_mass[b] * MjVec(data.xipos + 3 * b);
  }
  if (!(mass > merged.mass)) return merged;  // the welded bodies add no mass
  // the bodies' inertias about the common centre of mass, in the world (parallel axes)
  const Vec3 com = moment / mass;
  Mat3 inertia = Mat3::Zero();
  for (const int b : bodies) {
    const Mat3 R_world_inertial = MjPose(data.xipos + 3 * b, data.ximat + 9 * b).linear();
    const Vec3 d = MjVec(data.xipos + 3 * b) - com;
    inertia += R_world_inertial * MjVec(model.body_inertia + 3 * b).asDiagonal() *
                   R_world_inertial.transpose() +
               model.body_mass[b] * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(inertia);
  Mat3 axes = solver.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) *= -1.0;
  merged.mass = mass;
  merged.T_world_inertial.translation() = com;
  merged.T_world_inertial.linear() = axes;
  merged.moments = solver.eigenvalues().cwiseMax(0.0);
  return merged;
}

bool TreeContactFilter::needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const {
  // Bullet's own test first (btHashedOverlappingPairCache's, without a filter)
  const bool collides = (a->m_collisionFilterGroup & b->m_collisionFilterMask) != 0 &&
                        (b->m_collisionFilterGroup & a->m_collisionFilterMask) != 0;
  if (!collides) return false;
  const btMultiBodyLinkCollider* link_a =
      btMultiBodyLinkCollider::upcast(static_cast<const btCollisionObject*>(a->m_clientObject));
  const btMultiBodyLinkCollider* link_b =
      btMultiBodyLinkCollider::upcast(static_cast<const btCollisionObject*>(b->m_clientObject));
  if (link_a == nullptr || link_b == nullptr || link_a->m_multiBody != link_b->m_multiBody) {
    return true;
  }
  return !Excluded(link_a->m_multiBody, link_a->m_link, link_b->m_link);
}

void TreeContactFilter::Exclude(const btMultiBody* multibody, int link_a, int link_b) {
  excluded_.emplace(reinterpret_cast<std::uintptr_t>(multibody), std::min(link_a, link_b),
                    std::max(link_a, link_b));
}

bool TreeContactFilter::Excluded(const btMultiBody* multibody, int link_a, int link_b) const {
  return excluded_.count(std::make_tuple(reinterpret_cast<std::uintptr_t>(multibody),
                                         std::min(link_a, link_b), std::max(link_a, link_b))) > 0;
}

BulletTrees::~BulletTrees() {
  Clear();
}

void BulletTrees::Clear() {
  if (world_ != nullptr) {
    world_->getPairCache()->setOverlapFilterCallback(nullptr);
    for (auto& limit : limits_) world_->removeMultiBodyConstraint(limit.get());
    for (auto& collider : colliders_) world_->removeCollisionObject(collider.get());
    for (auto& multibody : multibodies_) world_->removeMultiBody(multibody.get());
  }
  filter_.Clear();
  limits_.clear();
  colliders_.clear();
  multibodies_.clear();
  shapes_.clear();
  trees_.clear();
  saved_bases_.clear();
  joints_.clear();
  joint_index_.clear();
  links_.clear();
  saved_.clear();
  world_ = nullptr;
}

void BulletTrees::Build(const mjModel& model, const mjData& reference, const mjtNum* qpos,
                        const mjtNum* qvel, const mjtNum* ctrl, btMultiBodyDynamicsWorld& world,
                        const std::string& path) {
  Clear();
  world_ = &world;
  // before any link is added: the broadphase pairs a new object with the others at once
  world_->getPairCache()->setOverlapFilterCallback(&filter_);
  for (int a = 0; a < model.nu; ++a) {
    const int target = model.actuator_trnid[2 * a];
    const bool on_tree_joint =
        model.actuator_trntype[a] == mjTRN_JOINT && IsTreeBody(model, model.jnt_bodyid[target]);
    const bool supported =
        model.actuator_dyntype[a] == mjDYN_NONE && model.actuator_gaintype[a] == mjGAIN_FIXED &&
        (model.actuator_biastype[a] == mjBIAS_NONE || model.actuator_biastype[a] == mjBIAS_AFFINE);
    if (!on_tree_joint || !supported) {
      throw Error("scene " + path + ": actuator '" + ElementName(model, mjOBJ_ACTUATOR, a) +
                  "' is not a joint actuator with a fixed gain and an affine bias (motor, "
                  "position, velocity); the Bullet peer supports only those");
    }
  }
  for (int b = 1; b < model.nbody; ++b) {
    if (model.body_parentid[b] == 0 && IsTreeBody(model, b)) {
      BuildTree(model, reference, b, ctrl, path);
    }
  }
  for (int j = 0; j < model.njnt; ++j) {
    const auto it = joint_index_.find(ElementName(model, mjOBJ_JOINT, j));
    if (it == joint_index_.end()) continue;
    const Joint& joint = joints_[static_cast<std::size_t>(it->second)];
    btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(joint.tree)];
    multibody.setJointPos(joint.link, qpos[model.jnt_qposadr[j]] - joint.qpos0);
    multibody.setJointVel(joint.link, qvel[model.jnt_dofadr[j]]);
  }
  for (std::size_t t = 0; t < multibodies_.size(); ++t) {
    if (trees_[t].floating) SetFloatingBase(model, trees_[t], *multibodies_[t], qpos, qvel);
    UpdatePoses(*multibodies_[t]);
  }
}

void BulletTrees::SetFloatingBase(const mjModel& model, const Tree& tree, btMultiBody& multibody,
                                  const mjtNum* qpos, const mjtNum* qvel) {
  // MuJoCo's free joint: qpos the body frame's origin and orientation (w, x, y, z) in the world;
  // qvel the origin's linear velocity in the world, then the angular velocity in the body's frame
  const mjtNum* q = qpos + model.jnt_qposadr[tree.free_joint];
  const mjtNum* v = qvel + model.jnt_dofadr[tree.free_joint];
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  T_world_body.translation() = Vec3(q[0], q[1], q[2]);
  T_world_body.linear() = Quat(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
  const Eigen::Isometry3d T_world_base = T_world_body * tree.T_body_base;
  // Bullet's base: the centre of mass's velocity and the angular velocity, both in the world
  const Vec3 omega_W = T_world_body.linear() * Vec3(v[3], v[4], v[5]);
  const Vec3 velocity_W = Vec3(v[0], v[1], v[2]) +
                          omega_W.cross(T_world_base.translation() - T_world_body.translation());
  multibody.setBaseWorldTransform(ToBullet(T_world_base));
  multibody.setBaseVel(ToBt(velocity_W));
  multibody.setBaseOmega(ToBt(omega_W));
}

namespace {

// a tree's bodies grouped into links: each body with a joint (and the root) with the bodies welded
// below it, in MuJoCo's order; and one link spec (body, joint) per hinge or slide
struct TreeLayout {
  std::unordered_map<int, std::vector<int>> welded;  // body with a joint or root -> its group
  std::unordered_map<int, int> group_of;             // body -> the body heading its group
  std::vector<std::pair<int, int>> specs;            // (body, joint)
  bool floating = false;                             // the root has a lone free joint
  bool welded_root = false;                          // the root has no joint
};

TreeLayout LayOutTree(const mjModel& model, int root, const std::string& path) {
  TreeLayout layout;
  const int root_joints = model.body_jntnum[root];
  layout.floating = root_joints == 1 && model.jnt_type[model.body_jntadr[root]] == mjJNT_FREE;
  layout.welded_root = root_joints == 0;
  for (int b = root; b < model.nbody; ++b) {
    if (model.body_rootid[b] != root) continue;
    const bool heads = b == root || model.body_jntnum[b] > 0;
    const int group = heads ? b : layout.group_of.at(model.body_parentid[b]);
    layout.group_of[b] = group;
    layout.welded[group].push_back(b);
    if (b == root && (layout.floating || layout.welded_root)) continue;  // the base
    for (int j = model.body_jntadr[b]; j < model.body_jntadr[b] + model.body_jntnum[b]; ++j) {
      if (model.jnt_type[j] != mjJNT_HINGE && model.jnt_type[j] != mjJNT_SLIDE) {
        const char* kind = model.jnt_type[j] == mjJNT_BALL ? "a ball joint" : "a free joint";
        throw Error("scene " + path + ": joint '" + ElementName(model, mjOBJ_JOINT, j) +
                    "' of body '" + ElementName(model, mjOBJ_BODY, b) + "' is " + kind +
                    "; the Bullet peer's btMultiBody takes hinges and slides, and a lone free "
                    "joint of a tree's root body as its floating base");
      }
      layout.specs.emplace_back(b, j);
    }
  }
  return layout;
}

}  // namespace

int BulletTrees::BuildTree(const mjModel& model, const mjData& reference, int root,
                           const mjtNum* ctrl, const std::string& path) {
  // one link per joint, a body's joints in MuJoCo's order; bodies without a joint in their
  // parent's link
  const TreeLayout layout = LayOutTree(model, root, path);
  const auto& specs = layout.specs;
  const int tree = static_cast<int>(multibodies_.size());
  // the base: a floating root body (its centre of mass and principal axes), a root welded to the
  // world (at its pose), or else a fixed base at the world frame for the root's joints
  Tree info;
  info.floating = layout.floating;
  const bool root_is_base = layout.floating || layout.welded_root;
  Eigen::Isometry3d T_world_base = Eigen::Isometry3d::Identity();
  double base_mass = 1.0;
  Vec3 base_moments(1, 1, 1);
  if (root_is_base) {
    const Eigen::Isometry3d T_world_root =
        MjPose(reference.xpos + 3 * root, reference.xmat + 9 * root);
    T_world_base = T_world_root;
    if (layout.floating) {
      const MergedInertia merged = MergeInertia(model, reference, layout.welded.at(root));
      if (!(merged.mass > 0.0)) {
        throw Error("scene " + path + ": free body '" + ElementName(model, mjOBJ_BODY, root) +
                    "' (with the bodies welded to it) has no mass; the Bullet peer's floating "
                    "base needs one");
      }
      T_world_base = merged.T_world_inertial;
      base_mass = merged.mass;
      base_moments = merged.moments;
      info.free_joint = model.body_jntadr[root];
    }
    info.T_body_base = T_world_root.inverse() * T_world_base;
  }
  auto multibody = std::make_unique<btMultiBody>(static_cast<int>(specs.size()), base_mass,
                                                 ToBt(base_moments), !layout.floating, false);
  multibody->setBaseWorldTransform(ToBullet(T_world_base));
  std::unordered_map<int, int> link_of_group;  // a group's link: the last of its head's joints
  if (root_is_base) link_of_group[root] = -1;
  for (int i = 0; i < static_cast<int>(specs.size()); ++i) link_of_group[specs[i].first] = i;
  ExcludeTreePairs(model, root, layout.welded_root, layout.group_of, link_of_group, *multibody);
  if (root_is_base) {
    AddCollider(model, reference, layout.welded.at(root), *multibody, tree, -1, T_world_base, path);
  }
  std::unordered_map<int, int> last_link_of;  // MuJoCo body -> its last joint's link
  std::vector<LinkFrame> frames;
  std::vector<std::pair<int, int>> limited;  // (link, joint)
  for (int i = 0; i < static_cast<int>(specs.size()); ++i) {
    const auto [b, j] = specs[static_cast<std::size_t>(i)];
    const bool first = j == model.body_jntadr[b];
    const bool last = j == model.body_jntadr[b] + model.body_jntnum[b] - 1;
    // a body's first joint hangs from its parent's group: the base for the root's (or for the
    // root's own joints), else that group's last link
    const int parent_group = b == root ? -1 : layout.group_of.at(model.body_parentid[b]);
    const int parent = !first ? i - 1
                       : parent_group < 0 || (parent_group == root && root_is_base)
                           ? -1
                           : last_link_of.at(parent_group);
    const Eigen::Isometry3d T_world_parent =
        parent < 0 ? T_world_base : frames[static_cast<std::size_t>(parent)].T_world_link;
    const MergedInertia merged =
        last ? MergeInertia(model, reference, layout.welded.at(b)) : MergedInertia{};
    const LinkFrame frame = MakeLinkFrame(model, reference, b, j, !last, merged);
    SetupLink(*multibody, i, parent, T_world_parent, frame, last ? merged.mass : 0.0, model,
              reference, j);
    frames.push_back(frame);
    AddJoint(model, j, tree, i, ctrl);
    if (model.jnt_limited[j]) limited.emplace_back(i, j);
    if (last) {
      last_link_of[b] = i;
      AddCollider(model, reference, layout.welded.at(b), *multibody, tree, i, frame.T_world_link,
                  path);
    }
  }
  // MuJoCo has no damping of link velocities; Bullet's default is 0.04
  multibody->setLinearDamping(0);
  multibody->setAngularDamping(0);
  // contacts between the links of one tree as MuJoCo has them (TreeContactFilter): Bullet's own
  // parent flags would see the massless links of a body with several joints as parents
  multibody->setHasSelfCollision(true);
  multibody->finalizeMultiDof();
  world_->addMultiBody(multibody.get());
  for (const auto& [link, j] : limited) {
    const double qpos0 = model.qpos0[model.jnt_qposadr[j]];
    limits_.push_back(std::make_unique<btMultiBodyJointLimitConstraint>(
        multibody.get(), link, model.jnt_range[2 * j] - qpos0, model.jnt_range[2 * j + 1] - qpos0));
    world_->addMultiBodyConstraint(limits_.back().get());
  }
  multibodies_.push_back(std::move(multibody));
  trees_.push_back(info);
  return tree;
}

void BulletTrees::ExcludeTreePairs(const mjModel& model, int root, bool welded_root,
                                   const std::unordered_map<int, int>& group_of,
                                   const std::unordered_map<int, int>& link_of_group,
                                   const btMultiBody& multibody) {
  const auto compatible = [&model](int g1, int g2) {
    return (model.geom_contype[g1] & model.geom_conaffinity[g2]) != 0 ||
           (model.geom_contype[g2] & model.geom_conaffinity[g1]) != 0;
  };
  // the bodies of each group, for their geoms
  std::unordered_map<int, std::vector<int>> bodies;
  for (const auto& [b, group] : group_of) bodies[group].push_back(b);
  for (const auto& [g1, link1] : link_of_group) {
    for (const auto& [g2, link2] : link_of_group) {
      if (link1 >= link2) continue;
      // MuJoCo's weld-parent test: a root welded to the world is the world's, never excluded
      const auto parent_of = [&](int g) {
        return g == root ? -1 : group_of.at(model.body_parentid[g]);
      };
      const bool parent_child = (parent_of(g2) == g1 || parent_of(g1) == g2) &&
                                !(welded_root && (g1 == root || g2 == root));
      bool any_compatible = false;
      for (const int b1 : bodies.at(g1)) {
        for (const int b2 : bodies.at(g2)) {
          for (int a = model.body_geomadr[b1]; a < model.body_geomadr[b1] + model.body_geomnum[b1];
               ++a) {
            for (int c = model.body_geomadr[b2];
                 c < model.body_geomadr[b2] + model.body_geomnum[b2]; ++c) {
              any_compatible |= compatible(a, c);
            }
          }
        }
      }
      if (parent_child || !any_compatible) filter_.Exclude(&multibody, link1, link2);
    }
  }
  // <exclude body1 body2>: MuJoCo's signature is ((body1 + 1) << 16) + body2 + 1
  for (int e = 0; e < model.nexclude; ++e) {
    const auto b1 = group_of.find((model.exclude_signature[e] >> 16) - 1);
    const auto b2 = group_of.find((model.exclude_signature[e] & 0xFFFF) - 1);
    if (b1 == group_of.end() || b2 == group_of.end()) continue;
    filter_.Exclude(&multibody, link_of_group.at(b1->second), link_of_group.at(b2->second));
  }
}

void BulletTrees::AddJoint(const mjModel& model, int j, int tree, int link, const mjtNum* ctrl) {
  Joint joint;
  joint.tree = tree;
  joint.link = link;
  joint.qpos0 = model.qpos0[model.jnt_qposadr[j]];
  joint.stiffness = model.jnt_stiffness[j];
  joint.springref = model.qpos_spring[model.jnt_qposadr[j]];
  joint.damping = model.dof_damping[model.jnt_dofadr[j]];
  for (int a = 0; a < model.nu; ++a) {
    if (model.actuator_trnid[2 * a] != j) continue;
    Actuator actuator;
    actuator.gear = model.actuator_gear[6 * a];
    actuator.gain = model.actuator_gainprm[mjNGAIN * a];
    if (model.actuator_biastype[a] == mjBIAS_AFFINE) {
      actuator.bias0 = model.actuator_biasprm[mjNBIAS * a];
      actuator.bias1 = model.actuator_biasprm[mjNBIAS * a + 1];
      actuator.bias2 = model.actuator_biasprm[mjNBIAS * a + 2];
    }
    actuator.ctrl = ctrl[a];
    if (model.actuator_ctrllimited[a]) {
      actuator.ctrl = std::clamp(actuator.ctrl, model.actuator_ctrlrange[2 * a],
                                 model.actuator_ctrlrange[2 * a + 1]);
    }
    actuator.force_limited = model.actuator_forcelimited[a] != 0;
    actuator.force_lo = model.actuator_forcerange[2 * a];
    actuator.force_hi = model.actuator_forcerange[2 * a + 1];
    joint.actuators.push_back(actuator);
  }
  joint_index_[ElementName(model, mjOBJ_JOINT, j)] = static_cast<int>(joints_.size());
  joints_.push_back(joint);
}

void BulletTrees::AddCollider(const mjModel& model, const mjData& reference,
                              const std::vector<int>& bodies, btMultiBody& multibody, int tree,
                              int i, const Eigen::Isometry3d& T_world_link,
                              const std::string& path) {
  // one compound of the geoms of the link's bodies (a body and those welded below it)
  auto compound = std::make_unique<btCompoundShape>();
  int first_geom = -1;
  for (const int b : bodies) {
    for (int g = model.body_geomadr[b]; g < model.body_geomadr[b] + model.body_geomnum[b]; ++g) {
      if (first_geom < 0) first_geom = g;
      shapes_.push_back(MakeBulletShape(model, g, path));
      const Eigen::Isometry3d T_link_geom =
          T_world_link.inverse() * MjPose(reference.geom_xpos + 3 * g, reference.geom_xmat + 9 * g);
      compound->addChildShape(ToBullet(T_link_geom), shapes_.back().get());
    }
  }
  btMultiBodyLinkCollider* made = nullptr;
  if (first_geom >= 0) {
    shapes_.push_back(std::move(compound));
    auto collider = std::make_unique<btMultiBodyLinkCollider>(&multibody, i);
    collider->setCollisionShape(shapes_.back().get());
    collider->setWorldTransform(ToBullet(T_world_link));
    // Bullet keeps one friction per object: the first geom's
    collider->setFriction(BulletFriction(model.geom_friction[3 * first_geom]));
    collider->setRestitution(0);
    const bool fixed = i < 0 && multibody.hasFixedBase();
    if (fixed) {
      // a base welded to the world is static, as the bodies welded to the world are
      collider->setCollisionFlags(collider->getCollisionFlags() |
                                  btCollisionObject::CF_STATIC_OBJECT);
      world_->addCollisionObject(collider.get(), btBroadphaseProxy::StaticFilter,
                                 btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
    } else {
      world_->addCollisionObject(collider.get(), btBroadphaseProxy::DefaultFilter,
                                 btBroadphaseProxy::AllFilter);
    }
    if (i < 0) {
      multibody.setBaseCollider(collider.get());
    } else {
      multibody.getLink(i).m_collider = collider.get();
    }
    made = collider.get();
    colliders_.push_back(std::move(collider));
  }
  for (const int b : bodies) {
    Link link;
    link.tree = tree;
    link.link = i;
    link.collider = made;
    link.T_link_body =
        T_world_link.inverse() * MjPose(reference.xpos + 3 * b, reference.xmat + 9 * b);
    links_[ElementName(model, mjOBJ_BODY, b)] = link;
  }
}

void BulletTrees::UpdatePoses(btMultiBody& multibody) {
  btAlignedObjectArray<btQuaternion> world_to_local;
  btAlignedObjectArray<btVector3> local_origin;
  multibody.forwardKinematics(world_to_local, local_origin);
  multibody.updateCollisionObjectWorldTransforms(world_to_local, local_origin);
}

void BulletTrees::ApplyJointForces() {
  for (const Joint& joint : joints_) {
    btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(joint.tree)];
    const double q = multibody.getJointPos(joint.link) + joint.qpos0;
    const double qdot = multibody.getJointVel(joint.link);
    double torque = -joint.damping * qdot - joint.stiffness * (q - joint.springref);
    for (const Actuator& a : joint.actuators) {
      double force = a.gain * a.ctrl + a.bias0 + a.bias1 * a.gear * q + a.bias2 * a.gear * qdot;
      if (a.force_limited) force = std::clamp(force, a.force_lo, a.force_hi);
      torque += a.gear * force;
    }
    multibody.addJointTorque(joint.link, torque);
  }
}

double BulletTrees::JointPosition(std::string_view joint) const {
  const auto it = joint_index_.find(std::string(joint));
  if (it == joint_index_.end()) {
    throw Error("the Bullet peer's trees have no hinge or slide joint named '" +
                std::string(joint) + "'");
  }
  const Joint& j = joints_[static_cast<std::size_t>(it->second)];
  return multibodies_[static_cast<std::size_t>(j.tree)]->getJointPos(j.link) + j.qpos0;
}

const btCollisionObject* BulletTrees::Collider(std::string_view body) const {
  const auto it = links_.find(std::string(body));
  return it == links_.end() ? nullptr : it->second.collider;
}

bool BulletTrees::HasBody(std::string_view body) const {
  return links_.count(std::string(body)) > 0;
}

Eigen::Isometry3d BulletTrees::BodyPose(std::string_view body) const {
  const auto it = links_.find(std::string(body));
  if (it == links_.end()) {
    throw Error("the Bullet peer's trees have no body named '" + std::string(body) + "'");
  }
  const Link& link = it->second;
  const btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(link.tree)];
  // the collider's pose is the link's after the last step's integration; the cached one is from
  // the kinematics at the step's start
  const btTransform T_world_link = link.collider != nullptr ? link.collider->getWorldTransform()
                                   : link.link < 0
                                       ? multibody.getBaseWorldTransform()
                                       : multibody.getLink(link.link).m_cachedWorldTransform;
  return FromBullet(T_world_link) * link.T_link_body;
}

void BulletTrees::Save() {
  saved_bases_.clear();
  for (const auto& multibody : multibodies_) {
    saved_bases_.push_back(SavedBase{multibody->getBasePos(), multibody->getBaseVel(),
                                     multibody->getBaseOmega(), multibody->getWorldToBaseRot()});
  }
  saved_.clear();
  for (const Joint& joint : joints_) {
    const btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(joint.tree)];
    saved_.push_back(multibody.getJointPos(joint.link));
    saved_.push_back(multibody.getJointVel(joint.link));
  }
}

void BulletTrees::Restore() {
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(joints_[k].tree)];
    multibody.setJointPos(joints_[k].link, saved_[2 * k]);
    multibody.setJointVel(joints_[k].link, saved_[2 * k + 1]);
    multibody.clearForcesAndTorques();
  }
  for (std::size_t t = 0; t < multibodies_.size() && t < saved_bases_.size(); ++t) {
    btMultiBody& multibody = *multibodies_[t];
    const SavedBase& base = saved_bases_[t];
    multibody.setBasePos(base.position);
    multibody.setWorldToBaseRot(base.world_to_base);
    multibody.setBaseVel(base.velocity);
    multibody.setBaseOmega(base.omega);
    multibody.clearForcesAndTorques();
  }
  for (auto& multibody : multibodies_) UpdatePoses(*multibody);
}

bool BulletTrees::Finite() const {
  const auto finite = [](const btVector3& v) {
    return FiniteScalar(v.x()) && FiniteScalar(v.y()) && FiniteScalar(v.z());
  };
  for (const auto& multibody : multibodies_) {
    if (!finite(multibody->getBasePos()) || !finite(multibody->getBaseVel()) ||
        !finite(multibody->getBaseOmega())) {
      return false;
    }
  }
  return std::all_of(joints_.begin(), joints_.end(), [this](const Joint& joint) {
    const btMultiBody& multibody = *multibodies_[static_cast<std::size_t>(joint.tree)];
    return FiniteScalar(multibody.getJointPos(joint.link)) &&
           FiniteScalar(multibody.getJointVel(joint.link));
  });
}

}  // namespace rigidtouch::bench
