// MuJoCo peer: mj_step on the scene's MJCF with every solver and contact setting left at the
// values the file gives (MuJoCo's defaults for the benchmark scenes).
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
  Vec3 tool_force_N_ = Vec3::Zero();
};

/// Makes an unloaded MuJoCo engine.
std::unique_ptr<Engine> MakeMujocoEngine();

}  // namespace rigidtouch::bench
