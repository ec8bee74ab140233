// Measures the collision-detection candidates (MuJoCo's narrow phase, FCL, Bullet's collision
// module) on the same scenes and poses: time per full detection pass, heap allocations per pass,
// contacts, manifold quality, and agreement of the deepest penetration on random poses.
// The numbers and the decision they support are in docs/collision-backend.md.
//
// Run: collision_backends [--quick]   (--quick: 10x fewer timed passes, for a smoke test)

#include <btBulletCollisionCommon.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/config.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "rigidtouch/types.h"

// the ABI of the Bullet build we link must match the headers (double precision, the -float64 libs)
static_assert(sizeof(btScalar) == sizeof(double), "build with BT_USE_DOUBLE_PRECISION");

// heap allocations counted by every allocator the three libraries use: C++ operator new (FCL,
// Eigen, the standard library), Bullet's btAlignedAlloc hook and MuJoCo's mju_user_malloc hook
namespace {
std::size_t g_allocations = 0;
}  // namespace

[[gnu::noinline]] void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

[[gnu::noinline]] void* operator new(std::size_t size, std::align_val_t alignment) {
  ++g_allocations;
  const auto align = static_cast<std::size_t>(alignment);
  const std::size_t rounded = (std::max<std::size_t>(size, 1) + align - 1) / align * align;
  if (void* p = std::aligned_alloc(align, rounded)) return p;
  throw std::bad_alloc();
}

// not inlined: gcc 12 -Wmismatched-new-delete pairs an inlined malloc/free with new/delete
[[gnu::noinline]] void operator delete(void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace rigidtouch::bench {
namespace {

/// Counting allocation hook handed to Bullet and MuJoCo. 64-byte aligned: MuJoCo lays out its
/// model buffer assuming the alignment of its own allocator.
void* CountingMalloc(std::size_t size) {
  ++g_allocations;
  return std::aligned_alloc(64, (std::max<std::size_t>(size, 1) + 63) / 64 * 64);
}

/// Free hook paired with CountingMalloc.
void CountingFree(void* p) {
  std::free(p);
}

// ---------------------------------------------------------------------------------------------
// scenes

/// The shape of one collision geometry.
enum class ShapeKind { kPlane, kSphere, kBox };

/// One geometry of a benchmark scene. The plane is z = 0 with normal +z and never moves.
struct GeomSpec {
  ShapeKind kind = ShapeKind::kBox;
  Vec3 half_size_m = Vec3::Zero();  // box half extents, geometry frame
  double radius_m = 0.0;            // sphere radius
};

/// The pose of geometry G in the world frame W.
struct Pose {
  Vec3 p_WG_m = Vec3::Zero();
  Quat q_WG = Quat::Identity();
};

/// A benchmark scene: geometry 0 is the plane, every other geometry is free.
struct Scene {
  std::string name;
  std::vector<GeomSpec> geoms;
  std::vector<Pose> nominal;      // one pose per geometry
  bool flat_faces = false;        // aligned face contacts only: 4 corner points expected per pair
  int expected_pairs = 0;         // geometry pairs in contact at the nominal pose
  double expected_depth_m = 0.0;  // depth of every contact at the nominal pose (0: no closed form)
};

/// One contact point in the convention shared by all backends.
struct Contact {
  int geom1 = 0;  // geom1 < geom2
  int geom2 = 0;
  Vec3 p_W_m = Vec3::Zero();  // the backend's contact point (mid-point or on one surface)
  Vec3 n_W = Vec3::UnitZ();   // unit normal pointing from geom1 to geom2
  double depth_m = 0.0;       // penetration depth, positive when the geometries overlap
};

constexpr double kBoxHalf_m = 0.025;
constexpr double kOverlap_m = 1e-5;
constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Returns the static ground plane geometry (always geometry 0).
GeomSpec Plane() {
  return {ShapeKind::kPlane, Vec3::Zero(), 0.0};
}

/// Returns a box with the given half extents.
GeomSpec BoxSpec(const Vec3& half_size_m) {
  return {ShapeKind::kBox, half_size_m, 0.0};
}

/// Scene (a): a 5 mm radius sphere penetrating the plane by 0.1 mm.
Scene MakeTap() {
  Scene s{"tap", {Plane(), {ShapeKind::kSphere, Vec3::Zero(), 0.005}}, {}, false, 1, 1e-4};
  s.nominal = {Pose{}, Pose{Vec3(0.0, 0.0, 0.005 - 1e-4), Quat::Identity()}};
  return s;
}

/// Scene (b): 10 boxes of half size 25 mm stacked on the plane, each overlapping the one below
/// (the bottom one the plane) by 10 um: z_i = 0.025 + 0.05 i - 1e-5 (i + 1).
Scene MakeStack() {
  Scene s{"stack", {Plane()}, {Pose{}}, true, 10, kOverlap_m};
  for (int i = 0; i < 10; ++i) {
    s.geoms.push_back(BoxSpec(Vec3::Constant(kBoxHalf_m)));
    s.nominal.push_back(
        {Vec3(0.0, 0.0, 0.025 + 0.05 * i - kOverlap_m * (i + 1)), Quat::Identity()});
  }
  return s;
}

/// Scene (c): 100 boxes on a 5x5x4 grid, columns overlapping vertically by 10 um, 1 mm gaps
/// sideways; with `tilted`, each box is tilted about a random horizontal axis by less than 0.5 deg.
Scene MakeBackendPile(bool tilted, std::uint32_t seed) {
  Scene s{tilted ? "pile-tilted" : "pile", {Plane()}, {Pose{}}, !tilted, 100,
          tilted ? 0.0 : kOverlap_m};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int z = 0; z < 4; ++z) {
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 5; ++x) {
        Pose pose{Vec3(-0.1 + 0.051 * x, -0.1 + 0.051 * y, 0.025 + 0.05 * z - kOverlap_m * (z + 1)),
                  Quat::Identity()};
        if (tilted) {
          const double heading_rad = 2.0 * std::numbers::pi * unit(rng);
          const double tilt_rad = 0.5 * kDegToRad * unit(rng);
          pose.q_WG = Quat(
              Eigen::AngleAxisd(tilt_rad, Vec3(std::cos(heading_rad), std::sin(heading_rad), 0.0)));
        }
        s.geoms.push_back(BoxSpec(Vec3::Constant(kBoxHalf_m)));
        s.nominal.push_back(pose);
      }
    }
  }
  return s;
}

