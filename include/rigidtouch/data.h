// The data: all mutable state of a running scene, preallocated by MakeData (MuJoCo's mjData).
// Fields are grouped by what they depend on, as in mjdata.h.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "rigidtouch/model.h"
#include "rigidtouch/types.h"

namespace rigidtouch {

/// Phase of one contact, set by the tick's groups-and-windows stage (docs/architecture.md).
enum class ContactPhase {
  kColliding,  ///< its group is inside a collision-rendering window: impulses may be due
  kResting,    ///< outside any window: penalty only
};

/// One contact point. The normal points from body b towards body a: the penalty force and the
/// impulse act as +n on a and -n on b. Body indices are into Model::bodies, -1 for static geometry.
struct Contact {
  int id = -1;                   // persistent identity across ticks
  int geom_a = -1, geom_b = -1;  // Model::geoms indices
  int body_a = -1, body_b = -1;
  int pair_points = 1;  // points the geom pair has this tick (shares the stiffness)
  // what matching reads of last tick's contacts and carries over, together at the record's start
  // (bytes 0 to 104: two or three cache lines, read for every contact in every tick)
  // contact point in a's principal frame (a link geom's own frame when a is a link), for
  // matching and the friction anchors
  Vec3 p_A = Vec3::Zero();
  // friction stick anchor on a (a's frame) and b (b's frame), placed at the contact point each
  // tick with the stretch it had (so a rolling body's anchor does not leave the contact)
  Vec3 anchor_A = Vec3::Zero();
  Vec3 anchor_B = Vec3::Zero();
  bool is_new = false;    // penetrating now, not matched to a penetrating contact before
  bool sticking = false;  // friction anchor holds
  // this tick's phase and group, for reports and viewers (written by stage 3 with the windows)
  ContactPhase phase = ContactPhase::kResting;
  int group = -1;
  Vec3 p_W = Vec3::Zero();      // contact point (midpoint between the surfaces)
  Vec3 n_W = Vec3::UnitZ();     // unit normal, from b towards a
  double depth_m = 0.0;         // penetration, > 0 when the geoms overlap
  Vec3 p_B = Vec3::Zero();      // contact point in b's frame, as p_A (world frame if b is static)
  double normal_force_N = 0.0;  // penalty force this tick
  Vec3 friction_force_N_W = Vec3::Zero();  // on a
  double impulse_Ns = 0.0;                 // normal impulse this tick
};

/// The contiguous run of one geom pair's points in a contact list (for grouping the bodies, and
/// for matching across ticks).
struct PairRun {
  int geom_a = -1, geom_b = -1;
  int body_a = -1, body_b = -1;  // the points' bodies (Contact::body_a, body_b)
  int begin = 0, count = 0;
};

/// A contact group's collision-rendering window, kept per body so it survives regrouping.
struct WindowState {
  std::int64_t onset_step = -1;  // step of the last collision onset; -1: never
  int impulses_done = 0;         // impulses applied since onset
  // the group's last impulse came from the interior-point method of the impulse solver: its
  // next ones go there at once while the group keeps colliding (an onset less than 0.1 s after
  // the last one keeps this; a later onset clears it)
  bool interior = false;
};

/// One applied collision impulse (kept for the ticks it happened in; see Data::impulses).
struct ImpulseEvent {
  std::int64_t step = 0;
  double time_s = 0.0;
  int group = -1;
  int contacts = 0;   // contact rows in the group (Jc rows)
  int index = 0;      // i, 1-based position in the train
  int total = 0;      // N
  bool tool = false;  // the tool is in the group
  double kinetic_energy_before_J = 0.0;
  double kinetic_energy_after_J = 0.0;
  double impulse_norm_Ns = 0.0;           // |p|, Euclidean norm over the group's rows
  Vec3 tool_impulse_Ns_W = Vec3::Zero();  // linear impulse on the tool  [N s]
};

/// Conditions Tick counts instead of throwing (MuJoCo's mjtWarning). Each is counted once per tick
/// in which it happened (Data::Warn).
enum class Warning : int {
  kContactFull = 0,  ///< more contacts than Model::max_contacts; extras dropped
  kGroupTooLarge,    ///< a group exceeded Model::max_group_bodies; its bodies move freely
  kSolverFailed,     ///< the impulse solver failed; the impulse was skipped (zero)
  kBadDeviceState,   ///< device state invalid or non-finite; zero force output
  kNonFiniteState,   ///< the simulation produced NaN/Inf; state reset to initial (ResetState)
  kForceClipped,     ///< the device force limit clipped the output
  kImpulseClipped,   ///< ... and the clipped output contained an impulsive force
  kImplausibleDeviceState,  ///< device state outside DeviceParams' plausible reach or speed;
                            ///< zero force output
  kCount
};

/// Name of a warning for reports.
const char* WarningName(Warning w);

/// Name of a joint's kind for reports: "free", "ball", "slide" or "hinge" (MJCF's joint types).
const char* JointKindName(JointKind kind);

/// Count and last step of one warning.
struct WarningStat {
  int count = 0;                // ticks in which the warning happened
  std::int64_t last_step = -1;  // the last of them; -1: never
};

namespace dynamics {
struct TreeData;  // src/dynamics/tree.h: one tree's state, kinematics and scratch
}  // namespace dynamics
/// Deleter so Data can own trees' state without exposing its definition.
struct TreeDataDeleter {
  void operator()(dynamics::TreeData* d) const;
};

struct Workspace;  // solver scratch, defined in src/engine/workspace.h
/// Deleter so Data can own a Workspace without exposing it.
struct WorkspaceDeleter {
  void operator()(Workspace* w) const;
};

/// The passivity observer and controller at the device port (render::PassivityControl).
struct PassivityState {
  /// Energy the renderer absorbed at the port since the current contact began [J]:
  /// -sum F_k . (x_{k+1} - x_k) over the ticks with a force. >= 0 is passive.
  double observed_J = 0.0;
  /// Energy the controller's damping has dissipated since the start [J], measured like observed_J.
  double dissipated_J = 0.0;
  /// The part of dissipated_J measured this tick (the controller's force of the last tick) [J].
  double step_dissipated_J = 0.0;
  /// The controller's damping this tick [N s/m]; 0 when it is idle.
  double damping_Ns_per_m = 0.0;
  /// sum |F_k - F_(k-1)| over the contact [N]: with the position quantum it bounds the observer's
  /// error.
  double force_variation_N = 0.0;
  Vec3 last_force_N = Vec3::Zero();          // the force the device held over the last tick
  Vec3 last_control_force_N = Vec3::Zero();  // the controller's part of it
  Vec3 last_position_m = Vec3::Zero();       // the device's position at the last tick
  bool has_last = false;
};

/// The event renderer's transient in progress (render::EventTransient).
struct EventState {
  std::int64_t onset_step = -1;     // the tick the transient started; -1: none
  double approach_speed_mps = 0.0;  // v_in
  Vec3 normal_W = Vec3::UnitZ();    // the direction it pushes the tool
};

/// All mutable state. Create with MakeData; every buffer is sized there and never grows in Tick.
struct Data {
  // time
  std::int64_t step = 0;
  double time_s = 0.0;

