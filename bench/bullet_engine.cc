#include "bench/bullet_engine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "bench/mujoco_engine.h"
#include "io/mjcf_compile.h"

namespace rigidtouch::bench {
namespace {

const EngineRegistrar kBulletRegistrar{"bullet", &MakeBulletEngine};

bool IsIdentity(const Eigen::Isometry3d& pose) {
  return pose.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12);
}

bool FiniteBt(const btVector3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

}  // namespace

BulletEngine::BulletEngine() = default;

BulletEngine::~BulletEngine() {
  Clear();
}

void BulletEngine::Clear() {
  trees_.Clear();
  if (world_ != nullptr) {
    for (auto& body : bodies_) world_->removeRigidBody(body.get());
  }
  bodies_.clear();
  dynamic_bodies_.clear();
  shapes_.clear();
  records_.clear();
  snapshot_.clear();
  world_.reset();
  multibody_world_ = nullptr;
  solver_.reset();
  broadphase_.reset();
  dispatcher_.reset();
  configuration_.reset();
  tool_ = nullptr;
}

btRigidBody* BulletEngine::AddBody(double mass_kg, const btVector3& inertia_kgm2,
                                   btCollisionShape* shape,
                                   const Eigen::Isometry3d& T_world_inertial, double friction) {
  btRigidBody::btRigidBodyConstructionInfo info(mass_kg, nullptr, shape, inertia_kgm2);
  info.m_startWorldTransform = ToBullet(T_world_inertial);
  info.m_friction = BulletFriction(friction);
  info.m_restitution = 0;
  auto body = std::make_unique<btRigidBody>(info);
  // no sleeping: MuJoCo keeps integrating resting bodies, so Bullet must too
  body->setActivationState(DISABLE_DEACTIVATION);
  world_->addRigidBody(body.get());
  bodies_.push_back(std::move(body));
  return bodies_.back().get();
}

void BulletEngine::Load(const Scene& scene) {
  // the same compiled model MuJoCo runs: sizes, poses, masses and inertias; compiled without
  // MuJoCo's solver sizes (Bullet needs none of them, and a file sized for MuJoCo's 1000-box pile
  // would need gigabytes for an mjData)
  std::array<char, 1024> error{};
  std::unique_ptr<mjModel, void (*)(mjModel*)> model_ptr(
      io::CompileWithoutSolverSizes(scene.mjcf_path, error.data(), static_cast<int>(error.size())),
      &mj_deleteModel);
  if (!model_ptr) {
    throw Error("scene " + scene.mjcf_path + " does not load in MuJoCo: " + error.data());
  }
  const mjModel& model = *model_ptr;
  std::unique_ptr<mjData, void (*)(mjData*)> data(mj_makeData(&model), &mj_deleteData);
  // free bodies start where the keyframe 'initial' puts them, as in MuJoCo and rigidtouch
  const int key = mj_name2id(&model, mjOBJ_KEY, "initial");
  if (key >= 0) mj_resetDataKeyframe(&model, data.get(), key);
  mj_forward(&model, data.get());

  Clear();
  path_ = scene.mjcf_path;
  configuration_ = std::make_unique<btDefaultCollisionConfiguration>();
  dispatcher_ = std::make_unique<btCollisionDispatcher>(configuration_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  bool has_trees = false;
  for (int b = 1; b < model.nbody; ++b) has_trees |= IsTreeBody(model, b);
  if (has_trees) {
    // kinematic trees: Featherstone's btMultiBody in the world PyBullet uses
    auto solver = std::make_unique<btMultiBodyConstraintSolver>();
    auto world = std::make_unique<btMultiBodyDynamicsWorld>(dispatcher_.get(), broadphase_.get(),
                                                            solver.get(), configuration_.get());
    multibody_world_ = world.get();
    solver_ = std::move(solver);
    world_ = std::move(world);
  } else {
    solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
    world_ = std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), broadphase_.get(),
                                                       solver_.get(), configuration_.get());
  }
  settings_ = scene.peer_settings;
  if (settings_ == PeerSettings::kStacking) {
    const BulletStackingSettings stacking;
    btContactSolverInfo& info = world_->getSolverInfo();
    info.m_numIterations = stacking.iterations;
    info.m_solverMode = stacking.solver_mode;
  }
  const mjtNum* gravity = model.opt.gravity;
  world_->setGravity(btVector3(gravity[0], gravity[1], gravity[2]));
  timestep_s_ = model.opt.timestep;

