// The model: everything that is constant while a scene runs (MuJoCo's mjModel, Pinocchio's Model).
// Built by LoadModel from an MJCF file plus rigidtouch's own parameters; Tick takes it as const.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rigidtouch/types.h"

struct mjModel_;

namespace rigidtouch {

namespace dynamics {
struct TreeModel;  // src/dynamics/tree.h: the joint-space dynamics of one kinematic tree
}  // namespace dynamics

/// Geometric primitive of a collision geom (the MJCF geom types rigidtouch accepts).
/// kMesh also stands for the other convex shapes that MuJoCo's pair functions collide (cylinder,
/// ellipsoid): GeomModel::mj_type says which.
enum class GeomType { kPlane, kSphere, kCapsule, kBox, kMesh };

/// Which rendering method produces the collision impulses (docs/method.md).
enum class RendererKind {
  kPenalty,  ///< penalty feedback only, no impulses
  kImpulse,  ///< one impulse at contact onset, Eq. 5 with restitution e (the [IAP] model)
  kTrain,    ///< a modulated train of N impulses over the collision window, Eq. 8 (e = 0)
  kEvent,    ///< penalty plus an open-loop decaying sinusoid at contact onset (Kuchenbecker,
             ///< Fiene and Niemeyer 2006; Okamura, Cutkosky and Dennerlein 2001); not passive
};

/// A material's contact transient, the decaying sinusoid A v_in e^(-B t) sin(2 pi f t) along the
/// contact normal (Okamura, Cutkosky and Dennerlein 2001), v_in the approach speed at onset.
/// Presets and JSON files: src/io/materials.h, docs/renderers.md.
///
/// A force material gives A as a force at the device. An acceleration material (fitted from a
/// recording of the handle's acceleration, docs/materials.md) keeps that slope as recorded and
/// the mass its force was computed with: A = amplitude_mps2_per_mps x effective_mass_kg. On a
/// device, io::MaterialOnDevice puts the device's effective mass in; with no device the mass
/// read from the file (the fit device's) stays.
struct Material {
  std::string name;                 // empty: none given
  double amplitude_Ns_per_m = 0.0;  // A: force per approach speed, as rendered [N/(m/s)]
  double decay_per_s = 0.0;         // B [1/s]
  double frequency_hz = 0.0;        // f [Hz]
  /// Acceleration materials only (both 0 for a force material): the handle's acceleration per
  /// approach speed as recorded [(m/s^2)/(m/s)] and the effective mass A was converted with [kg]
  /// (a device's apparent mass plus the hand's).
  double amplitude_mps2_per_mps = 0.0;
  double effective_mass_kg = 0.0;
  /// An acceleration material: its force A follows the mass it is rendered with.
  bool acceleration() const { return effective_mass_kg > 0.0; }
};

/// How the device drives the virtual tool (tick stage 1, docs/architecture.md).
enum class Coupling {
  kNone,     ///< no device: the user wrench comes from TickInput::tool_wrench (offline simulation)
  kDirect,   ///< the tool is the device end effector: its pose and velocity are the device's
  kVirtual,  ///< a spring-damper between device and tool positions (Colgate et al. 1995); the
             ///< tool's orientation and angular velocity are the device's
};

/// A free rigid body; its state lives at the centre of mass in the principal inertial frame.
struct BodyModel {
  std::string name;
  double mass_kg = 0.0;
  Vec3 inertia_kgm2 = Vec3::Zero();  // principal moments, inertial frame
  Vec3 ipos_B = Vec3::Zero();        // inertial frame origin in the MJCF body frame
  Quat iquat_B = Quat::Identity();   // inertial frame orientation in the MJCF body frame
  int mj_body = -1;                  // id in the compiled MuJoCo model
  int mj_qpos_adr = -1;              // freejoint qpos address (7 numbers)
  int mj_qvel_adr = -1;              // freejoint qvel address (6 numbers)
};

/// A collision geom. `body` is an index into Model::bodies, or -1 for static world geometry and for
/// the geoms of a tree's links. A link geom has `tree` >= 0 (Model::trees) and `link` (the tree's
/// body): the tick's trees stage moves its pose every step. Collision sees it as static geometry at
/// that pose (so links collide with free bodies and the tool only); the contact stages make its
/// contacts rows on the link of its tree's group (docs/decisions.md, "Contact groups over
/// trees in the tick").
struct GeomModel {
  std::string name;
  GeomType type = GeomType::kSphere;
  int body = -1;
  int tree = -1;                     // index into Model::trees, -1 if not on a link
  int link = -1;                     // body of that tree the geom is fixed to
  Vec3 pos_L = Vec3::Zero();         // centre in the link's body frame (link geoms only)
  Quat quat_L = Quat::Identity();    // orientation in the link's body frame (link geoms only)
  double friction = 0.0;             // MJCF sliding friction coefficient
  Vec3 size = Vec3::Zero();          // MuJoCo size: radius, (radius, half-length), half-extents
  double rbound_m = 0.0;             // radius of a bounding sphere about the geom centre
  Vec3 pos_B = Vec3::Zero();         // centre in the body's principal frame (world if static)
  Quat quat_B = Quat::Identity();    // orientation in the body's principal frame
  int contype = 1, conaffinity = 1;  // MJCF collision filter bits
  int mj_geom = -1;
  /// MJCF condim (1 frictionless, 3 sliding friction). A condim-1 geom's `friction` is 0, so the
  /// contact law's max over the two geoms gives MuJoCo's rule (a contact is frictionless when
  /// both geoms' condim is 1); 4 and 6 keep sliding friction only (a load warning says so).
  int condim = 3;
  double mjcf_friction = 0.0;  // the MJCF sliding friction as written, before condim
  int mj_type = -1;            // MuJoCo's geom type (mjtGeom) in the compiled model
};

/// Joint kinds of an articulated tree, with MuJoCo's coordinates (dynamics::JointType).
enum class JointKind { kFree, kBall, kSlide, kHinge };

/// One joint of an articulated tree: its name, coordinates and limit (MJCF <joint>).
struct JointModel {
  std::string name;
  JointKind type = JointKind::kHinge;
  int link = -1;      // the tree body the joint moves
  int qpos_adr = -1;  // into the tree's qpos: 1 number (hinge, slide), 4 (ball), 7 (free)
  int dof_adr = -1;   // into the tree's qvel: 1, 3 or 6 numbers
  /// MJCF range with limited (or the compiler's autolimits): hinge [rad], slide [m]; a ball's
  /// limit is the rotation angle, range_hi_rad_or_m (range_lo is 0). Reported by the trees stage
  /// (Data::joint_at_limit); a hinge's or slide's limit is enforced as a unilateral row of its
  /// tree's contact group (RenderParams::joint_limit_renderer); a ball's is only reported.
  bool limited = false;
  double range_lo_rad_or_m = 0.0;
  double range_hi_rad_or_m = 0.0;
};

/// One actuator on a hinge or slide joint at a constant control (MJCF <actuator>: motor, position,
/// velocity, damper, general with fixed or affine gain and bias, no activation state). With
/// length l = gear q and velocity v = gear qdot (MuJoCo's joint transmission), the actuator force
/// is f = (g0 + g1 l + g2 v) ctrl + (b0 + b1 l + b2 v), clamped to the force range when
/// force_limited, and the joint force is gear f. ctrl is clamped once, at load, to the control
/// range when ctrl_limited.
struct ActuatorModel {
  std::string name;
  int joint = -1;     // index into ArticulatedTree::joints
  double gear = 1.0;  // joint force per actuator force (MJCF gear[0])
  double ctrl = 0.0;  // the constant control: keyframe 'initial' ctrl, default 0, clamped
  double gain[3] = {1.0, 0.0, 0.0};  // g0, g1 [1/(m or rad)], g2 [s/(m or rad)]
  double bias[3] = {0.0, 0.0, 0.0};  // b0 [N or N m], b1, b2
  bool force_limited = false;
  double force_lo = 0.0, force_hi = 0.0;  // N (slide) or N m (hinge), before the gear
};

/// An articulated tree of MJCF bodies: a body with joints whose parent is static (welded to the
/// world), with every body below it. Bodies without joints below it are welded into their
/// nearest jointed ancestor (masses and inertias merged), as MuJoCo's body_weldid groups them.
struct ArticulatedTree {
  std::string name;                     // the root body's MJCF name
  std::vector<std::string> link_names;  // per tree body: the MJCF body it is
  std::vector<int> link_mj_body;        // per tree body: its id in the compiled MuJoCo model
  std::vector<int> link_parent;         // per tree body: its parent body in the tree, -1 world
  std::vector<JointModel> joints;       // in the tree's joint order (MuJoCo's)
  std::vector<ActuatorModel> actuators;
  /// Joint-space dynamics: bodies, joints, damping, armature, springs, gravity. Shared by copies
  /// of the Model (it is constant); dynamics::TreeModel is complete in src/dynamics/tree.h.
  std::shared_ptr<const dynamics::TreeModel> dynamics;
  int nq = 0, nv = 0;
  std::vector<double> initial_qpos;  // (nq) keyframe 'initial', else the MJCF defaults (qpos0)
  std::vector<double> initial_qvel;  // (nv) keyframe 'initial', else zero
};

/// Penalty contact law (tick stage 4). Stiffness and damping are per geom pair; a manifold of n
/// points shares them equally, so a box face on a plane is as stiff as a sphere on it.
struct ContactParams {
  /// Contacts involving the tool: the haptic wall the device renders, explicit as on a device.
  double stiffness_N_per_m = 2000.0;
  double damping_Ns_per_m = 2.0;
  /// Contacts between other bodies and the world: simulated with implicit (backward Euler) penalty,
  /// stiff enough that a 10-box stack compresses less than 1 mm.
  double scene_stiffness_N_per_m = 2.0e5;
  double scene_damping_Ns_per_m = 100.0;
  /// Coulomb friction during penalty contact, >= 0; exactly -1 means "use the MJCF geom
  /// friction" (Configure refuses any other negative value).
  double friction_static = -1.0;
  double friction_kinetic = -1.0;
  /// Tangential stick-anchor spring relative to the normal stiffness and damping.
  double tangential_ratio = 1.0;
  /// A new contact starts a collision window only if it approaches faster than this.
  double onset_speed_mps = 1.0e-3;
  /// The user gave the scene stiffness / damping (flag or config): Configure keeps it even when it
  /// equals the default. Unset and equal to the default, Configure derives it from the scene
  /// (docs/method.md, "Contact defaults from the scene"); a value that differs from the default
  /// counts as given either way.
  bool scene_stiffness_given = false;
  bool scene_damping_given = false;
};

/// Collision rendering (Eq. 6-7, docs/method.md).
struct RenderParams {
  RendererKind renderer = RendererKind::kTrain;
  double restitution = 0.0;       // e in [0, 1]; the train requires e = 0
  double t_collision_s = 0.1;     // t_c, collision-rendering window, at most 0.1 s
  double frequency_hz = 250.0;    // f, impulse-train frequency, in [1/t_c, 1/h]
  bool reference_solver = false;  // use the exact Eq. 5/8 pseudo-inverse (may pull) instead
  /// The user gave f (flag, config or material): kept as given. Unset and equal to the default
  /// 250 Hz, LoadModel lowers it to 1/h (one impulse per step) for a scene whose time step is
  /// longer than 4 ms, with a load warning (docs/config.md).
  bool frequency_given = false;
  /// Time-domain passivity observer and controller at the device port (Hannaford and Ryu 2002,
  /// render::PassivityControl), over any renderer; needs a device (direct or virtual coupling).
  bool passivity_control = false;
  /// The event renderer's transient (required by it); other renderers refuse one.
  Material material;
  /// How a hinge or slide joint's limit (its `range`) renders when the joint reaches it: always a
  /// unilateral penalty row of its contact group (stiffness from the joint's inertia, docs/
  /// decisions.md, "Joint limits as rows"), plus at onset a single impulse (kImpulse, Eq. 5 with
  /// restitution e), a train (kTrain, Eq. 8, plastic, over t_c at f) or nothing (kPenalty), like
  /// a wall. kEvent is refused.
  RendererKind joint_limit_renderer = RendererKind::kTrain;
};

/// Impulse schedule derived from RenderParams and the time step (Eq. 6, Eq. 7).
struct Schedule {
  int window_steps = 1;    // n = t_c / h, rounded to the nearest whole step
  int interval_steps = 1;  // n_i = 1 / (f h), rounded to the nearest whole step
  int impulses = 1;        // N = round(n / n_i); impulse k (0-based) at step k n_i after onset
};

/// Device-side settings used by Tick's coupling and render stages.
struct DeviceParams {
  Coupling coupling = Coupling::kNone;
  /// What the device can display (a preset's or the device's own limits; 0: no force limit,
  /// stiffness or damping unknown). The render stage clips the force to limits.max_force_N.
  /// Configure refuses a rendered stiffness or damping above the limits: the contact law's under
  /// direct coupling, the coupling's under virtual coupling (docs/decisions.md, "Device limits").
  /// The torque limit is the device's: the loop's last guard and the bridge apply it.
  DeviceLimits limits;
  double coupling_stiffness_N_per_m = 1000.0;  // virtual coupling
  double coupling_damping_Ns_per_m = 5.0;
  Vec3 workspace_offset_m = Vec3::Zero();  // tool position = device position + offset
  /// The device's position quantum (encoder resolution) [m]; 0: exact. The passivity observer
  /// keeps a reserve for the error it makes in the observed energy.
  double position_resolution_m = 0.0;
  /// A device state farther than this from the device's origin, or faster, is implausible: the
  /// tick outputs zero force and counts Warning::kImplausibleDeviceState.
  double plausible_radius_m = 1.0;
  double plausible_speed_mps = 10.0;
  double plausible_angular_speed_radps = 100.0;
};

/// The state of one body: centre of mass and principal-frame orientation, world frame (W).
struct BodyState {
  Vec3 x_W = Vec3::Zero();
  Quat q_WB = Quat::Identity();
  Vec3 v_W = Vec3::Zero();
  Vec3 w_W = Vec3::Zero();
};

/// Everything constant while a scene runs.
struct Model {
  std::string source;         // scene file it was loaded from
  double timestep_s = 0.001;  // h
  Vec3 gravity_W = Vec3(0, 0, -9.81);
  std::vector<BodyModel> bodies;       // dynamic bodies (MJCF freejoint bodies)
  std::vector<GeomModel> geoms;        // collision geoms, static (body -1) and dynamic
  std::vector<BodyState> initial;      // per body, from keyframe "initial" or the MJCF defaults
  std::vector<ArticulatedTree> trees;  // articulated trees (MJCF bodies with joints other than a
                                       // lone top-level freejoint), stepped by the trees stage
  int tool = 0;                        // index of the tool in `bodies` (the method's body 1)
  /// false for a scene loaded without a tool (LoadOptions::tool_name "none"): `tool` is then a
  /// placeholder body without geoms that the trees stage holds at its initial state
  bool has_tool = true;
  ContactParams contact;
  RenderParams render;
  Schedule schedule;  // derived by Configure from render and timestep_s
  /// The joint limits' train schedule (render.joint_limit_renderer kTrain; Eq. 6-7 with the
  /// render's t_c and f), derived by Configure
  Schedule joint_limit_schedule;
  DeviceParams device;
  int max_contacts = 0;                 // capacity of the contact list; extra contacts are dropped
  int max_group_bodies = 0;             // capacity of one group (implicit penalty solve is dense)
  std::shared_ptr<mjModel_> collision;  // compiled MJCF, owned (shared by copies of the Model)
  /// Threads stepping the scene: 1, or 2 (a worker thread shares collision detection, the
  /// contacts' classification and forces, and the contact groups' solves; the results are the
  /// same bit for bit).
  int threads = 1;
  /// Problems found at load that do not stop the scene (e.g. a contact stiffness that cannot hold
  /// a body or is unstable for it at h; an MJCF element accepted but not simulated as MuJoCo would,
  /// named), one sentence each; the CLI prints them to stderr.
  std::vector<std::string> load_warnings;
  /// The scene-contact stiffness and damping Configure derived from the bodies' masses and h
  /// (docs/method.md, "Contact defaults from the scene"); 0 if they were set by the user.
  double derived_scene_stiffness_N_per_m = 0.0;
  double derived_scene_damping_Ns_per_m = 0.0;
  /// Geom pairs that never collide (MJCF <contact><exclude body1 body2>: every geom of the one
  /// MJCF body with every geom of the other), as indices into `geoms`, each pair (a, b) with
  /// a < b, sorted and without repeats. Kept by geoms, not by Model::bodies, because every static
  /// MJCF body is body -1 there (and welded bodies are one): excluding one static body must leave
  /// the others, and the world, in contact.
  std::vector<std::pair<int, int>> excluded_geom_pairs;
  /// MuJoCo's parent filter: a link's geoms do not collide with the geoms of its parent link
  /// (a tree's root link still collides with static geometry). False when the scene has
  /// <flag filterparent="disable"/>.
  bool filter_parent = true;
};

}  // namespace rigidtouch