  // POSITION and VELOCITY state, per body
  std::vector<BodyState> bodies;  // (nbody)

  // POSITION and VELOCITY state, per articulated tree (Model::trees): qpos (nq) and qvel (nv) in
  // MuJoCo's coordinates, with the tree's kinematics, mass matrix, factor and scratch
  std::vector<std::unique_ptr<dynamics::TreeData, TreeDataDeleter>> trees;  // (ntree)
  // per tree and joint, written by the trees stage: the joint is at or beyond a limit of its range
  std::vector<std::vector<unsigned char>> joint_at_limit;  // (ntree) x (njoint of the tree)
  // per tree: the collision-rendering window of its group (as Data::window for bodies)
  std::vector<WindowState> tree_window;  // (ntree)

  // POSITION dependent, written by the kinematics stage before collision detection and read by
  // every later stage until the positions are integrated
  std::vector<Mat3> R_WB;  // (nbody) rotation matrix of each body's frame, from bodies[i].q_WB

  // CONTACT dependent, per tick
  std::vector<Contact> contacts;  // (max_contacts); the first ncontact are valid
  int ncontact = 0;
  // (max_contacts) the runs of contacts[0 .. ncontact), one per geom pair, in list order: the
  // list's index by geom pair (a Contact spans several cache lines), written with it by collision
  // detection and read by grouping. Last tick's contacts, which identity matching reads, are the
  // collision stage's own (src/geometry/contact_matching.h)
  std::vector<PairRun> runs;
  int nruns = 0;
  // (nbody) group of each body, -1 if in no contact; a body in a group with a tree (a contact on
  // a link) has a group from ngroup on (the groups with trees come after the others)
  std::vector<int> body_group;
  int ngroup = 0;                   // groups without a tree
  std::vector<WindowState> window;  // (nbody) collision-window state of each body's group

  // FORCE outputs of the last tick
  Vec3 tool_penalty_force_N_W = Vec3::Zero();   // contact penalty on the tool
  Vec3 tool_coupling_force_N_W = Vec3::Zero();  // virtual coupling on the tool
  Vec3 tool_impulse_Ns_W = Vec3::Zero();        // linear impulse on the tool this tick
  double tool_penetration_m = 0.0;
  Vec3 tool_normal_W = Vec3::UnitZ();
  int tool_contacts = 0;
  std::vector<ImpulseEvent> impulses;  // (nbody + ntree) impulses applied this tick
  int nimpulse = 0;

  // PASSIVITY observer and controller state, kept across ticks
  PassivityState passivity;
  // EVENT transient state, kept across ticks
  EventState event;

  // diagnostics
  std::array<WarningStat, static_cast<int>(Warning::kCount)> warnings{};

  // scratch
  std::unique_ptr<Workspace, WorkspaceDeleter> workspace;

  /// Counts warning `w` for this tick: at most once per step, however often it happens in it.
  void Warn(Warning w) { WarnAt(w, step); }
  /// Counts warning `w` for step `at_step` (the haptic loop's guards, after Tick has advanced
  /// `step`, count for the tick that made the command).
  void WarnAt(Warning w, std::int64_t at_step) {
    WarningStat& s = warnings[static_cast<int>(w)];
    if (s.last_step == at_step && s.count > 0) return;
    ++s.count;
    s.last_step = at_step;
  }
};

}  // namespace rigidtouch