/// Returns `count` pose sets, each the nominal poses moved by at most 1 um per axis and rotated by
/// at most 1e-5 rad: small against the 10 um overlaps, so the contact set stays the same while
/// every pass sees new numbers.
std::vector<std::vector<Pose>> PerturbedPoseSets(const Scene& scene, int count,
                                                 std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter_m(-1e-6, 1e-6);
  std::uniform_real_distribution<double> angle_rad(0.0, 1e-5);
  std::normal_distribution<double> gauss;
  std::vector<std::vector<Pose>> sets(count, scene.nominal);
  for (auto& set : sets) {
    for (std::size_t g = 1; g < set.size(); ++g) {
      set[g].p_WG_m += Vec3(jitter_m(rng), jitter_m(rng), jitter_m(rng));
      const Vec3 axis = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      set[g].q_WG = (set[g].q_WG * Quat(Eigen::AngleAxisd(angle_rad(rng), axis))).normalized();
    }
  }
  return sets;
}

/// Returns a rotation drawn uniformly from SO(3).
Quat RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  return Quat(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized();
}

/// Returns the 8 vertices of a box in the world frame.
std::array<Vec3, 8> BoxVertices_W(const Vec3& half_size_m, const Pose& pose) {
  std::array<Vec3, 8> v;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p_GV((i & 1 ? 1 : -1) * half_size_m.x(), (i & 2 ? 1 : -1) * half_size_m.y(),
                    (i & 4 ? 1 : -1) * half_size_m.z());
    v[i] = pose.p_WG_m + pose.q_WG * p_GV;
  }
  return v;
}

// ---------------------------------------------------------------------------------------------
// backends

/// Appends a contact in the shared convention; drops it when `out` is full (4096 here, far above
/// any scene's count) or when it does not penetrate (Bullet's manifolds also hold points up to its
/// breaking threshold apart).
int Push(std::span<Contact> out, int n, int geom1, int geom2, const Vec3& p_W_m, Vec3 n12_W,
         double depth_m) {
  if (depth_m < 0.0 || n >= static_cast<int>(out.size())) return n;
  if (geom1 > geom2) {
    std::swap(geom1, geom2);
    n12_W = -n12_W;
  }
  out[n] = {geom1, geom2, p_W_m, n12_W, depth_m};
  return n + 1;
}

/// A collision-detection backend built for one scene.
class Backend {
 public:
  virtual ~Backend() = default;

  /// Short name used in the result tables.
  virtual std::string name() const = 0;

  /// Writes `poses` (one per geometry) into the backend, runs its broad and narrow phases over all
  /// pairs and copies the penetrating contacts into `out`. Returns the number of contacts written.
  virtual int Detect(std::span<const Pose> poses, std::span<Contact> out) = 0;

  /// Drops the state a backend keeps between passes (Bullet's persistent manifolds).
  virtual void Forget() {}

  /// Pairs the broadphase handed to the narrow phase in the last pass, or -1 if not known.
  virtual int NarrowPhasePairs() const { return -1; }
};

/// Writes the scene as MJCF: the plane in the world body, every other geometry in its own free
/// body. MuJoCo 2.2 sizes its contact buffer from nconmax (100 unless set) and drops contacts
/// beyond it with a warning, so the pile needs an explicit, larger value.
std::string ToMjcf(const Scene& scene) {
  std::string xml =
      "<mujoco model=\"" + scene.name + "\">\n  <size nconmax=\"4096\"/>\n  <worldbody>\n";
  char line[512];
  for (std::size_t g = 0; g < scene.geoms.size(); ++g) {
    const GeomSpec& spec = scene.geoms[g];
    if (spec.kind == ShapeKind::kPlane) {
      xml += "    <geom type=\"plane\" size=\"1 1 0.01\"/>\n";
      continue;
    }
    const Vec3& p = scene.nominal[g].p_WG_m;
    std::snprintf(line, sizeof line, "    <body pos=\"%.17g %.17g %.17g\"><freejoint/>", p.x(),
                  p.y(), p.z());
    xml += line;
    if (spec.kind == ShapeKind::kBox) {
      std::snprintf(line, sizeof line, "<geom type=\"box\" size=\"%.17g %.17g %.17g\"/>",
                    spec.half_size_m.x(), spec.half_size_m.y(), spec.half_size_m.z());
    } else {
      std::snprintf(line, sizeof line, "<geom type=\"sphere\" size=\"%.17g\"/>", spec.radius_m);
    }
    xml += line;
    xml += "</body>\n";
  }
  xml += "  </worldbody>\n</mujoco>\n";
  return xml;
}

