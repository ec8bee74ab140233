// The project's own scenes load without a warning: a newcomer's first runs print none.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

TEST(ShippedScenesTest, EveryShippedSceneLoadsWithoutAWarning) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(RIGIDTOUCH_SCENES)) {
    if (entry.path().extension() != ".xml") continue;
    ++scenes;
    ::testing::internal::CaptureStderr();
    const Model model = LoadModel(entry.path().string(), {});
    const std::string printed = ::testing::internal::GetCapturedStderr();
    // MuJoCo's own warnings are printed as the compiler gives them, the loader's are kept
    EXPECT_EQ(printed, "") << entry.path().filename();
    std::string warnings;
    for (const std::string& w : model.load_warnings) warnings += w + "\n";
    EXPECT_EQ(warnings, "") << entry.path().filename();
  }
  EXPECT_GE(scenes, 8);
}

}  // namespace
}  // namespace rigidtouch
