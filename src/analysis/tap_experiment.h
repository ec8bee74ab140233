// The tap experiment: the engine's tick driving the simulated hand and device offline, one row
// of trace per tick, and the per-tap metrics (issue "simulated hand and device").
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/tap_metrics.h"
#include "base/progress.h"
#include "device/device_spec.h"
#include "device/presets.h"
#include "device/simulated_device.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::analysis {

/// The three walls of the method's perception study (docs/method.md, docs/study.md): 0 single
/// impulse, 1 train at 250 Hz, 2 train at 50 Hz (t_c = 0.1 s, e = 0).
RenderParams WallRenderParams(int wall);

/// The surface a tap is aimed at: a point of it and its outward normal.
struct Wall {
  Vec3 point_m = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  std::string geom;  // the geom it belongs to; empty when given as a point and normal
  /// A moving wall: a link geom of an articulated tree (docs/articulated.md, "Tapping a link: a
  /// moving wall"): the tree, its link, the geom's index in Model::geoms and the joint whose
  /// motion is reported (the hinge or slide nearest above the link, -1 if none). All -1 for a
  /// static wall.
  int tree = -1;
  int link = -1;
  int geom_index = -1;
  int joint = -1;
  bool moving() const { return tree >= 0; }
};

/// One tick of a moving wall (TapRun::wall_trace, aligned with TapRun::trace).
struct WallSample {
  double joint_position = 0.0;  // the reported joint's coordinate: rad (hinge) or m (slide)
  double joint_velocity = 0.0;  // rad/s or m/s
  /// Velocity of the wall's point under the tool (the tool's centre minus its reach along the
  /// wall's normal), moving with the link [m/s].
  Vec3 surface_velocity_mps = Vec3::Zero();
  /// Generalised impulse the tool's contacts with the wall gave the joint this tick, J^T P over
  /// the contact points: about a hinge's axis [N m s] (r x P . axis) or along a slide [N s].
  double joint_impulse = 0.0;
  bool touching_wall = false;  // some tool contact this tick is with the wall's geom
};

/// A moving wall's joint over one tap (TapRun::joint_taps, aligned with TapRun::taps).
struct JointMotion {
  double position_at_start = 0.0;  // at the tap's first sample [rad or m]
  double position_at_end = 0.0;    // at its last sample
  double velocity_at_end = 0.0;    // [rad/s or m/s]
  double min_position = 0.0, max_position = 0.0;
  double peak_speed = 0.0;  // largest |velocity| [rad/s or m/s]
  double impulse = 0.0;     // sum of WallSample::joint_impulse over the tap [N m s or N s]
};

/// Everything a tap run needs.
struct TapExperimentConfig {
  std::string scene_path;                   // MJCF with a wall and the tool
  LoadOptions load;                         // tool name, renderer, contact law, coupling
  std::string device_preset = "touch";      // a preset name or a JSON device spec (device_spec.h)
  std::optional<double> max_force_N;        // overrides the preset's force limit (0: unlimited)
  double rate_hz = 1000.0;                  // haptic rate: engine step and device tick, h = 1/rate
  std::optional<double> stiffness_N_per_m;  // default: the preset's maximum stiffness
  std::optional<double> damping_Ns_per_m;   // default: k h (capped at the device's damping)
  // virtual coupling only; default: the preset's maximum stiffness, and k h capped at its damping
  std::optional<double> coupling_stiffness_N_per_m;
  std::optional<double> coupling_damping_Ns_per_m;
  // the wall: a static geom of the scene (FindWall with wall_geom), or, when wall_point_m is set,
  // that point of its surface and wall_normal, its outward normal
  std::string wall_geom;
  std::optional<Vec3> wall_point_m;
  Vec3 wall_normal = Vec3::UnitZ();
  // true: aim at the first surface below the scene's tool along the wall's normal (any body's,
  // SurfaceBelowTool), falling back to the wall itself when there is none; for running a scene
  // (serve, view), where the surface under the tool need not be the wall. The tap experiment's
  // metrics describe the static wall and keep false.
  bool aim_below_tool = false;
  // true: the simulated hand, which works in the scene's coordinates, counts as plausible within
  // 0.5 m of the wall and of the scene's tool (a door's panel lies 1.2 m from the origin, beyond
  // the default radius of 1 m). False where the user wrote a radius: load.device's, as written.
  bool widen_plausible_radius = true;
  device::HandParams hand;
  // default: the device spec's inertia and sensing; tick_rate_hz is set from rate_hz
  std::optional<device::DeviceModelParams> device_model;
  device::TapScript script;  // surface point and normal are set from the wall
  // the longer task this run is part of (may be null): the run reports the fractions
  // progress_from to progress_to of it as its ticks pass, saying `progress_where`, and at a stop
  // request throws Interrupted saying `progress_kept` (what the task has kept)
  Progress* progress = nullptr;
  double progress_from = 0.0;
  double progress_to = 1.0;
  std::string progress_where;
  std::string progress_kept;
};