/// MuJoCo 2.2: write qpos, mj_kinematics, mj_collision on a compiled model (margin 0), as the
/// engine does today. MuJoCo keeps no state between passes.
class MujocoBackend final : public Backend {
 public:
  /// Compiles the scene from an in-memory MJCF file. Throws Error if MuJoCo rejects it.
  explicit MujocoBackend(const Scene& scene) {
    const std::string xml = ToMjcf(scene);
    auto vfs = std::make_unique<mjVFS>();
    mj_defaultVFS(vfs.get());
    if (mj_makeEmptyFileVFS(vfs.get(), "scene.xml", static_cast<int>(xml.size())) != 0) {
      throw Error("MuJoCo VFS refused the generated MJCF for scene '" + scene.name + "'");
    }
    std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "scene.xml")], xml.data(), xml.size());
    char error[1000] = "";
    model_ = mj_loadXML("scene.xml", vfs.get(), error, sizeof error);
    mj_deleteVFS(vfs.get());
    if (model_ == nullptr) {
      throw Error("MuJoCo could not compile scene '" + scene.name + "': " + error);
    }
    if (model_->ngeom != static_cast<int>(scene.geoms.size())) {
      throw Error("MuJoCo geometry count differs from scene '" + scene.name + "'");
    }
    data_ = mj_makeData(model_);
    qpos_adr_.assign(scene.geoms.size(), -1);
    for (int g = 1; g < model_->ngeom; ++g) {
      const int body = model_->geom_bodyid[g];
      qpos_adr_[g] = model_->jnt_qposadr[model_->body_jntadr[body]];
    }
  }

  ~MujocoBackend() override {
    mj_deleteData(data_);
    mj_deleteModel(model_);
  }

  MujocoBackend(const MujocoBackend&) = delete;
  MujocoBackend& operator=(const MujocoBackend&) = delete;

  std::string name() const override { return "MuJoCo " + std::string(mj_versionString()); }

  int Detect(std::span<const Pose> poses, std::span<Contact> out) override {
    for (int g = 1; g < model_->ngeom; ++g) {
      mjtNum* qpos = data_->qpos + qpos_adr_[g];
      const Pose& pose = poses[g];
      qpos[0] = pose.p_WG_m.x();
      qpos[1] = pose.p_WG_m.y();
      qpos[2] = pose.p_WG_m.z();
      qpos[3] = pose.q_WG.w();
      qpos[4] = pose.q_WG.x();
      qpos[5] = pose.q_WG.y();
      qpos[6] = pose.q_WG.z();
    }
    mj_kinematics(model_, data_);
    mj_collision(model_, data_);
    int n = 0;
    for (int i = 0; i < data_->ncon; ++i) {
      const mjContact& c = data_->contact[i];
      // frame[0..2] is the normal from geom1 to geom2; dist < 0 on penetration
      n = Push(out, n, c.geom1, c.geom2, Vec3(c.pos[0], c.pos[1], c.pos[2]),
               Vec3(c.frame[0], c.frame[1], c.frame[2]), -c.dist);
    }
    return n;
  }

 private:
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> qpos_adr_;  // per geometry, the free joint's qpos address (-1 for the plane)
};

/// FCL 0.7: one CollisionObject per geometry, DynamicAABBTree broadphase over the free objects,
/// fcl::collide per broadphase pair with enable_contact and up to 8 contacts per pair. The ground
/// stays out of the tree (an infinite Halfspace AABB crashes the tree build, FCL issue #455 /
/// Drake issue #19263) and is queried against the tree each pass. With `ground_box` the ground is a
/// 2 m x 2 m x 0.2 m box whose top face is z = 0 instead of a Halfspace, so box-ground pairs go
/// through FCL's box-box clipping.
class FclBackend final : public Backend {
 public:
  /// Builds the objects and the broadphase tree.
  FclBackend(const Scene& scene, bool ground_box) : ground_box_(ground_box) {
    request_.num_max_contacts = 8;  // more than the 4 the box-box clipping can return
    request_.enable_contact = true;
    ids_.resize(scene.geoms.size());
    std::vector<fcl::CollisionObjectd*> free_objects;
    for (std::size_t g = 0; g < scene.geoms.size(); ++g) {
      const GeomSpec& spec = scene.geoms[g];
      std::shared_ptr<fcl::CollisionGeometryd> geometry;
      Pose pose = scene.nominal[g];
      switch (spec.kind) {
        case ShapeKind::kPlane:
          if (ground_box) {
            geometry = std::make_shared<fcl::Boxd>(2.0, 2.0, 2.0 * kGroundBoxHalfHeight_m);
            pose.p_WG_m = Vec3(0.0, 0.0, -kGroundBoxHalfHeight_m);
          } else {
            geometry = std::make_shared<fcl::Halfspaced>(Vec3::UnitZ(), 0.0);
          }
          break;
        case ShapeKind::kSphere:
          geometry = std::make_shared<fcl::Sphered>(spec.radius_m);
          break;
        case ShapeKind::kBox:
          // fcl::Box takes full side lengths
          geometry = std::make_shared<fcl::Boxd>(2.0 * spec.half_size_m);
          break;
      }
      ids_[g] = static_cast<int>(g);
      auto object = std::make_unique<fcl::CollisionObjectd>(geometry);
      object->setTransform(pose.q_WG, pose.p_WG_m);
      object->computeAABB();
      object->setUserData(&ids_[g]);
      if (g > 0) free_objects.push_back(object.get());
      objects_.push_back(std::move(object));
    }
    manager_.registerObjects(free_objects);
    manager_.setup();
  }

  std::string name() const override {
    return std::string("FCL " FCL_VERSION) + (ground_box_ ? " ground-box" : "");
  }

  int Detect(std::span<const Pose> poses, std::span<Contact> out) override {
    for (std::size_t g = 1; g < objects_.size(); ++g) {
      objects_[g]->setTransform(poses[g].q_WG, poses[g].p_WG_m);
      objects_[g]->computeAABB();
    }
    manager_.update();
    PassContext context{this, out, 0};
    narrow_phase_pairs_ = 0;
    manager_.collide(&context, &FclBackend::OnPair);                     // free-free pairs
    manager_.collide(objects_[0].get(), &context, &FclBackend::OnPair);  // ground-free pairs
    return context.n;
  }

  int NarrowPhasePairs() const override { return narrow_phase_pairs_; }

 private:
  static constexpr double kGroundBoxHalfHeight_m = 0.1;

  struct PassContext {
    FclBackend* self;
    std::span<Contact> out;
    int n;
  };

  /// Broadphase callback: narrow phase for one pair, lower geometry index first.
  static bool OnPair(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
    auto* context = static_cast<PassContext*>(data);
    FclBackend& self = *context->self;
    int g1 = *static_cast<const int*>(o1->getUserData());
    int g2 = *static_cast<const int*>(o2->getUserData());
    if (g1 > g2) {
      std::swap(o1, o2);
      std::swap(g1, g2);
    }
    ++self.narrow_phase_pairs_;
    self.result_.clear();
    fcl::collide(o1, o2, self.request_, self.result_);
    for (std::size_t i = 0; i < self.result_.numContacts(); ++i) {
      const fcl::Contactd& c = self.result_.getContact(i);
      // fcl 0.7: normal points from o1 to o2
      context->n = Push(context->out, context->n, g1, g2, c.pos, c.normal, c.penetration_depth);
    }
    return false;  // keep going: we want every pair
  }

  bool ground_box_;
  int narrow_phase_pairs_ = 0;
  std::vector<int> ids_;  // user data: the geometry index of each object
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects_;
  fcl::DynamicAABBTreeCollisionManagerd manager_;
  fcl::CollisionRequestd request_;
  fcl::CollisionResultd result_;
};

