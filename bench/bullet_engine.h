// Bullet peer: a btDiscreteDynamicsWorld built from the compiled mjModel of the same MJCF file
// (geom types, sizes and poses, body masses and inertias; a btMultiBodyDynamicsWorld with the
// kinematic trees as btMultiBody when the scene has any: bench/bullet_tree.h), stepped with one
// fixed step of the MJCF timestep per Step(), with Bullet's default solver settings or the ones
// Bullet's own documentation and examples give for stable stacks (PeerSettings::kStacking).
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "bench/bullet_tree.h"
#include "bench/engine.h"

namespace rigidtouch::bench {

/// The solver and contact settings of PeerSettings::kStacking, each from Bullet's own
/// documentation or examples (docs/performance.md, "Peer configuration", gives the source of
/// each). The time step is the scene's: one step of it per Step(), never sub-stepped.
struct BulletStackingSettings {
  int iterations = 50;  ///< Bullet's default: 10
  /// Bullet's default: warm starting and SIMD only
  int solver_mode = SOLVER_USE_WARMSTARTING | SOLVER_SIMD | SOLVER_RANDMIZE_ORDER |
                    SOLVER_USE_2_FRICTION_DIRECTIONS | SOLVER_ENABLE_FRICTION_DIRECTION_CACHING |
                    SOLVER_DISABLE_VELOCITY_DEPENDENT_FRICTION_DIRECTION;
};

/// The Bullet engine: the constant tool force goes through applyCentralForce every step.
/// Sleeping (deactivation) is disabled for every body, as MuJoCo has none.
class BulletEngine final : public Engine {
 public:
  /// Makes an engine with nothing loaded.
  BulletEngine();
  /// Frees everything the last Load() made.
  ~BulletEngine() override;

  std::string_view Name() const override { return "bullet"; }
  RIGIDTOUCH_PEER_ENGINE_OVERRIDES
  long WarningCount() const override { return 0; }

  /// Returns the Bullet body built for the named MJCF body (null for a static one). Throws
  /// `rigidtouch::Error` when the scene has no such body.
  const btRigidBody* RigidBody(std::string_view body) const;

  /// Returns the dynamics world (null before Load()).
  const btDiscreteDynamicsWorld* world() const { return world_.get(); }

  /// Returns the scene's kinematic trees as btMultiBody (empty for a scene without trees).
  const BulletTrees& trees() const { return trees_; }

  /// Returns the time step, in seconds, taken from the MJCF `<option timestep>`.
  double timestep_s() const { return timestep_s_; }

 private:
  // one MJCF body; static bodies have body == nullptr and a fixed pose
  struct BodyRecord {
    btRigidBody* body = nullptr;
    Eigen::Isometry3d T_inertial_body = Eigen::Isometry3d::Identity();  // body frame in COM frame
    Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();     // static bodies only
  };
  struct SavedMotion {
    btTransform transform;
    btVector3 linear_velocity;
    btVector3 angular_velocity;
  };

  void Clear();
  void BuildTrees(const mjModel& model);
  const BodyRecord& Record(std::string_view body) const;
  const btCollisionObject* CollisionObject(std::string_view body) const;
  btRigidBody* AddBody(double mass_kg, const btVector3& inertia_kgm2, btCollisionShape* shape,
                       const Eigen::Isometry3d& T_world_inertial, double friction);

  std::string path_;
  // declaration order is destruction order in reverse: bodies go before the world they are in
  std::unique_ptr<btDefaultCollisionConfiguration> configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  btMultiBodyDynamicsWorld* multibody_world_ = nullptr;  // world_, when the scene has trees
  BulletTrees trees_;  // cleared (out of the world) before the world goes
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;  // dynamic and static
  std::vector<btRigidBody*> dynamic_bodies_;
  std::unordered_map<std::string, BodyRecord> records_;
  std::vector<SavedMotion> snapshot_;
  btRigidBody* tool_ = nullptr;
  btVector3 tool_force_N_{0, 0, 0};
  double timestep_s_ = 0.0;
  PeerSettings settings_ = PeerSettings::kDefaults;
};

/// Makes an unloaded Bullet engine.
std::unique_ptr<Engine> MakeBulletEngine();

}  // namespace rigidtouch::bench
