// `rigidtouch view` headless under Xvfb with Mesa's software OpenGL: the screenshot shows the
// scene (the floor's grid, the tool), the tool where the scripted cursor took it, and the scope's
// impulsive-force trace with a train's spikes during a tap (flat for penalty rendering). The
// colours are the viewer's fixed ones (src/view/viewer.cc), drawn without anti-aliasing.
#include <gtest/gtest.h>
#include <stb_image.h>

#include <signal.h>

#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/cli_util.h"
#include "io/device_record.h"

namespace rigidtouch::test {
namespace {

// whether an X server can be started here (Xvfb through xvfb-run), asked once
bool HaveXvfb() {
  static const bool have =
      std::system("command -v xvfb-run >/dev/null 2>&1") == 0 &&
      std::system("xvfb-run -a -s '-screen 0 64x64x24' true >/dev/null 2>&1") == 0;
  return have;
}

struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  bool Is(int x, int y, int r, int g, int b) const {
    const unsigned char* p = &rgb[3 * (static_cast<std::size_t>(y) * w + x)];
    return p[0] == r && p[1] == g && p[2] == b;
  }
};

Image Load(const std::string& path) {
  Image im;
  int n = 0;
  unsigned char* data = stbi_load(path.c_str(), &im.w, &im.h, &n, 3);
  if (data != nullptr) {
    im.rgb.assign(data, data + 3 * static_cast<std::size_t>(im.w) * im.h);
    stbi_image_free(data);
  }
  return im;
}

struct Blob {
  long count = 0;
  double cx = 0.0, cy = 0.0;
  int top = 1 << 30, bottom = -1;
};

Blob Find(const Image& im, int r, int g, int b, int x0 = 0) {
  Blob out;
  for (int y = 0; y < im.h; ++y) {
    for (int x = x0; x < im.w; ++x) {
      if (!im.Is(x, y, r, g, b)) continue;
      ++out.count;
      out.cx += x;
      out.cy += y;
      out.top = std::min(out.top, y);
      out.bottom = std::max(out.bottom, y);
    }
  }
  if (out.count > 0) {
    out.cx /= out.count;
    out.cy /= out.count;
  }
  return out;
}

// runs the viewer for 60 frames at 60 Hz off-screen and loads the last one
Image View(const std::string& args, const std::string& png) {
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x720x24' " + std::string(RIGIDTOUCH_CLI) +
                          " view --frames 60 --screenshot " + png + " " + args + " --json >" + png +
                          ".json 2>" + png + ".err";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(status, 0) << cmd << "\n" << ReadAll(png + ".err");
  return Load(png);
}

constexpr int kTool[3] = {255, 140, 0}, kFloor[3] = {90, 90, 90}, kImpulsive[3] = {255, 0, 0};

TEST(ViewCliTest, SceneIsDrawnAndTheToolFollowsTheScriptedMouse) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_mouse");
  // the cursor stays at the centre, or moves 300 px right over the 60 frames
  const Image still = View("--mouse-path '640,360 640,360'", (dir / "still.png").string());
  const Image moved = View("--mouse-path '640,360 940,360'", (dir / "moved.png").string());
  ASSERT_EQ(still.w, 1280);
  ASSERT_EQ(moved.w, 1280);
  const Blob floor = Find(still, kFloor[0], kFloor[1], kFloor[2], 480);  // right of the panel
  EXPECT_GT(floor.count, 5000);                                          // the grid
  const Blob a = Find(still, kTool[0], kTool[1], kTool[2], 480);
  const Blob b = Find(moved, kTool[0], kTool[1], kTool[2], 480);
  ASSERT_GT(a.count, 200);  // the 5 mm sphere seen from 0.2 m: a disc of about 20 px radius
  ASSERT_GT(b.count, 200);
  EXPECT_NEAR(a.cx, 640.0, 5.0);  // under the cursor
  EXPECT_NEAR(a.cy, 360.0, 5.0);
  // the handle lags the cursor by 20 ms (about one frame): nearly all of the 300 px
  EXPECT_GT(b.cx - a.cx, 250.0);
  EXPECT_LT(b.cx - a.cx, 310.0);
  EXPECT_NEAR(b.cy, a.cy, 5.0);
  std::filesystem::remove_all(dir);
}

