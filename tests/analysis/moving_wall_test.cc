// Tapping a link of an articulated tree (a moving wall, docs/articulated.md): the wall found on
// the link, the door stop's three renderings passive at the port, and the damped swing of a door
// against its closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "analysis/tap_experiment.h"
#include "test_util.h"

namespace rigidtouch::analysis {
namespace {

std::string Scene(const std::string& path) {
  return std::string(RIGIDTOUCH_SOURCE_DIR) + "/" + path;
}

// the shipped door tapped on its panel (from -y, towards its stop) at `speed` on `preset`
TapExperimentConfig DoorConfig(RendererKind limit, const std::string& preset, double speed) {
  TapExperimentConfig c;
  c.scene_path = Scene("scenes/door.xml");
  c.wall_geom = "panel";
  c.device_preset = preset;
  c.load.render.renderer = RendererKind::kTrain;
  c.load.render.joint_limit_renderer = limit;
  c.script.approach_speed_mps = speed;
  c.script.taps = 1;
  c.script.dwell_s = 0.2;
  return c;
}

// the panel's face nearest the scene's tool (4 cm in front of its -y face, 0.6 m from the hinge)
// is the wall: the point under the tool on that face, the normal -y; the joint is the hinge
TEST(MovingWallTest, ALinkGeomIsAMovingWallFacingTheTool) {
  LoadOptions o;
  const std::string scene = Scene("scenes/door.xml");
  const Model model = LoadModel(scene, o);
  const Wall wall = FindWall(model, scene, "panel");
  EXPECT_TRUE(wall.moving());
  EXPECT_NEAR((wall.normal - Vec3(0.0, -1.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((wall.point_m - Vec3(0.6, -0.02, 1.0)).norm(), 0.0, 1e-12);
  ASSERT_GE(wall.joint, 0);
  EXPECT_EQ(model.trees[wall.tree].joints[wall.joint].name, "hinge");
  // a static wall stays one
  EXPECT_FALSE(FindWall(model, scene, "jamb").moving());
}

// the door pushed into its stop: whichever way the stop renders (penalty, one impulse, a train),
// the device gives the hand no energy over the tap (energy to user = sum F_k . (x_{k+1} - x_k)
// <= 0), every displayed force is finite and within the device's limit, the stop holds (the door
// turns less than 1 degree past it), every impulse of the tool's group (door included) takes
// kinetic energy out, and the approach speed at onset is the tool's relative to the resting door
// (the requested speed within 10 %: the hand's spring and the encoder)
TEST(MovingWallTest, TheDoorStopIsPassiveAtThePortWhateverItsRenderer) {
  for (RendererKind limit :
       {RendererKind::kPenalty, RendererKind::kImpulse, RendererKind::kTrain}) {
    for (const char* preset : {"touch", "omega3"}) {
      const TapRun run = RunTapExperiment(DoorConfig(limit, preset, 0.2));
      const std::string what =
          std::string(preset) + ", limit renderer " + std::to_string(static_cast<int>(limit));
      ASSERT_EQ(run.taps.size(), 1u) << what;
      ASSERT_EQ(run.joint_taps.size(), 1u) << what;
      const TapMetrics& m = run.taps[0];
      ASSERT_TRUE(m.contact) << what;
      EXPECT_LE(m.energy_to_user_J, 0.0) << what;
      EXPECT_NEAR(m.approach_speed_mps, 0.2, 0.02) << what;
      EXPECT_LT(run.joint_taps[0].max_position, 1.0 * M_PI / 180.0) << what;
      int impulse_ticks = 0;
      for (const TraceSample& s : run.trace) {
        ASSERT_TRUE(s.device_force_N.allFinite()) << what;
        ASSERT_LE(s.device_force_N.norm(), run.device.max_force_N + 1e-9) << what;
        // every impulse of the tool's group (the contact's and the stop's, with the door in the
        // group) leaves it no more kinetic energy than it had
        if (s.impulses > 0) {
          ++impulse_ticks;
          EXPECT_LE(s.kinetic_energy_after_J, s.kinetic_energy_before_J * (1.0 + 1e-12))
              << what << " at " << s.time_s << " s";
        }
      }
      EXPECT_GT(impulse_ticks, 0) << what;
    }
  }
}

// A door at rest with hinge damping c and no spring, given angular impulse L = (r x P) . axis,
// comes to rest again having turned by L / c: integrating I dw/dt = tau - c w from rest to rest,
// c (theta_end - theta_start) = integral of tau dt = L, whatever the tap's time course (for an
// instantaneous tap, I w0 = L and the swing is I w0 / c). Measured on the test door tapped on its
// +y face (it opens away from its stop), L summed from the tool's contact impulses at their
// points (J^T P), with the door's inertia I = 3.2584 kg m^2 (the panel about the hinge plus the
// armature, the scene's comment). At the run's end the door still turns a little: what is left
// of its swing, I w_end / c, is asserted under 1 % of it, and the swing so far is within 1 % of
// L / c; with that remainder, the momentum balance c (theta_end - theta_start) + I w_end = L
// holds to 1e-6 (the step's damper is backward Euler: the sum of c w h over the ticks is exactly
// c times the turned angle). Were the damping ignored, the door would keep turning at L / I and
// both would fail. The onset tick checks the inertia: the single impulse changes the door's
// velocity by its joint impulse over I + h c (the damper is implicit in the solve: 1.2 % here;
// without the armature I would be 18 % smaller), within 0.1 %.
TEST(MovingWallTest, ATappedDoorSwingsByItsAngularImpulseOverTheDamping) {
  TapExperimentConfig c;
  c.scene_path = Scene("tests/scenes/articulated/door_swing.xml");
  c.wall_geom = "panel";
  c.device_preset = "omega3";
  c.load.render.renderer = RendererKind::kImpulse;
  c.script.approach_speed_mps = 0.2;
  c.script.taps = 1;
  const TapRun run = RunTapExperiment(c);
  ASSERT_TRUE(run.wall.moving());
  EXPECT_NEAR((run.wall.normal - Vec3(0.0, 1.0, 0.0)).norm(), 0.0, 1e-12);
  const double damping = 40.0, h = 1e-3;
  EXPECT_NEAR(run.joint_damping, damping, 1e-12);
  const double inertia = 12.0 * (0.8 * 0.8 + 0.04 * 0.04) / 12.0 + 12.0 * 0.42 * 0.42 + 0.5;
  EXPECT_NEAR(run.joint_inertia, inertia, 1e-9 * inertia);
  ASSERT_EQ(run.joint_taps.size(), 1u);
  const JointMotion& j = run.joint_taps[0];
  const double swing = j.position_at_end - j.position_at_start;
  ASSERT_LT(swing, -1e-3);  // it opened (negative angles), by more than a milliradian
  const double remainder = inertia * j.velocity_at_end / damping;
  EXPECT_LT(std::abs(remainder), 0.01 * std::abs(swing));
  EXPECT_NEAR(swing, j.impulse / damping, 0.01 * std::abs(swing))
      << "swing " << swing << " rad, L / c " << j.impulse / damping << " rad";
  EXPECT_NEAR(damping * swing + inertia * j.velocity_at_end, j.impulse, 1e-6 * std::abs(j.impulse));
  // the onset tick: the single impulse (and the tick's penalty) sets the door moving
  std::size_t onset = 0;
  while (onset < run.trace.size() && run.trace[onset].impulses == 0) ++onset;
  ASSERT_LT(onset, run.trace.size());
  ASSERT_GT(onset, 0u);
  const WallSample& w = run.wall_trace[onset];
  ASSERT_LT(w.joint_impulse, 0.0);
  const double dw = w.joint_velocity - run.wall_trace[onset - 1].joint_velocity;
  const double expected = w.joint_impulse / (inertia + h * damping);
  EXPECT_NEAR(dw, expected, 1e-3 * std::abs(expected));
}

}  // namespace
}  // namespace rigidtouch::analysis