/// How the Bullet backend is set up.
struct BulletOptions {
  bool plane_multipoint = false;  // setPlaneConvexMultipointIterations(): several box-plane
                                  // points per frame instead of one
  bool sweep_and_prune = false;   // btAxisSweep3 instead of btDbvtBroadphase
  bool ground_box = false;        // the ground as a 2 m x 2 m x 0.2 m static box (top at z = 0)
                                  // instead of btStaticPlaneShape: box-ground goes through the
                                  // box-box clipping
  double breaking_threshold_m = 0.02;  // gContactBreakingThreshold (Bullet's default 0.02 m)
};

/// Bullet 3.24 collision module (double precision): btCollisionWorld, btSphereShape / btBoxShape
/// and a static plane (or ground box), performDiscreteCollisionDetection, contacts read from the
/// persistent manifolds.
class BulletBackend final : public Backend {
 public:
  /// Builds the world.
  BulletBackend(const Scene& scene, const BulletOptions& options) : options_(options) {
    // a global in Bullet: it widens every AABB and sets each new manifold's breaking distance
    gContactBreakingThreshold = options_.breaking_threshold_m;
    config_ = std::make_unique<btDefaultCollisionConfiguration>();
    if (options_.plane_multipoint) config_->setPlaneConvexMultipointIterations();
    dispatcher_ = std::make_unique<btCollisionDispatcher>(config_.get());
    if (options_.sweep_and_prune) {
      broadphase_ = std::make_unique<btAxisSweep3>(btVector3(-2, -2, -2), btVector3(2, 2, 2));
    } else {
      broadphase_ = std::make_unique<btDbvtBroadphase>();
    }
    world_ =
        std::make_unique<btCollisionWorld>(dispatcher_.get(), broadphase_.get(), config_.get());
    for (std::size_t g = 0; g < scene.geoms.size(); ++g) {
      const GeomSpec& spec = scene.geoms[g];
      Pose pose = scene.nominal[g];
      switch (spec.kind) {
        case ShapeKind::kPlane:
          if (options_.ground_box) {
            shapes_.push_back(std::make_unique<btBoxShape>(btVector3(1.0, 1.0, 0.1)));
            pose.p_WG_m = Vec3(0.0, 0.0, -0.1);
          } else {
            shapes_.push_back(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0.0));
          }
          break;
        case ShapeKind::kSphere:
          shapes_.push_back(std::make_unique<btSphereShape>(spec.radius_m));
          break;
        case ShapeKind::kBox:
          shapes_.push_back(std::make_unique<btBoxShape>(
              btVector3(spec.half_size_m.x(), spec.half_size_m.y(), spec.half_size_m.z())));
          break;
      }
      auto object = std::make_unique<btCollisionObject>();
      object->setCollisionShape(shapes_.back().get());
      object->setUserIndex(static_cast<int>(g));
      object->setWorldTransform(ToBullet(pose));
      if (spec.kind == ShapeKind::kPlane) {
        object->setCollisionFlags(object->getCollisionFlags() |
                                  btCollisionObject::CF_STATIC_OBJECT);
      }
      world_->addCollisionObject(object.get());
      objects_.push_back(std::move(object));
    }
  }

  ~BulletBackend() override {
    for (auto& object : objects_) world_->removeCollisionObject(object.get());
  }

  BulletBackend(const BulletBackend&) = delete;
  BulletBackend& operator=(const BulletBackend&) = delete;

  std::string name() const override {
    std::string name = "Bullet 3." + std::to_string(btGetVersion() % 100);
    if (options_.plane_multipoint) name += " multipoint";
    if (options_.sweep_and_prune) name += " SAP";
    if (options_.ground_box) name += " ground-box";
    if (options_.breaking_threshold_m != 0.02) {
      char text[48];
      std::snprintf(text, sizeof text, " threshold %g mm", options_.breaking_threshold_m * 1e3);
      name += text;
    }
    return name;
  }

  int Detect(std::span<const Pose> poses, std::span<Contact> out) override {
    gContactBreakingThreshold = options_.breaking_threshold_m;
    for (std::size_t g = 1; g < objects_.size(); ++g) {
      objects_[g]->setWorldTransform(ToBullet(poses[g]));
    }
    world_->performDiscreteCollisionDetection();
    int n = 0;
    for (int m = 0; m < dispatcher_->getNumManifolds(); ++m) {
      const btPersistentManifold* manifold = dispatcher_->getManifoldByIndexInternal(m);
      const int g1 = manifold->getBody0()->getUserIndex();
      const int g2 = manifold->getBody1()->getUserIndex();
      for (int i = 0; i < manifold->getNumContacts(); ++i) {
        const btManifoldPoint& point = manifold->getContactPoint(i);
        // m_normalWorldOnB points from body1 towards body0; getDistance() < 0 on penetration
        const btVector3 mid = 0.5 * (point.getPositionWorldOnA() + point.getPositionWorldOnB());
        const btVector3& n_10 = point.m_normalWorldOnB;
        n = Push(out, n, g1, g2, Vec3(mid.x(), mid.y(), mid.z()),
                 -Vec3(n_10.x(), n_10.y(), n_10.z()), -point.getDistance());
      }
    }
    return n;
  }

  int NarrowPhasePairs() const override {
    // every overlapping pair is dispatched to its collision algorithm each pass
    return broadphase_->getOverlappingPairCache()->getNumOverlappingPairs();
  }

  void Forget() override {
    // deletes each pair's algorithm and manifold; the next pass builds fresh ones
    for (auto& object : objects_) {
      broadphase_->getOverlappingPairCache()->cleanProxyFromPairs(object->getBroadphaseHandle(),
                                                                  dispatcher_.get());
    }
  }

 private:
  static btTransform ToBullet(const Pose& pose) {
    return btTransform(btQuaternion(pose.q_WG.x(), pose.q_WG.y(), pose.q_WG.z(), pose.q_WG.w()),
                       btVector3(pose.p_WG_m.x(), pose.p_WG_m.y(), pose.p_WG_m.z()));
  }

  BulletOptions options_;
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btCollisionWorld> world_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btCollisionObject>> objects_;
};