  for (int b = 0; b < model.nbody; ++b) {
    if (IsTreeBody(model, b)) continue;  // built below, as btMultiBody links
    const std::string body_name = ElementName(model, mjOBJ_BODY, b);
    const bool is_static = b == 0 || model.body_jntnum[b] == 0;
    if (b != 0) {
      const bool free = model.body_jntnum[b] == 1 &&
                        model.jnt_type[model.body_jntadr[b]] == mjJNT_FREE &&
                        model.body_parentid[b] == 0;
      if (!free && !(is_static && model.body_parentid[b] == 0)) {
        throw Error("scene " + path_ + ": body '" + body_name +
                    "' is neither a free body nor welded to the world; the Bullet peer supports "
                    "only those");
      }
    }
    const Eigen::Isometry3d T_world_body = MjPose(data->xpos + 3 * b, data->xmat + 9 * b);
    const int first_geom = model.body_geomadr[b];
    const int geom_count = model.body_geomnum[b];
    BodyRecord record;
    if (is_static) {
      // every static geom is its own fixed collision object at its world pose
      record.T_world_body = T_world_body;
      for (int g = first_geom; g < first_geom + geom_count; ++g) {
        shapes_.push_back(MakeBulletShape(model, g, path_));
        AddBody(0.0, btVector3(0, 0, 0), shapes_.back().get(),
                MjPose(data->geom_xpos + 3 * g, data->geom_xmat + 9 * g),
                model.geom_friction[3 * g]);
      }
      records_[body_name] = record;
      continue;
    }
    if (geom_count == 0) {
      throw Error("scene " + path_ + ": free body '" + body_name + "' has no geom");
    }
    const Eigen::Isometry3d T_world_inertial = MjPose(data->xipos + 3 * b, data->ximat + 9 * b);
    btCollisionShape* shape = nullptr;
    const Eigen::Isometry3d T_inertial_geom0 =
        T_world_inertial.inverse() *
        MjPose(data->geom_xpos + 3 * first_geom, data->geom_xmat + 9 * first_geom);
    if (geom_count == 1 && IsIdentity(T_inertial_geom0)) {
      shapes_.push_back(MakeBulletShape(model, first_geom, path_));
      shape = shapes_.back().get();
    } else {
      // several geoms or an offset geom: a compound in the centre-of-mass frame
      auto compound = std::make_unique<btCompoundShape>();
      for (int g = first_geom; g < first_geom + geom_count; ++g) {
        shapes_.push_back(MakeBulletShape(model, g, path_));
        const Eigen::Isometry3d T_inertial_geom =
            T_world_inertial.inverse() * MjPose(data->geom_xpos + 3 * g, data->geom_xmat + 9 * g);
        compound->addChildShape(ToBullet(T_inertial_geom), shapes_.back().get());
      }
      shapes_.push_back(std::move(compound));
      shape = shapes_.back().get();
    }
    const mjtNum* inertia = model.body_inertia + 3 * b;
    // Bullet keeps one friction per body; the first geom's sliding friction
    record.body = AddBody(model.body_mass[b], btVector3(inertia[0], inertia[1], inertia[2]), shape,
                          T_world_inertial, model.geom_friction[3 * first_geom]);
    record.T_inertial_body = T_world_inertial.inverse() * T_world_body;
    dynamic_bodies_.push_back(record.body);
    records_[body_name] = record;
  }

  if (has_trees) BuildTrees(model);

  tool_ = Record(scene.tool_body).body;
  if (tool_ == nullptr) throw Error("scene " + path_ + ": the tool body is not free");
  tool_force_N_ = btVector3(scene.tool_force_N.x(), scene.tool_force_N.y(), scene.tool_force_N.z());
}

void BulletEngine::BuildTrees(const mjModel& model) {
  // the links' frames at the reference configuration qpos0, the state from the keyframe
  // 'initial' (MuJoCo's and rigidtouch's start), or qpos0 and rest without one
  std::unique_ptr<mjData, void (*)(mjData*)> reference(mj_makeData(&model), &mj_deleteData);
  mj_forward(&model, reference.get());
  std::unique_ptr<mjData, void (*)(mjData*)> start(mj_makeData(&model), &mj_deleteData);
  const int key = mj_name2id(&model, mjOBJ_KEY, "initial");
  if (key >= 0) mj_resetDataKeyframe(&model, start.get(), key);
  trees_.Build(model, *reference, start->qpos, start->qvel, start->ctrl, *multibody_world_, path_);
}

