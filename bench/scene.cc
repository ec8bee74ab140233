#include "bench/scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rigidtouch::bench {

PeerSettings ParsePeerSettings(const std::string& text) {
  if (text == "defaults") return PeerSettings::kDefaults;
  if (text == "stacking") return PeerSettings::kStacking;
  throw Error("peer settings '" + text + "' are unknown: use defaults or stacking");
}

const char* PeerSettingsName(PeerSettings settings) {
  return settings == PeerSettings::kDefaults ? "defaults" : "stacking";
}

std::string DefaultScenesDir() {
  return RIGIDTOUCH_SCENES;
}

std::vector<Scene> BenchmarkScenes(const std::string& scenes_dir, double scale) {
  if (!(scale > 0.0 && scale <= 1.0)) {
    throw Error("benchmark scale " + std::to_string(scale) + " is out of range (0, 1]");
  }
  const auto scaled = [scale](int steps) {
    return std::max(10, static_cast<int>(std::lround(steps * scale)));
  };
  std::vector<Scene> scenes;

  Scene tap;
  tap.name = "tap";
  tap.mjcf_path = scenes_dir + "/tap.xml";
  tap.measured_steps = scaled(20000);
  scenes.push_back(tap);

  Scene stack;
  stack.name = "stack";
  stack.mjcf_path = scenes_dir + "/stack.xml";
  stack.measured_steps = scaled(20000);
  // the top box, over 10 s from the settled snapshot
  stack.watch_body = "box_9";
  stack.watch_steps = 10000;
  stack.max_watch_displacement_m = 0.001;
  scenes.push_back(stack);

  Scene pile;
  pile.name = "pile";
  pile.mjcf_path = scenes_dir + "/pile.xml";
  pile.measured_steps = scaled(3000);
  pile.max_penetration_m = 0.001;
  scenes.push_back(pile);

  Scene strike = pile;
  strike.name = "pile-strike";
  strike.kind = SceneKind::kStrike;
  strike.warmup_steps = 3000;  // settle 3 s
  strike.measured_steps = scaled(1000);
  // top box of the centre column: grid (2, 2, 3), index x + 5 y + 25 z
  strike.strike_target = "box_87";
  scenes.push_back(strike);
  return scenes;
}

namespace {

// the tool's weight, which the user carries while pushing sideways (0.1 kg)
constexpr double kToolWeight_N = 0.1 * 9.81;

Scene ArticulatedScene(const std::string& name, const std::string& path, const Vec3& force_N,
                       int measured_steps) {
  Scene scene;
  scene.name = name;
  scene.mjcf_path = path;
  scene.tool_force_N = force_N;
  scene.measured_steps = measured_steps;
  // a 2 N push: 0.1 mm in rigidtouch's 2e4 N/m tool contact, 0.3 mm in MuJoCo's tap scene
  scene.max_tool_penetration_m = 0.001;
  return scene;
}

}  // namespace

std::vector<Scene> ArticulatedBenchmarkScenes(const std::string& scenes_dir, double scale) {
  if (!(scale > 0.0 && scale <= 1.0)) {
    throw Error("benchmark scale " + std::to_string(scale) + " is out of range (0, 1]");
  }
  const int steps = std::max(10, static_cast<int>(std::lround(5000 * scale)));
  constexpr double kPi = 3.14159265358979323846;
  std::vector<Scene> scenes;
  // the panel's -y face pushed towards +y, which turns the door into its stop at 0 rad
  Scene door =
      ArticulatedScene("door", scenes_dir + "/door.xml", Vec3(0.0, 2.0, kToolWeight_N), steps);
  door.limit_joint = "hinge";
  door.limit_lo = -100.0 * kPi / 180.0;
  door.limit_hi = 0.0;
  door.max_limit_overshoot = 0.005;  // rad: 3 mm at the panel's far edge
  scenes.push_back(door);
  // the front pushed towards -x: the drawer slides home against its back stop at 0 m
  Scene drawer =
      ArticulatedScene("drawer", scenes_dir + "/drawer.xml", Vec3(-2.0, 0.0, kToolWeight_N), steps);
  drawer.limit_joint = "rail";
  drawer.limit_lo = 0.0;
  drawer.limit_hi = 0.3;
  drawer.max_limit_overshoot = 0.001;  // m
  scenes.push_back(drawer);
  // the knob pressed down against the spring (3.8 N m at the lower stop, 0.35 rad): 15 N at
  // 0.263 m, with the tool's weight, hold it there with 0.5 N m to spare
  Scene lever = ArticulatedScene("lever", scenes_dir + "/lever.xml", Vec3(0.0, 0.0, -15.0), steps);
  lever.limit_joint = "pivot";
  lever.limit_lo = -0.35;
  lever.limit_hi = 0.35;
  lever.max_limit_overshoot = 0.005;  // rad: 1.5 mm at the knob
  // 16 N: 0.8 mm in rigidtouch's 2e4 N/m tool contact
  lever.max_tool_penetration_m = 0.0015;
  scenes.push_back(lever);
  // the forearm pushed down from above; the servos hold it within a few milliradians of its pose,
  // so the shoulder's limit (2 rad) is checked but not reached
  Scene arm = ArticulatedScene("arm", scenes_dir + "/arm.xml", Vec3(0.0, 0.0, -2.0), steps);
  arm.limit_joint = "shoulder";
  arm.limit_lo = -2.0;
  arm.limit_hi = 2.0;
  arm.max_limit_overshoot = 0.005;
  scenes.push_back(arm);
  return scenes;
}

