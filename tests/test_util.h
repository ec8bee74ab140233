// Helpers shared by the tests: scene paths, temporary files, CPUs.
#pragma once

#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace rigidtouch::test {

/// The highest-numbered CPU this process may run on when it may run on two or more; -1 otherwise
/// (a test that pins a loop to one CPU and its helpers to the others then has nothing to check).
inline int LastCpuOfSeveral() {
  cpu_set_t allowed;
  if (sched_getaffinity(0, sizeof(allowed), &allowed) != 0 || CPU_COUNT(&allowed) < 2) return -1;
  int last = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &allowed)) last = c;
  }
  return last;
}

/// `x` with every digit a double holds (%.17g), for scenes written from numbers.
inline std::string ExactNumber(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

/// Path of a scene shipped for the tests (tests/scenes/NAME).
inline std::string TestScene(const std::string& name) {
  return std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/" + name;
}

/// The test process's temporary directory; removed, with everything in it, when the process
/// exits normally (a crashed test leaves it behind for inspection).
inline std::filesystem::path TempDir() {
  struct Owner {
    std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("rigidtouch_test_" + std::to_string(::getpid()));
    ~Owner() {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  };
  static const Owner owner;
  return owner.dir;
}

/// Writes `text` to a fresh file in the test's temporary directory and returns its path.
inline std::string WriteTempFile(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = TempDir();
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

/// MJCF text of a pile of boxes (half-size 25 mm, 0.1 kg) on an nx x ny x nz grid with spacing
/// `pitch`, a floor, and the tool sphere (5 mm, 0.1 kg) at height tool_z.
inline std::string PileXml(int nx, int ny, int nz, double pitch, double tool_z) {
  std::string xml =
      "<mujoco model=\"pile\"><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\" friction=\"0.5\"/>";
  int n = 0;
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x) {
        xml += "<body name=\"box_" + std::to_string(n++) + "\" pos=\"" +
               std::to_string(-0.1 + pitch * x) + " " + std::to_string(-0.1 + pitch * y) + " " +
               std::to_string(0.025 + pitch * z) +
               "\"><freejoint/><geom type=\"box\" size=\"0.025 0.025 0.025\" mass=\"0.1\"/></body>";
      }
    }
  }
  xml += "<body name=\"tool\" pos=\"0 0 " + std::to_string(tool_z) +
         "\"><freejoint/><geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body>";
  xml += "</worldbody></mujoco>";
  return xml;
}

}  // namespace rigidtouch::test
