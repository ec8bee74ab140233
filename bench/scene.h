// The benchmark scenes: which MJCF file, the constant tool force, how long to warm up and
// measure, and the quality gates each engine must pass for its numbers to count.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::bench {

/// How a scene is measured.
enum class SceneKind {
  kSteady,  ///< every measured step is a step of the settled scene
  kStrike,  ///< every measured step is the one that resolves a tool strike on the settled scene
};

/// How the peers (MuJoCo, Bullet) are configured; rigidtouch's own settings never change.
enum class PeerSettings {
  kDefaults,  ///< every solver and contact setting at the engine's default (as the MJCF gives)
  kStacking,  ///< the settings each peer's documentation recommends for resting contact and
              ///< stacks (docs/performance.md, "Peer configuration"); the suite's default
};

/// Parses "defaults" or "stacking". Throws `rigidtouch::Error` naming the value otherwise.
PeerSettings ParsePeerSettings(const std::string& text);

/// Returns "defaults" or "stacking".
const char* PeerSettingsName(PeerSettings settings);

/// One benchmark scene with its measurement plan and quality gates (immutable once built).
struct Scene {
  std::string name;       ///< benchmark name, e.g. "pile-strike"
  std::string mjcf_path;  ///< the MJCF file
  SceneKind kind = SceneKind::kSteady;
  std::string tool_body = "tool";
  Vec3 tool_force_N = Vec3(0.0, 0.0, -2.0);  ///< constant, world frame, at the tool's centre
  double tool_radius_m = 0.005;
  PeerSettings peer_settings = PeerSettings::kStacking;

  int warmup_steps = 2000;  ///< steps after load before the snapshot
  int measured_steps = 0;   ///< steady: measured steps; strike: measured strikes
  int batch_steps = 1000;   ///< steady: restore the snapshot every this many steps

  /// Gate: this body moves less than `max_watch_displacement_m` over `watch_steps` steps run
  /// from the snapshot (empty: no such gate).
  std::string watch_body;
  int watch_steps = 0;
  double max_watch_displacement_m = std::numeric_limits<double>::infinity();

  /// Gate: the deepest penetration over every step run (warm-up, gates, measurement).
  double max_penetration_m = std::numeric_limits<double>::infinity();

  /// Gate (articulated scenes): the deepest penetration among the contacts of the tool over every
  /// step after the warm-up (the gate run and the measurement: the push held steadily, after the
  /// tool's first arrival), under this limit.
  double max_tool_penetration_m = std::numeric_limits<double>::infinity();

  /// Gate (articulated scenes): the joint `limit_joint` stays within [limit_lo, limit_hi] (its
  /// MJCF range: rad for a hinge, m for a slide) to within `max_limit_overshoot` over every step
  /// after the warm-up. Empty: no such gate.
  std::string limit_joint;
  double limit_lo = 0.0;
  double limit_hi = 0.0;
  double max_limit_overshoot = 0.0;

  /// Strike: the tool is placed straight above the centre of `strike_target`, `strike_gap_m` from
  /// its upward face (between the tool's surface and the face, along the face normal), moving
  /// down at `strike_speed_mps`.
  std::string strike_target;
  double strike_target_half_size_m = 0.025;  ///< the target is a cube of this half-size
  double strike_gap_m = 0.010;
  double strike_speed_mps = 0.3;
  int strike_max_steps = 200;  ///< a strike that takes longer fails the gate
};

/// The scene folder compiled into the benchmark (the source tree's scenes/).
std::string DefaultScenesDir();

/// Returns the four benchmark scenes (tap, stack, pile, pile-strike) reading MJCF files from
/// `scenes_dir`. `scale` in (0, 1] shortens the measurement (for smoke runs); gates and warm-up
/// stay as specified. Throws `rigidtouch::Error` when `scale` is out of range.
std::vector<Scene> BenchmarkScenes(const std::string& scenes_dir, double scale = 1.0);

/// The articulated scenes (door, drawer, lever, arm: scenes/door.xml and so on), steady, the tool
/// pushed onto the part a user touches with a constant force, with the tool-contact and
/// joint-limit gates (docs/performance.md, "Articulated scenes").
std::vector<Scene> ArticulatedBenchmarkScenes(const std::string& scenes_dir, double scale = 1.0);

/// The humanoid scene: `wrapper_path` is the MJCF file WriteHumanoidWrapper() wrote. Steady, the
/// tool pushed onto the torso with 2 N, the tool-contact gate only.
Scene HumanoidBenchmarkScene(const std::string& wrapper_path, double scale = 1.0);

/// Writes, into the folder `out_dir`, `humanoid_tool.xml`: an MJCF file that <include>s MuJoCo's
/// model/humanoid/humanoid.xml from `humanoid_path`, sets the step to 1 ms, and adds the tool on
/// the chest of the humanoid lying on its back (keyframe 'initial'). Returns its path. Throws
/// `rigidtouch::Error` naming `flag` when `humanoid_path` is not a readable file.
std::string WriteHumanoidWrapper(const std::string& humanoid_path, const std::string& out_dir,
                                 const std::string& flag);

/// The large scenes, run only when asked for (`--rigidtouch_large`): pile400, pile1000 and
/// pile2000 (the pile's boxes on 10 x 10 x 4, x 10 and x 20 grids), steady, with the pile's gates.
std::vector<Scene> LargeBenchmarkScenes(const std::string& scenes_dir, double scale = 1.0);

}  // namespace rigidtouch::bench