void BulletEngine::Step() {
  // stepSimulation clears forces after the step, so the push is applied every step
  tool_->applyCentralForce(tool_force_N_);
  trees_.ApplyJointForces();
  // maxSubSteps = 0: exactly one step of length h, no interpolation
  world_->stepSimulation(timestep_s_, 0);
}

int BulletEngine::ContactCount() const {
  int count = 0;
  const int manifolds = dispatcher_->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    count += dispatcher_->getManifoldByIndexInternal(i)->getNumContacts();
  }
  return count;
}

const btCollisionObject* BulletEngine::CollisionObject(std::string_view body) const {
  if (trees_.HasBody(body)) return trees_.Collider(body);
  return Record(body).body;
}

double BulletEngine::BodyPenetration_m(std::string_view body) const {
  const btCollisionObject* target = CollisionObject(body);
  double deepest_m = 0.0;
  if (target == nullptr) return deepest_m;
  const int manifolds = dispatcher_->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(i);
    if (manifold->getBody0() != target && manifold->getBody1() != target) continue;
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      deepest_m =
          std::max(deepest_m, -static_cast<double>(manifold->getContactPoint(k).getDistance()));
    }
  }
  return deepest_m;
}

double BulletEngine::JointPosition(std::string_view joint) const {
  return trees_.JointPosition(joint);
}

int BulletEngine::BodyContactCount(std::string_view body) const {
  const btCollisionObject* target = CollisionObject(body);
  if (target == nullptr) return 0;
  int count = 0;
  const int manifolds = dispatcher_->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(i);
    if (manifold->getBody0() == target || manifold->getBody1() == target) {
      count += manifold->getNumContacts();
    }
  }
  return count;
}

double BulletEngine::DeepestPenetration_m() const {
  double deepest_m = 0.0;
  const int manifolds = dispatcher_->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(i);
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      deepest_m =
          std::max(deepest_m, -static_cast<double>(manifold->getContactPoint(k).getDistance()));
    }
  }
  return deepest_m;
}

const BulletEngine::BodyRecord& BulletEngine::Record(std::string_view body) const {
  const auto it = records_.find(std::string(body));
  if (it == records_.end()) {
    throw Error("scene " + path_ + " has no body named '" + std::string(body) + "'");
  }
  return it->second;
}

const btRigidBody* BulletEngine::RigidBody(std::string_view body) const {
  return Record(body).body;
}

Vec3 BulletEngine::BodyPosition(std::string_view body) const {
  if (trees_.HasBody(body)) return trees_.BodyPose(body).translation();
  const BodyRecord& record = Record(body);
  if (record.body == nullptr) return record.T_world_body.translation();
  return (FromBullet(record.body->getWorldTransform()) * record.T_inertial_body).translation();
}

Quat BulletEngine::BodyOrientation(std::string_view body) const {
  if (trees_.HasBody(body)) return Quat(trees_.BodyPose(body).linear()).normalized();
  const BodyRecord& record = Record(body);
  if (record.body == nullptr) return Quat(record.T_world_body.linear());
  const Eigen::Isometry3d T_world_body =
      FromBullet(record.body->getWorldTransform()) * record.T_inertial_body;
  return Quat(T_world_body.linear()).normalized();
}

void BulletEngine::SetBodyMotion(std::string_view body, const Vec3& position_m,
                                 const Vec3& velocity_mps) {
  const BodyRecord& record = Record(body);
  if (record.body == nullptr) {
    throw Error("body '" + std::string(body) + "' in " + path_ + " is not free");
  }
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  T_world_body.translation() = position_m;
  const btTransform transform = ToBullet(T_world_body * record.T_inertial_body.inverse());
  const btVector3 velocity(velocity_mps.x(), velocity_mps.y(), velocity_mps.z());
  btRigidBody* rigid = record.body;
  rigid->setWorldTransform(transform);
  rigid->setInterpolationWorldTransform(transform);
  rigid->setLinearVelocity(velocity);
  rigid->setInterpolationLinearVelocity(velocity);
  rigid->setAngularVelocity(btVector3(0, 0, 0));
  rigid->setInterpolationAngularVelocity(btVector3(0, 0, 0));
  world_->updateSingleAabb(rigid);
}