/// The result of a run.
struct TapRun {
  Model model;  // as rendered (tool mass, stiffness, schedule)
  Wall wall;    // where the taps were aimed
  DeviceLimits device;
  std::string material_note;               // TapSetup::material_note
  std::vector<TraceSample> trace;          // one sample per tick
  std::vector<TapMetrics> taps;            // one per scripted tap
  double energy_to_user_J = 0.0;           // the device's own bookkeeping over the whole run
  std::int64_t clipped_ticks = 0;          // ticks whose force the device limit clipped
  std::int64_t clipped_impulse_ticks = 0;  // ... while an impulsive force was in the command
  std::array<WarningStat, static_cast<int>(Warning::kCount)> warnings{};
  // a moving wall only (wall.moving()); empty or zero otherwise
  std::vector<WallSample> wall_trace;   // one per tick, as trace
  std::vector<JointMotion> joint_taps;  // one per tap, as taps (when the wall has a joint)
  std::string joint_name;               // the reported joint (wall.joint)
  JointKind joint_kind = JointKind::kHinge;
  double joint_inertia = 0.0;    // M_dd at the start: the tree's inertia about the joint with
                                 // armature, as compiled [kg m^2 or kg]
  double joint_damping = 0.0;    // the joint's damping [N m s/rad or N s/m]
  double joint_stiffness = 0.0;  // its spring [N m/rad or N/m]
};

/// The wall of `model` (loaded from `scene_path`, for messages): the static geom named `geom`, or
/// when `geom` is empty the static geom named "wall", else the scene's only static plane. A
/// plane's surface passes through its centre with the normal its frame's z axis; a box's is the
/// face whose outward normal is its frame's z axis. A link geom of an articulated tree is a
/// moving wall: its surface is the point of the geom (a plane, box, sphere or capsule, at the
/// scene's initial pose) nearest the scene's tool, with the outward normal there (a box's: the
/// face nearest the tool). Throws Error naming the scene and listing its static planes and boxes
/// when there is no such geom, it is a free body's, or it is another type.
Wall FindWall(const Model& model, const std::string& scene_path, const std::string& geom);

/// The first surface that a ray from the tool's position in the scene (`model.initial`) along
/// -normal meets: its point and the geom's name, or nothing. Geoms of the tool's own body, geoms
/// the tool's geoms cannot collide with and geoms the ray starts inside are skipped. Planes,
/// spheres and boxes are met exactly; other shapes at their bounding spheres.
std::optional<Wall> SurfaceBelowTool(const Model& model, const Vec3& normal);

/// Makes the tool the end effector of a directly coupled device: its mass in Eq. 1 becomes the
/// device's apparent mass plus the hand's (the rotational inertia keeps its shape).
void UseDeviceAndHandMass(Model& model, const device::DeviceModelParams& device,
                          const device::HandParams& hand);

/// A model and a simulated device made ready for a tap run: the tool starts at the device's
/// start position, with the device's and hand's mass when coupled directly.
struct TapSetup {
  Model model;
  Wall wall;
  DeviceLimits device;
  std::unique_ptr<device::SimulatedDevice> simulated;
  /// Set when the material's amplitude was converted for this device with another mass than its
  /// file's (io::RenderMaterialOnDevice): the note for the user; else empty.
  std::string material_note;
};

/// Builds the model and simulated device of `config`. The model's material is the one rendered on
/// the device: an acceleration material converted with the device's and hand's effective mass
/// (io::RenderMaterialOnDevice). Throws Error on bad configuration (naming
/// the parameter).
TapSetup PrepareTap(const TapExperimentConfig& config);

/// Runs the experiment offline, as fast as it computes. Throws Error on bad configuration.
TapRun RunTapExperiment(const TapExperimentConfig& config);

}  // namespace rigidtouch::analysis