/// The backends compared in the timing table, in table order.
enum class BackendKind {
  kMujoco,
  kFcl,
  kFclGroundBox,
  kBullet,            // the configuration named in the task: btDbvtBroadphase, plane shape
  kBulletMultipoint,  // same with the multipoint plane-convex algorithm
  kBulletTuned,       // btAxisSweep3, ground box, 0.2 mm breaking threshold
};

/// Every backend kind, in table order.
constexpr std::array<BackendKind, 6> kAllBackends = {
    BackendKind::kMujoco,           BackendKind::kFcl,
    BackendKind::kFclGroundBox,     BackendKind::kBullet,
    BackendKind::kBulletMultipoint, BackendKind::kBulletTuned};

/// Returns true for the Bullet backends (persistent manifolds: steady and fresh rows).
bool IsBullet(BackendKind kind) {
  return kind == BackendKind::kBullet || kind == BackendKind::kBulletMultipoint ||
         kind == BackendKind::kBulletTuned;
}

/// Builds one backend for a scene.
std::unique_ptr<Backend> MakeBackend(BackendKind kind, const Scene& scene) {
  switch (kind) {
    case BackendKind::kMujoco:
      return std::make_unique<MujocoBackend>(scene);
    case BackendKind::kFcl:
      return std::make_unique<FclBackend>(scene, false);
    case BackendKind::kFclGroundBox:
      return std::make_unique<FclBackend>(scene, true);
    case BackendKind::kBullet:
      return std::make_unique<BulletBackend>(scene, BulletOptions{});
    case BackendKind::kBulletMultipoint:
      return std::make_unique<BulletBackend>(scene, BulletOptions{.plane_multipoint = true});
    case BackendKind::kBulletTuned:
      return std::make_unique<BulletBackend>(
          scene,
          BulletOptions{.sweep_and_prune = true, .ground_box = true, .breaking_threshold_m = 2e-4});
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// timing and manifold quality

/// Timing of many detection passes.
struct Timing {
  double min_ns = 0.0;  // the least disturbed pass: closest to the cost on an idle machine
  double median_ns = 0.0;
  double p99_ns = 0.0;
  double allocations_per_pass = 0.0;
  int min_contacts = 0;  // over the timed passes: a steady count means stable manifolds
  int max_contacts = 0;
};

/// Times `iterations` passes (write poses + detect + copy contacts) after `warmup` untimed ones,
/// cycling through the pose sets. With `forget_each`, state is dropped before every pass (outside
/// the timer), which measures a fresh frame.
Timing TimePasses(Backend& backend, const std::vector<std::vector<Pose>>& pose_sets, int warmup,
                  int iterations, bool forget_each, std::span<Contact> buffer) {
  using Clock = std::chrono::steady_clock;
  for (int i = 0; i < warmup; ++i) backend.Detect(pose_sets[i % pose_sets.size()], buffer);
  std::vector<double> times_ns(iterations);
  int min_contacts = std::numeric_limits<int>::max();
  int max_contacts = 0;
  std::size_t allocations = 0;
  for (int i = 0; i < iterations; ++i) {
    if (forget_each) backend.Forget();
    const std::size_t allocations_before = g_allocations;
    const auto start = Clock::now();
    const int n = backend.Detect(pose_sets[i % pose_sets.size()], buffer);
    const auto stop = Clock::now();
    allocations += g_allocations - allocations_before;
    times_ns[i] = std::chrono::duration<double, std::nano>(stop - start).count();
    min_contacts = std::min(min_contacts, n);
    max_contacts = std::max(max_contacts, n);
  }
  std::sort(times_ns.begin(), times_ns.end());
  Timing t;
  t.min_ns = times_ns.front();
  t.median_ns = times_ns[iterations / 2];
  t.p99_ns = times_ns[static_cast<std::size_t>(std::ceil(0.99 * iterations)) - 1];
  t.allocations_per_pass = static_cast<double>(allocations) / iterations;
  t.min_contacts = min_contacts;
  t.max_contacts = max_contacts;
  return t;
}

/// Points per pair for one kind of pair (box-plane, box-box, sphere-plane).
struct PairStats {
  int pairs = 0;
  int min_points = std::numeric_limits<int>::max();
  int max_points = 0;
  int all_corners = 0;  // flat scenes: pairs with a point at each of the 4 face corners
};

/// Manifold quality of one detection pass.
struct Quality {
  int contacts = 0;
  int pairs = 0;
  double max_depth_error_m = 0.0;  // against Scene::expected_depth_m
  PairStats sphere_plane, box_plane, box_box;
};

/// Distance, within the contact plane, under which a contact point counts as at a corner.
constexpr double kCornerTolerance_m = 1e-4;

/// Groups the contacts by pair, counts points per pair and, in flat scenes, checks that the 4
/// corners of the contact face each carry a point (distance measured within the contact plane).
Quality Analyse(const Scene& scene, std::span<const Contact> contacts) {
  std::map<std::pair<int, int>, std::vector<const Contact*>> by_pair;
  for (const Contact& c : contacts) by_pair[{c.geom1, c.geom2}].push_back(&c);
  Quality q;
  q.contacts = static_cast<int>(contacts.size());
  q.pairs = static_cast<int>(by_pair.size());
  for (const Contact& c : contacts) {
    q.max_depth_error_m =
        std::max(q.max_depth_error_m, std::abs(c.depth_m - scene.expected_depth_m));
  }
  for (const auto& [pair, points] : by_pair) {
    const auto [g1, g2] = pair;
    const bool plane = scene.geoms[g1].kind == ShapeKind::kPlane;
    PairStats& stats = scene.geoms[g2].kind == ShapeKind::kSphere ? q.sphere_plane
                       : plane                                    ? q.box_plane
                                                                  : q.box_box;
    const int count = static_cast<int>(points.size());
    ++stats.pairs;
    stats.min_points = std::min(stats.min_points, count);
    stats.max_points = std::max(stats.max_points, count);
    if (!scene.flat_faces) continue;
    // the face in contact: the bottom face of the upper box (aligned, same-size boxes)
    const int upper =
        plane || scene.nominal[g2].p_WG_m.z() > scene.nominal[g1].p_WG_m.z() ? g2 : g1;
    std::array<Vec3, 8> vertices =
        BoxVertices_W(scene.geoms[upper].half_size_m, scene.nominal[upper]);
    std::sort(vertices.begin(), vertices.end(),
              [](const Vec3& a, const Vec3& b) { return a.z() < b.z(); });
    int covered = 0;
    for (int k = 0; k < 4; ++k) {
      for (const Contact* c : points) {
        const Vec3 d = c->p_W_m - vertices[k];
        if ((d - d.dot(c->n_W) * c->n_W).norm() < kCornerTolerance_m) {
          ++covered;
          break;
        }
      }
    }
    if (covered == 4) ++stats.all_corners;
  }
  return q;
}

/// Formats points per pair as "min-max" (or "-" when there is no such pair).
std::string PointsText(const PairStats& s) {
  if (s.pairs == 0) return "-";
  if (s.min_points == s.max_points) return std::to_string(s.min_points);
  return std::to_string(s.min_points) + "-" + std::to_string(s.max_points);
}

/// Formats corner coverage as "pairs with all 4 corners / pairs".
std::string CornersText(const Scene& scene, const Quality& q) {
  if (!scene.flat_faces) return "n/a";
  return std::to_string(q.box_plane.all_corners + q.box_box.all_corners) + "/" +
         std::to_string(q.box_plane.pairs + q.box_box.pairs);
}

/// Prints one row of the timing table.
void PrintRow(const Scene& scene, const Backend& backend, const std::string& label, const Timing& t,
              const Quality& q) {
  const std::string points =
      scene.name == "tap" ? PointsText(q.sphere_plane) + " (sphere)" : PointsText(q.box_plane);
  char depth_error[32] = "n/a";
  if (scene.expected_depth_m > 0.0) {
    std::snprintf(depth_error, sizeof depth_error, "%.2f", q.max_depth_error_m * 1e6);
  }
  const int narrow = backend.NarrowPhasePairs();
  const std::string narrow_text = narrow < 0 ? "n/a" : std::to_string(narrow);
  std::printf(
      "| %s | %s | %.0f | %.0f | %.0f | %.1f | %d (%d-%d) | %d/%d | %s | %s | %s | %s | %s |\n",
      scene.name.c_str(), (backend.name() + label).c_str(), t.min_ns, t.median_ns, t.p99_ns,
      t.allocations_per_pass, q.contacts, t.min_contacts, t.max_contacts, q.pairs,
      scene.expected_pairs, points.c_str(), PointsText(q.box_box).c_str(),
      CornersText(scene, q).c_str(), depth_error, narrow_text.c_str());
}

/// Returns the 1, 5 and 15 minute load averages of the machine as text.
std::string LoadAverage() {
  std::string text = "unknown";
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    char line[128] = "";
    if (std::fgets(line, sizeof line, f) != nullptr) {
      text = line;
      text = text.substr(0, text.find(' ', text.find(' ', text.find(' ') + 1) + 1));
    }
    std::fclose(f);
  }
  return text;
}

/// Times every backend on every scene and prints the table.
void RunTimings(bool quick) {
  const std::vector<Scene> scenes = {MakeTap(), MakeStack(), MakeBackendPile(false, 7u),
                                     MakeBackendPile(true, 7u)};
  std::vector<Contact> buffer(4096);
  std::printf(
      "| scene | backend | min ns | median ns | p99 ns | allocs/pass | points (range over passes) "
      "| pairs "
      "| pts/box-plane | pts/box-box | pairs with 4 corners | max depth error um "
      "| narrow-phase pairs |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Scene& scene : scenes) {
    const int iterations = (scene.geoms.size() > 20 ? 3000 : 20000) / (quick ? 10 : 1);
    const int warmup = 100;
    const auto pose_sets = PerturbedPoseSets(scene, 64, 11u);
    for (BackendKind kind : kAllBackends) {
      auto backend = MakeBackend(kind, scene);
      const Timing t = TimePasses(*backend, pose_sets, warmup, iterations, false, buffer);
      // quality at the nominal pose; Bullet's manifolds now hold the points of earlier passes
      const int n = backend->Detect(scene.nominal, buffer);
      const Quality q = Analyse(scene, std::span<const Contact>(buffer.data(), n));
      const bool bullet = IsBullet(kind);
      PrintRow(scene, *backend, bullet ? " steady" : "", t, q);
      if (!bullet) continue;
      // a fresh frame: manifolds dropped before the pass (outside the timer)
      const Timing fresh = TimePasses(*backend, pose_sets, 0, iterations / 4, true, buffer);
      backend->Forget();
      const int n_fresh = backend->Detect(scene.nominal, buffer);
      const Quality q_fresh = Analyse(scene, std::span<const Contact>(buffer.data(), n_fresh));
      PrintRow(scene, *backend, " fresh", fresh, q_fresh);
    }
  }
}

/// Which Bullet setting buys what on the pile: broadphase x breaking threshold x ground shape,
/// steady-state timing plus the box-ground points of a fresh frame.
void RunBulletAblation(bool quick) {
  const Scene scene = MakeBackendPile(false, 7u);
  const auto pose_sets = PerturbedPoseSets(scene, 64, 11u);
  const int iterations = 3000 / (quick ? 10 : 1);
  std::vector<Contact> buffer(4096);
  std::printf(
      "\nBullet settings on the pile (steady state; fresh-frame points per box-ground pair)\n"
      "| broadphase | breaking threshold mm | ground | min ns | median ns | p99 ns | allocs/pass "
      "| narrow-phase pairs | pts/box-ground fresh |\n|---|---|---|---|---|---|---|---|---|\n");
  for (bool sweep_and_prune : {false, true}) {
    for (double threshold_m : {0.02, 2e-4}) {
      for (bool ground_box : {false, true}) {
        BulletBackend backend(scene, BulletOptions{.sweep_and_prune = sweep_and_prune,
                                                   .ground_box = ground_box,
                                                   .breaking_threshold_m = threshold_m});
        const Timing t = TimePasses(backend, pose_sets, 100, iterations, false, buffer);
        const int pairs = backend.NarrowPhasePairs();
        backend.Forget();
        const int n = backend.Detect(scene.nominal, buffer);
        const Quality q = Analyse(scene, std::span<const Contact>(buffer.data(), n));
        std::printf("| %s | %g | %s | %.0f | %.0f | %.0f | %.1f | %d | %s |\n",
                    sweep_and_prune ? "btAxisSweep3" : "btDbvtBroadphase", threshold_m * 1e3,
                    ground_box ? "box" : "plane", t.min_ns, t.median_ns, t.p99_ns,
                    t.allocations_per_pass, pairs, PointsText(q.box_plane).c_str());
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// agreement on random poses

/// The deepest contact between two geometries.
struct Deepest {
  bool found = false;
  double depth_m = 0.0;
  Vec3 n_W = Vec3::Zero();
};

/// Returns the deepest contact of pair (g1, g2), g1 < g2.
Deepest DeepestOf(std::span<const Contact> contacts, int g1, int g2) {
  Deepest d;
  for (const Contact& c : contacts) {
    if (c.geom1 != g1 || c.geom2 != g2) continue;
    if (!d.found || c.depth_m > d.depth_m) d = {true, c.depth_m, c.n_W};
  }
  return d;
}

/// Separating-axis reference for two boxes: the penetration depth is the smallest overlap over
/// the 15 candidate axes (exact for boxes), the normal that axis oriented from A to B.
struct SatResult {
  double depth_m = 0.0;
  Vec3 n_W = Vec3::Zero();
  bool edge_edge = false;  // the best axis is an edge cross product, not a face normal
};

/// Computes the separating-axis penetration depth of boxes A and B (negative when separated).
SatResult BoxBoxSat(const Vec3& half_a_m, const Pose& a, const Vec3& half_b_m, const Pose& b) {
  const Mat3 R_WA = a.q_WG.toRotationMatrix();
  const Mat3 R_WB = b.q_WG.toRotationMatrix();
  const Vec3 d_W = b.p_WG_m - a.p_WG_m;
  std::array<Vec3, 15> axes;
  int count = 0;
  for (int i = 0; i < 3; ++i) axes[count++] = R_WA.col(i);
  for (int i = 0; i < 3; ++i) axes[count++] = R_WB.col(i);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 c = R_WA.col(i).cross(R_WB.col(j));
      // near-parallel edges: the face axes already cover that direction
      if (c.norm() > 1e-6) axes[count++] = c.normalized();
    }
  }
  SatResult result;
  result.depth_m = std::numeric_limits<double>::infinity();
  for (int k = 0; k < count; ++k) {
    double r_m = 0.0;
    for (int i = 0; i < 3; ++i) {
      r_m += half_a_m[i] * std::abs(R_WA.col(i).dot(axes[k])) +
             half_b_m[i] * std::abs(R_WB.col(i).dot(axes[k]));
    }
    const double overlap_m = r_m - std::abs(d_W.dot(axes[k]));
    if (overlap_m < result.depth_m) {
      result.depth_m = overlap_m;
      result.n_W = d_W.dot(axes[k]) >= 0.0 ? axes[k] : Vec3(-axes[k]);
      result.edge_edge = k >= 6;
    }
  }
  return result;
}

/// Angle between two unit vectors in degrees.
double AngleDeg(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDegToRad;
}

/// Differences of the deepest contact for one class of poses, per backend and per backend pair.
struct Agreement {
  static constexpr int kBackends = 5;  // MuJoCo, FCL, FCL ground-box, Bullet, Bullet tuned
  int samples = 0;
  std::array<int, kBackends> misses{};
  std::array<double, kBackends> max_depth_error_m{};         // against the reference
  std::array<double, kBackends> max_relative_depth_error{};  // where the depth is >= 0.1 mm
  std::array<double, kBackends> max_angle_deg{};             // against the reference
  std::array<int, kBackends> normals_off{};    // samples with a normal more than 1 deg off
  std::array<int, kBackends> depths_off{};     // samples with a depth off by > 1 % + 1 um
  std::array<double, 3> max_pair_depth_m{};    // MuJoCo-FCL, MuJoCo-Bullet, FCL-Bullet
  std::array<double, 3> max_pair_angle_deg{};  // same pairs
};

/// Records one sample: the reference and the deepest contact of each backend.
void Record(Agreement& a, double ref_depth_m, const Vec3& ref_n_W,
            const std::array<Deepest, Agreement::kBackends>& got) {
  ++a.samples;
  for (int k = 0; k < Agreement::kBackends; ++k) {
    if (!got[k].found) {
      ++a.misses[k];
      continue;
    }
    const double error_m = std::abs(got[k].depth_m - ref_depth_m);
    a.max_depth_error_m[k] = std::max(a.max_depth_error_m[k], error_m);
    if (error_m > 0.01 * ref_depth_m + 1e-6) ++a.depths_off[k];
    if (ref_depth_m >= 1e-4) {
      a.max_relative_depth_error[k] =
          std::max(a.max_relative_depth_error[k], error_m / ref_depth_m);
    }
    const double angle_deg = AngleDeg(got[k].n_W, ref_n_W);
    a.max_angle_deg[k] = std::max(a.max_angle_deg[k], angle_deg);
    if (angle_deg > 1.0) ++a.normals_off[k];
  }
  constexpr std::array<std::pair<int, int>, 3> kPairs = {{{0, 1}, {0, 3}, {1, 3}}};
  for (int p = 0; p < 3; ++p) {
    const Deepest& x = got[kPairs[p].first];
    const Deepest& y = got[kPairs[p].second];
    if (!x.found || !y.found) continue;
    a.max_pair_depth_m[p] = std::max(a.max_pair_depth_m[p], std::abs(x.depth_m - y.depth_m));
    a.max_pair_angle_deg[p] = std::max(a.max_pair_angle_deg[p], AngleDeg(x.n_W, y.n_W));
  }
}

/// Runs the deepest contact of every agreement backend (manifolds dropped first) on one pose set.
std::array<Deepest, Agreement::kBackends> DeepestOfAll(
    std::array<std::unique_ptr<Backend>, Agreement::kBackends>& backends,
    std::span<const Pose> poses, int g1, int g2, std::span<Contact> buffer) {
  std::array<Deepest, Agreement::kBackends> got;
  for (int k = 0; k < Agreement::kBackends; ++k) {
    backends[k]->Forget();
    const int n = backends[k]->Detect(poses, buffer);
    got[k] = DeepestOf(std::span<const Contact>(buffer.data(), n), g1, g2);
  }
  return got;
}

/// Prints one agreement table.
void PrintAgreement(const char* title, const Agreement& a) {
  static const char* const kNames[] = {"MuJoCo", "FCL", "FCL ground-box", "Bullet", "Bullet tuned"};
  static const char* const kPairNames[] = {"MuJoCo vs FCL", "MuJoCo vs Bullet", "FCL vs Bullet"};
  std::printf("\n%s: %d poses\n", title, a.samples);
  std::printf(
      "| backend | misses | max depth error um | max depth error %% (depth >= 0.1 mm) "
      "| depths > 1 %% + 1 um off | max normal angle deg | normals > 1 deg off |\n"
      "|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < Agreement::kBackends; ++k) {
    std::printf("| %s | %d | %.3g | %.3g | %d | %.3g | %d |\n", kNames[k], a.misses[k],
                a.max_depth_error_m[k] * 1e6, a.max_relative_depth_error[k] * 100.0,
                a.depths_off[k], a.max_angle_deg[k], a.normals_off[k]);
  }
  std::printf("| **pair** | | **max depth difference um** | | | **max normal angle deg** | |\n");
  for (int p = 0; p < 3; ++p) {
    std::printf("| %s | | %.3g | | | %.3g | |\n", kPairNames[p], a.max_pair_depth_m[p] * 1e6,
                a.max_pair_angle_deg[p]);
  }
}

/// Box-plane and box-box agreement on seeded random poses: 4 box-size variants x 500 poses each,
/// penetration depths uniform in [1 um, 5 mm].
void RunAgreement() {
  std::mt19937 rng(2024u);
  std::uniform_real_distribution<double> half_m(0.01, 0.04);
  std::uniform_real_distribution<double> depth_m(1e-6, 5e-3);
  std::uniform_real_distribution<double> offset_m(-0.05, 0.05);
  std::normal_distribution<double> gauss;
  std::vector<Contact> buffer(256);
  Agreement plane_agreement, face_agreement, edge_agreement;
  for (int variant = 0; variant < 4; ++variant) {
    Scene scene{"agreement", {Plane()}, {Pose{}}, false, 1, 0.0};
    for (int b = 0; b < 2; ++b) {
      scene.geoms.push_back(BoxSpec(Vec3(half_m(rng), half_m(rng), half_m(rng))));
      scene.nominal.push_back({Vec3(0.3 * b, 0.0, 0.5), Quat::Identity()});
    }
    std::array<std::unique_ptr<Backend>, Agreement::kBackends> backends = {
        MakeBackend(BackendKind::kMujoco, scene), MakeBackend(BackendKind::kFcl, scene),
        MakeBackend(BackendKind::kFclGroundBox, scene), MakeBackend(BackendKind::kBullet, scene),
        MakeBackend(BackendKind::kBulletTuned, scene)};
    const Vec3 half_a_m = scene.geoms[1].half_size_m;
    const Vec3 half_b_m = scene.geoms[2].half_size_m;
    for (int i = 0; i < 500; ++i) {
      // box A near the plane, box B far above: closed form depth = -(lowest vertex z), normal +z
      std::vector<Pose> poses = scene.nominal;
      const double target_m = depth_m(rng);
      poses[1] = {Vec3(offset_m(rng), offset_m(rng), 0.0), RandomRotation(rng)};
      double lowest_m = 0.0;
      for (const Vec3& v : BoxVertices_W(half_a_m, poses[1])) lowest_m = std::min(lowest_m, v.z());
      poses[1].p_WG_m.z() = -lowest_m - target_m;
      poses[2] = {Vec3(0.0, 0.0, 1.0), Quat::Identity()};
      Record(plane_agreement, target_m, Vec3::UnitZ(), DeepestOfAll(backends, poses, 0, 1, buffer));

      // boxes A and B both high above the plane, B moved from A along a random direction until
      // the SAT depth equals the target (depth falls monotonically along the ray: it is the
      // distance to the boundary of a convex, centrally symmetric Minkowski difference)
      poses[1] = {Vec3(0.0, 0.0, 0.5), RandomRotation(rng)};
      poses[2].q_WG = RandomRotation(rng);
      const Vec3 u = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      const double target_box_m = depth_m(rng);
      auto sat_at = [&](double s_m) {
        poses[2].p_WG_m = poses[1].p_WG_m + s_m * u;
        return BoxBoxSat(half_a_m, poses[1], half_b_m, poses[2]);
      };
      double lo_m = 0.0;
      double hi_m = half_a_m.norm() + half_b_m.norm();
      for (int it = 0; it < 80; ++it) {
        const double mid_m = 0.5 * (lo_m + hi_m);
        (sat_at(mid_m).depth_m > target_box_m ? lo_m : hi_m) = mid_m;
      }
      const SatResult sat = sat_at(0.5 * (lo_m + hi_m));
      Record(sat.edge_edge ? edge_agreement : face_agreement, sat.depth_m, sat.n_W,
             DeepestOfAll(backends, poses, 1, 2, buffer));
    }
  }
  PrintAgreement("Box-plane agreement (reference: closed form)", plane_agreement);
  PrintAgreement("Box-box agreement, face-vertex reference axis (reference: separating axes)",
                 face_agreement);
  PrintAgreement("Box-box agreement, edge-edge reference axis (reference: separating axes)",
                 edge_agreement);
}

}  // namespace
}  // namespace rigidtouch::bench

int main(int argc, char** argv) {
  using namespace rigidtouch::bench;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string_view(argv[i]) == "--quick") {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: %s [--quick]\nunknown argument '%s'\n", argv[0], argv[i]);
      return 2;
    }
  }
  btAlignedAllocSetCustom(&CountingMalloc, &CountingFree);
  mju_user_malloc = &CountingMalloc;
  mju_user_free = &CountingFree;
  try {
    std::printf(
        "collision backends: MuJoCo %s, FCL %s, Bullet %d (double), %u hardware threads\n\n",
        mj_versionString(), FCL_VERSION, btGetVersion(), std::thread::hardware_concurrency());
    std::printf("load average at start: %s\n\n", LoadAverage().c_str());
    RunTimings(quick);
    RunBulletAblation(quick);
    std::printf("\nload average after timing: %s\n", LoadAverage().c_str());
    RunAgreement();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "collision_backends: %s\n", e.what());
    return 1;
  }
  return 0;
}