TEST(ViewCliTest, ScopeShowsTheTrainsSpikesDuringATap) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_scope");
  // the tap starts half way, so its contact is inside the scope's last 0.5 s at the end
  const std::string tap = "--mouse-path '640,360 640,360' --tap-at-frame 30 ";
  const Image train = View(tap + "--renderer train", (dir / "train.png").string());
  const Image penalty = View(tap + "--renderer penalty", (dir / "penalty.png").string());
  const auto jt = nlohmann::json::parse(ReadAll(dir / "train.png.json"));
  ASSERT_GT(jt["impulses"].get<long>(), 0) << jt.dump();
  // the impulsive trace: spikes up the plot for the train, a flat line at zero for penalty
  const Blob spikes = Find(train, kImpulsive[0], kImpulsive[1], kImpulsive[2]);
  const Blob flat = Find(penalty, kImpulsive[0], kImpulsive[1], kImpulsive[2]);
  ASSERT_GT(spikes.count, 0);
  ASSERT_GT(flat.count, 0);
  EXPECT_GT(spikes.bottom - spikes.top, 30);  // of the plot's 70 px
  EXPECT_LE(flat.bottom - flat.top, 1);
  std::filesystem::remove_all(dir);
}

nlohmann::json ViewJson(const std::string& args) {
  const CliResult r = RunCli(args + " --json", "xvfb-run -a");
  EXPECT_EQ(r.exit_code, 0) << args << ": " << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
}

// the renderer switches between ticks, and only while the tool touches nothing: asked for before a
// tap, the tap is rendered by penalty alone; asked for during the tap's contact, the switch waits
// and the train renders the whole contact (its 25 impulses: 100 ms at 250 Hz)
TEST(ViewCliTest, RendererSwitchesOnlyWithoutContact) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const std::string tap = "view --frames 75 --tap-at-frame 20 --mouse-path '640,360 640,360' ";
  const auto dir = TempDir("view_switch");
  const std::string rec = (dir / "rec.csv").string();
  const auto before = ViewJson(tap + "--switch-at-frame 5 --record " + rec);
  EXPECT_EQ(before["renderer"], "penalty");
  EXPECT_EQ(before["renderer_switches"], 1);
  EXPECT_EQ(before["impulses"], 0);
  // the record runs on over the loop's restart: one row per tick of the session, in order
  EXPECT_EQ(static_cast<long>(io::ReadRecord(rec).samples.size()), before["ticks"].get<long>());
  std::filesystem::remove_all(dir);
  const auto during = ViewJson(tap + "--switch-at-contact");
  EXPECT_EQ(during["renderer"], "penalty");
  EXPECT_EQ(during["renderer_switches"], 1);
  EXPECT_GT(during["renderer_switch_wait_frames"].get<int>(), 0);
  EXPECT_EQ(during["impulses"], 25);
}

// the viewer drives the UDP bridge as serve does: device-sim's simulated hand taps, the viewer's
// loop renders the contacts and draws them
TEST(ViewCliTest, DrivesTheUdpBridge) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_udp");
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const pid_t sim = Spawn("device-sim --listen " + addr +
                              " --preset touch --rate 1000 --taps 20 --speed 0.2 --duration 20",
                          (dir / "sim.json").string());
  const auto j = ViewJson("view --device " + addr + " --startup-timeout 5 --frames 120");
  ::kill(sim, SIGTERM);
  Wait(sim);
  EXPECT_EQ(j["device"], addr);
  EXPECT_GT(j["ticks"].get<long>(), 500);
  EXPECT_GT(j["max_force_N"].get<double>(), 1.0);  // the hand reached the wall
  EXPECT_LE(j["max_force_N"].get<double>(), 3.3);  // the Touch's limit
  EXPECT_TRUE(j["finite"].get<bool>());
  std::filesystem::remove_all(dir);
}

TEST(ViewCliTest, BadArgumentsAreRefused) {
  for (const std::string args :
       {"view --device tcp://x --frames 1", "view --frames 1 --key k", "view --screenshot a.png",
        "view --device sim --tap-at-frame 3", "view --device mouse --taps 3 --frames 1",
        "view --frames 2 --mouse-path '1,2 x'"}) {
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("rigidtouch: error:"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace rigidtouch::test