void BulletEngine::SaveSnapshot() {
  trees_.Save();
  snapshot_.clear();
  for (const btRigidBody* body : dynamic_bodies_) {
    snapshot_.push_back(SavedMotion{body->getWorldTransform(), body->getLinearVelocity(),
                                    body->getAngularVelocity()});
  }
}

void BulletEngine::RestoreSnapshot() {
  // bodies and joints only: contact manifolds (and their warm-start impulses) stay as the last
  // step left them; Bullet refreshes them from the restored poses at the next step
  trees_.Restore();
  for (std::size_t i = 0; i < dynamic_bodies_.size(); ++i) {
    btRigidBody* body = dynamic_bodies_[i];
    const SavedMotion& saved = snapshot_[i];
    body->setWorldTransform(saved.transform);
    body->setInterpolationWorldTransform(saved.transform);
    body->setLinearVelocity(saved.linear_velocity);
    body->setInterpolationLinearVelocity(saved.linear_velocity);
    body->setAngularVelocity(saved.angular_velocity);
    body->setInterpolationAngularVelocity(saved.angular_velocity);
    body->clearForces();
    world_->updateSingleAabb(body);
  }
}

bool BulletEngine::StateIsFinite() const {
  return trees_.Finite() &&
         std::all_of(dynamic_bodies_.begin(), dynamic_bodies_.end(), [](const btRigidBody* body) {
           return FiniteBt(body->getWorldTransform().getOrigin()) &&
                  FiniteBt(body->getLinearVelocity()) && FiniteBt(body->getAngularVelocity());
         });
}

std::string BulletEngine::Configuration() const {
  const btContactSolverInfo& info = world_->getSolverInfo();
  const auto mode = [&info](int flag) { return (info.m_solverMode & flag) ? "on" : "off"; };
  const auto number = [](double value) {
    std::array<char, 32> text{};
    std::snprintf(text.data(), text.size(), "%g", value);
    return std::string(text.data());
  };
  double box_margin_m = -1;
  for (const auto& shape : shapes_) {
    if (shape->getShapeType() == BOX_SHAPE_PROXYTYPE) box_margin_m = shape->getMargin();
  }
  return "Bullet " + std::to_string(btGetVersion()) +
         (btIsDoublePrecision() ? " double" : " single") + " precision, settings " +
         PeerSettingsName(settings_) + ": " +
         (multibody_world_ != nullptr
              ? "btMultiBodyDynamicsWorld, btMultiBodyConstraintSolver (" +
                    std::to_string(trees_.multibodies().size()) + " btMultiBody, " +
                    std::to_string(trees_.limit_count()) +
                    " joint limits; springs, dampers and actuators as explicit joint torques)"
              : std::string("btSequentialImpulseConstraintSolver")) +
         ", iterations " + std::to_string(info.m_numIterations) + ", erp2 " + number(info.m_erp2) +
         ", split impulse " + (info.m_splitImpulse ? "on" : "off") + ", warm starting " +
         mode(SOLVER_USE_WARMSTARTING) + " (factor " + number(info.m_warmstartingFactor) +
         "), 2 friction directions " + mode(SOLVER_USE_2_FRICTION_DIRECTIONS) +
         ", friction direction caching " + mode(SOLVER_ENABLE_FRICTION_DIRECTION_CACHING) +
         ", randomized order " + mode(SOLVER_RANDMIZE_ORDER) + ", linear slop " +
         number(info.m_linearSlop) + ", residual threshold " +
         number(info.m_leastSquaresResidualThreshold) + ", contact breaking threshold " +
         number(gContactBreakingThreshold) +
         (box_margin_m >= 0 ? ", box margin " + number(box_margin_m) : std::string()) +
         ", btDbvtBroadphase, deactivation disabled, stepSimulation(h, 0) with h " +
         number(timestep_s_) + " s";
}

std::unique_ptr<Engine> MakeBulletEngine() {
  return std::make_unique<BulletEngine>();
}

}  // namespace rigidtouch::bench