Scene HumanoidBenchmarkScene(const std::string& wrapper_path, double scale) {
  if (!(scale > 0.0 && scale <= 1.0)) {
    throw Error("benchmark scale " + std::to_string(scale) + " is out of range (0, 1]");
  }
  Scene humanoid = ArticulatedScene("humanoid", wrapper_path, Vec3(0.0, 0.0, -2.0),
                                    std::max(10, static_cast<int>(std::lround(3000 * scale))));
  humanoid.warmup_steps = 3000;  // the lying humanoid settles on the floor
  return humanoid;
}

std::string WriteHumanoidWrapper(const std::string& humanoid_path, const std::string& out_dir,
                                 const std::string& flag) {
  std::ifstream in(humanoid_path, std::ios::binary);
  if (humanoid_path.empty() || !in || std::filesystem::is_directory(humanoid_path)) {
    throw Error("--" + flag + "=" + humanoid_path +
                ": not a readable file; give MuJoCo's model/humanoid/humanoid.xml (from "
                "https://github.com/deepmind/mujoco, tag 2.2.2 or later)");
  }
  std::ostringstream text;
  text << in.rdbuf();
  // MuJoCo 2.2's <include> takes a path relative to the including file only, so the model is
  // copied beside the wrapper (it uses no asset files)
  std::filesystem::create_directories(out_dir);
  const std::string included = out_dir + "/humanoid_included.xml";
  std::ofstream(included, std::ios::binary) << text.str();
  const std::string wrapper = out_dir + "/humanoid_tool.xml";
  std::ofstream out(wrapper);
  // the humanoid on its back (its x axis up: a rotation of -90 degrees about y), the chest's
  // front at z = 0.19 m; the tool 10 mm above it; 21 hinges at 0
  out << "<mujoco model=\"humanoid with a tool\">\n"
         "  <include file=\"humanoid_included.xml\"/>\n"
         "  <option timestep=\"0.001\"/>\n"
         "  <worldbody>\n"
         "    <body name=\"tool\" pos=\"0 0 0.205\">\n"
         "      <freejoint/>\n"
         "      <geom name=\"tool\" type=\"sphere\" size=\"0.005\" mass=\"0.1\"/>\n"
         "    </body>\n"
         "  </worldbody>\n"
         "  <keyframe>\n"
         "    <key name=\"initial\" qpos=\"0 0 0.12 0.70710678 0 -0.70710678 0";
  for (int i = 0; i < 21; ++i) out << " 0";
  out << "  0 0 0.205 1 0 0 0\"/>\n"
         "  </keyframe>\n"
         "</mujoco>\n";
  if (!out) throw Error("could not write " + wrapper);
  return wrapper;
}

std::vector<Scene> LargeBenchmarkScenes(const std::string& scenes_dir, double scale) {
  if (!(scale > 0.0 && scale <= 1.0)) {
    throw Error("benchmark scale " + std::to_string(scale) + " is out of range (0, 1]");
  }
  std::vector<Scene> scenes;
  // the pile's box and spacing on 10 x 10 grids (scenes/make_pile.py); fewer measured steps, as
  // the peers take 5-20 ms (Bullet) and more (MuJoCo) per step
  for (const auto& [name, steps] :
       {std::pair<const char*, int>{"pile400", 1000}, std::pair<const char*, int>{"pile1000", 500},
        std::pair<const char*, int>{"pile2000", 300}}) {
    Scene pile;
    pile.name = name;
    pile.mjcf_path = scenes_dir + "/" + name + ".xml";
    pile.measured_steps = std::max(10, static_cast<int>(std::lround(steps * scale)));
    pile.max_penetration_m = 0.001;
    scenes.push_back(pile);
  }
  return scenes;
}

}  // namespace rigidtouch::bench
