// What the benchmark harness's tests share: the shipped scenes by file name, the benchmark's time
// step, and the tool's acceleration before contact.
#pragma once

#include <string>

#include "bench/scene.h"

namespace rigidtouch::bench {

/// The shipped scene scenes/`file`, named after its file.
inline Scene SceneFor(const std::string& file) {
  Scene scene;
  scene.name = file;
  scene.mjcf_path = std::string(RIGIDTOUCH_SCENES) + "/" + file;
  return scene;
}

/// The benchmark's time step [s].
inline constexpr double kH = 0.001;
/// The tool's acceleration before contact [m/s^2]: gravity plus the 2 N push on 0.1 kg.
inline constexpr double kToolAcceleration = 9.81 + 2.0 / 0.1;

}  // namespace rigidtouch::bench
