// Bullet peer, articulated scenes: every kinematic tree of a compiled mjModel as a btMultiBody
// (Featherstone), one link per MJCF body's joint, bodies without a joint merged into their
// parent's link, a base fixed at the world or floating (a root body with a lone free joint, as
// MuJoCo's humanoid), joint limits as
// btMultiBodyJointLimitConstraint, and the joints' springs, dampers and actuators as explicit joint
// torques before every step (as PyBullet applies a URDF's joint damping). The approximations are
// listed in docs/performance.md ("Articulated scenes").
#pragma once

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <btBulletDynamicsCommon.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::bench {

/// Pose from MuJoCo's world position (3) and row-major rotation matrix (9).
Eigen::Isometry3d MjPose(const mjtNum* position, const mjtNum* rotation);
/// The Bullet transform of a pose.
btTransform ToBullet(const Eigen::Isometry3d& pose);
/// The pose of a Bullet transform.
Eigen::Isometry3d FromBullet(const btTransform& transform);
/// The MJCF name of an element, or "#<id>" when it has none.
std::string ElementName(const mjModel& model, mjtObj type, int id);
/// The Bullet shape of a geom with its MJCF size, in the geom's own frame (plane, sphere, box,
/// capsule, cylinder). Throws `rigidtouch::Error` naming `path` and the geom for other types.
std::unique_ptr<btCollisionShape> MakeBulletShape(const mjModel& model, int geom,
                                                  const std::string& path);
/// The friction given to each Bullet object for an MJCF sliding friction `mu`: Bullet multiplies
/// the two objects' frictions, MuJoCo takes the larger; sqrt(mu) makes equal frictions agree.
double BulletFriction(double mu);

/// Returns true when `body` belongs to a kinematic tree: a body of its tree (its root below the
/// world and everything under it) has a joint other than a lone free joint of the root. A free
/// body alone, or with only welded bodies below it, is no tree.
bool IsTreeBody(const mjModel& model, int body);

/// The mass, centre of mass and principal inertia of bodies welded together (a body and the bodies
/// below it without a joint), from their own in `model` at the kinematics of `data`.
struct MergedInertia {
  double mass = 0.0;
  /// The centre of mass with axes along the principal axes of inertia, in the world.
  Eigen::Isometry3d T_world_inertial = Eigen::Isometry3d::Identity();
  /// The principal moments of inertia about those axes.
  Vec3 moments = Vec3::Zero();
};
/// Merges the bodies `bodies` (the first one's frame is kept when the others have no mass) with
/// the parallel-axis theorem.
MergedInertia MergeInertia(const mjModel& model, const mjData& data,
                           const std::vector<int>& bodies);

/// MuJoCo's contact filter between the links of one tree, for Bullet's broadphase (set as the
/// world's overlap filter; pairs of other objects keep Bullet's group and mask test): no contact
/// between a body and its parent, bodies welded together counting as one (MuJoCo's weld-parent
/// test), none between bodies whose geoms' contype and conaffinity never match, none between the
/// bodies of an MJCF <exclude>.
class TreeContactFilter final : public btOverlapFilterCallback {
 public:
  bool needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const override;
  /// No contact between links `link_a` and `link_b` (-1: the base) of `multibody`.
  void Exclude(const btMultiBody* multibody, int link_a, int link_b);
  /// Returns true when the links' pair is excluded.
  bool Excluded(const btMultiBody* multibody, int link_a, int link_b) const;
  void Clear() { excluded_.clear(); }

 private:
  std::set<std::tuple<std::uintptr_t, int, int>> excluded_;
};

/// The trees of one scene, built into a btMultiBodyDynamicsWorld and owned here.
class BulletTrees {
 public:
  BulletTrees() = default;
  BulletTrees(const BulletTrees&) = delete;
  BulletTrees& operator=(const BulletTrees&) = delete;
  ~BulletTrees();

  /// Builds every tree of `model` into `world`. `reference` must hold the kinematics at the
  /// reference configuration (qpos0, after mj_forward); `qpos`, `qvel` and `ctrl` are the initial
  /// state and controls (the keyframe). One link per joint: a body with several joints becomes a
  /// chain of massless links ending in the body's; a body without a joint is merged into its
  /// parent's link (mass, inertia and geoms). A root body with a lone free joint is a floating
  /// base (its centre of mass and principal axes the base frame, its pose and twist from the free
  /// joint's qpos and qvel); a root welded to the world is a fixed base at its pose; a root with
  /// hinges or slides hangs from a fixed base at the world frame. Throws `rigidtouch::Error`
  /// naming `path` for what is not built here: a joint other than a hinge or slide below the root
  /// (or a free joint with other joints), a floating base without mass, an actuator other than a
  /// joint's fixed-gain, affine-bias one.
  void Build(const mjModel& model, const mjData& reference, const mjtNum* qpos, const mjtNum* qvel,
             const mjtNum* ctrl, btMultiBodyDynamicsWorld& world, const std::string& path);

  /// Removes everything Build() added from the world and frees it.
  void Clear();

  /// Adds this step's joint torques: -damping qdot - stiffness (q - springref) plus each
  /// actuator's gear (gain ctrl + bias0 + bias1 l + bias2 ldot), clamped to its force range.
  void ApplyJointForces();

  /// Returns the named hinge's or slide's position in MuJoCo's coordinates (Bullet's plus
  /// qpos0). Throws `rigidtouch::Error` when no tree has that joint.
  double JointPosition(std::string_view joint) const;

  /// Returns the named tree body's collision object (null when it has no geom), or null when no
  /// tree has that body.
  const btCollisionObject* Collider(std::string_view body) const;

  /// Returns true when `body` is a body of a tree.
  bool HasBody(std::string_view body) const;

  /// Returns the named tree body's MJCF frame in the world. Throws when no tree has that body.
  Eigen::Isometry3d BodyPose(std::string_view body) const;

  /// Stores every joint's position and velocity, and every floating base's pose and twist.
  void Save();
  /// Brings back the last Save() and updates the links' poses and colliders.
  void Restore();
  /// Returns true when every joint position and velocity, and every floating base's, is finite.
  bool Finite() const;

  /// Returns the multibodies (one per tree).
  const std::vector<std::unique_ptr<btMultiBody>>& multibodies() const { return multibodies_; }
  /// Returns the contact filter between the links of a tree.
  const TreeContactFilter& contact_filter() const { return filter_; }
  /// Returns the number of joint-limit constraints.
  int limit_count() const { return static_cast<int>(limits_.size()); }

 private:
  struct Actuator {
    double gear = 1, gain = 0, bias0 = 0, bias1 = 0, bias2 = 0, ctrl = 0;
    bool force_limited = false;
    double force_lo = 0, force_hi = 0;
  };
  struct Joint {
    int tree = -1, link = -1;
    double qpos0 = 0, stiffness = 0, springref = 0, damping = 0;
    std::vector<Actuator> actuators;
  };
  struct Link {
    int tree = -1, link = -1;  // link -1: the tree's base
    btMultiBodyLinkCollider* collider = nullptr;
    Eigen::Isometry3d T_link_body = Eigen::Isometry3d::Identity();  // MJCF frame in the link's
  };

  struct Tree {
    bool floating = false;
    int free_joint = -1;                                            // floating bases only
    Eigen::Isometry3d T_body_base = Eigen::Isometry3d::Identity();  // base frame in the root's
  };
  struct SavedBase {
    btVector3 position, velocity, omega;
    btQuaternion world_to_base;
  };

  int BuildTree(const mjModel& model, const mjData& reference, int root, const mjtNum* ctrl,
                const std::string& path);
  void SetFloatingBase(const mjModel& model, const Tree& tree, btMultiBody& multibody,
                       const mjtNum* qpos, const mjtNum* qvel);
  void AddJoint(const mjModel& model, int j, int tree, int link, const mjtNum* ctrl);
  void AddCollider(const mjModel& model, const mjData& reference, const std::vector<int>& bodies,
                   btMultiBody& multibody, int tree, int i, const Eigen::Isometry3d& T_world_link,
                   const std::string& path);
  void UpdatePoses(btMultiBody& multibody);
  void ExcludeTreePairs(const mjModel& model, int root, bool welded_root,
                        const std::unordered_map<int, int>& group_of,
                        const std::unordered_map<int, int>& link_of_group,
                        const btMultiBody& multibody);

  btMultiBodyDynamicsWorld* world_ = nullptr;
  TreeContactFilter filter_;  // the world's overlap filter while Build()'s trees are in it
  std::vector<std::unique_ptr<btMultiBody>> multibodies_;
  std::vector<Tree> trees_;  // one per multibody
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders_;
  std::vector<std::unique_ptr<btMultiBodyJointLimitConstraint>> limits_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<Joint> joints_;
  std::unordered_map<std::string, int> joint_index_;
  std::unordered_map<std::string, Link> links_;
  std::vector<double> saved_;
  std::vector<SavedBase> saved_bases_;  // one per multibody
};

}  // namespace rigidtouch::bench
