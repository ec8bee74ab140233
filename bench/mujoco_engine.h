// MuJoCo peer: mj_step on the scene's MJCF, either with every solver and contact setting at the
// values the file gives (MuJoCo's defaults for the benchmark scenes) or with the settings
// MuJoCo's documentation recommends against slip and penetration (PeerSettings::kStacking).
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>

#include "bench/engine.h"

namespace rigidtouch::bench {

/// Compiles an MJCF file with MuJoCo. Throws `rigidtouch::Error` naming the file and MuJoCo's
/// message when it does not load.
std::unique_ptr<mjModel, void (*)(mjModel*)> LoadMjcf(const std::string& path);

/// Returns the id of the named body. Throws `rigidtouch::Error` naming the file when absent.
int MjBodyId(const mjModel& model, std::string_view body, const std::string& path);

/// The solver and contact settings of PeerSettings::kStacking, each from MuJoCo's documentation
/// (docs/performance.md, "Peer configuration", gives the source of each). The time step is the
/// scene's: it is never changed.
struct MujocoStackingSettings {
  int solver = mjSOL_NEWTON;          ///< MuJoCo's default
  int iterations = 100;               ///< MuJoCo's default
  double tolerance = 1e-10;           ///< default 1e-8
  bool elliptic_cone = true;          ///< default pyramidal
  double impratio = 10;               ///< default 1
  int noslip_iterations = 0;          ///< MuJoCo's default (off); not needed for the gates
  double noslip_tolerance = 1e-6;     ///< MuJoCo's default
  double solref_timeconst_s = 0.005;  ///< default 0.02; at least two time steps (refsafe)
  double solref_dampratio = 1;        ///< MuJoCo's default
  double solimp_dmin = 0.99;          ///< default 0.9
  double solimp_dmax = 0.999;         ///< default 0.95
  double solimp_width_m = 0.001;      ///< MuJoCo's default
};

/// Writes `settings` into the compiled model: the solver options and every geom's solref and
/// solimp (the benchmark scenes set neither, so every contact gets these).
void ApplyMujocoStackingSettings(mjModel& model, const MujocoStackingSettings& settings);

/// The MuJoCo engine: the constant tool force goes through `xfrc_applied` every step.
class MujocoEngine final : public Engine {
 public:
  /// Makes an engine with nothing loaded.
  MujocoEngine();
  /// Frees everything the last Load() made.
  ~MujocoEngine() override;

  std::string_view Name() const override { return "mujoco"; }
  RIGIDTOUCH_PEER_ENGINE_OVERRIDES
  long WarningCount() const override;

  /// Returns the compiled model (null before Load()).
  const mjModel* model() const { return model_; }

 private:
  // address of the body's free joint in qpos (-1 if the body has none)
  int FreeQposAddress(int body_id) const;
  int BodyId(std::string_view body) const;

  std::string path_;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  mjData* snapshot_ = nullptr;
  int tool_id_ = -1;
  PeerSettings settings_ = PeerSettings::kDefaults;
  Vec3 tool_force_N_ = Vec3::Zero();
};

/// Makes an unloaded MuJoCo engine.
std::unique_ptr<Engine> MakeMujocoEngine();

}  // namespace rigidtouch::bench
