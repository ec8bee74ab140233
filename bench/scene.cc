#include "bench/scene.h"

#include <algorithm>
#include <cmath>
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
