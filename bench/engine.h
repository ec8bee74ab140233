// The interface every benchmarked engine implements (rigidtouch, MuJoCo, Bullet), and a registry
// so that adding an engine touches only its own file.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bench/scene.h"
#include "rigidtouch/types.h"

namespace rigidtouch::bench {

/// One physics engine running one benchmark scene. Load() is the only call that may throw
/// (`rigidtouch::Error` on bad scene files); Step() is the measured call. Every other query is
/// made outside the timed region, so it may be slow (name look-ups, loops over contacts).
class Engine {
 public:
  virtual ~Engine() = default;

  /// Returns the engine's short name, used in benchmark names and table columns.
  virtual std::string_view Name() const = 0;

  /// Builds the engine's world from the scene's MJCF file; the body `scene.tool_body` receives
  /// `scene.tool_force_N` (world frame, at its centre of mass) on every Step().
  virtual void Load(const Scene& scene) = 0;

  /// Advances the world by one time step (the MJCF timestep).
  virtual void Step() = 0;

  /// Returns the number of contact points the last Step() handed to the solver.
  virtual int ContactCount() const = 0;

  /// Returns the number of those contact points that involve the named body.
  virtual int BodyContactCount(std::string_view body) const = 0;

  /// Returns the deepest penetration among the last Step()'s contact points, in metres (0 when
  /// no point penetrates).
  virtual double DeepestPenetration_m() const = 0;

  /// Returns the deepest penetration among the last Step()'s contact points that involve the named
  /// body, in metres (0 when none penetrates). The default throws `rigidtouch::Error`: an engine
  /// without it cannot run a scene with a tool-contact gate.
  virtual double BodyPenetration_m(std::string_view body) const;

  /// Returns the position of the named hinge [rad] or slide [m] joint, in MuJoCo's coordinates.
  /// The default throws `rigidtouch::Error`: an engine without it cannot run a joint-limit gate.
  virtual double JointPosition(std::string_view joint) const;

  /// Returns the position of the named body's frame origin in the world frame.
  virtual Vec3 BodyPosition(std::string_view body) const = 0;

  /// Returns the orientation of the named body's frame relative to the world frame.
  virtual Quat BodyOrientation(std::string_view body) const = 0;

  /// Places the named free body: frame origin at `position_m` (world), orientation identity,
  /// linear velocity `velocity_mps` (world), angular velocity zero.
  virtual void SetBodyMotion(std::string_view body, const Vec3& position_m,
                             const Vec3& velocity_mps) = 0;

  /// Stores the whole dynamic state, to be brought back by RestoreSnapshot().
  virtual void SaveSnapshot() = 0;

  /// Brings back the state stored by the last SaveSnapshot().
  virtual void RestoreSnapshot() = 0;

  /// Returns true when every position and velocity is finite.
  virtual bool StateIsFinite() const = 0;

  /// Returns how many warnings the engine has raised since Load() (e.g. MuJoCo's full contact
  /// buffer); 0 for engines without such counters.
  virtual long WarningCount() const = 0;

  /// Returns one line describing how the loaded engine is configured (version, solver,
  /// iterations, precision), printed with the results so the comparison can be checked.
  virtual std::string Configuration() const = 0;
};

/// The overrides of Engine that a peer engine (bench/bullet_engine.h, bench/mujoco_engine.h)
/// defines in its own .cc file: the one declaration of them, so that a call added to Engine is
/// added here once. Name() and WarningCount() stay in each class.
#define RIGIDTOUCH_PEER_ENGINE_OVERRIDES                                                      \
  void Load(const Scene& scene) override;                                                     \
  void Step() override;                                                                       \
  int ContactCount() const override;                                                          \
  int BodyContactCount(std::string_view body) const override;                                 \
  double DeepestPenetration_m() const override;                                               \
  Vec3 BodyPosition(std::string_view body) const override;                                    \
  Quat BodyOrientation(std::string_view body) const override;                                 \
  void SetBodyMotion(std::string_view body, const Vec3& position_m, const Vec3& velocity_mps) \
      override;                                                                               \
  void SaveSnapshot() override;                                                               \
  void RestoreSnapshot() override;                                                            \
  bool StateIsFinite() const override;                                                        \
  double BodyPenetration_m(std::string_view body) const override;                             \
  double JointPosition(std::string_view joint) const override;                                \
  std::string Configuration() const override;

/// Makes a new, unloaded engine.
using EngineFactory = std::unique_ptr<Engine> (*)();

/// A registered engine: its name and factory.
struct EngineEntry {
  std::string name;
  EngineFactory make;
};

/// All registered engines: the reference engine first, then the peers by name.
std::vector<EngineEntry>& Engines();

/// Registers an engine at static-initialisation time: a file `bench/<name>_engine.cc` defines
/// `const EngineRegistrar kRegistrar{"<name>", &Make<Name>Engine};` and needs no other change.
struct EngineRegistrar {
  /// Adds the engine to Engines(), keeping its order.
  EngineRegistrar(std::string name, EngineFactory make);
};

/// The name of the reference engine whose time is divided by each peer's in the ratio table.
inline constexpr std::string_view kReferenceEngine = "rigidtouch";

}  // namespace rigidtouch::bench
