// `rigidtouch view` headless under Xvfb with Mesa's software OpenGL: the screenshot shows the
// scene (the floor's grid, the tool), the tool where the scripted cursor took it, and the scope's
// impulsive-force trace with a train's spikes during a tap (flat for penalty rendering); every geom
// type drawn as its own shape, nearer geoms hiding farther ones. The colours are the viewer's fixed
// ones (src/view/viewer.cc), drawn without anti-aliasing; a geom's pixels are its colour times a
// light factor in [0.45, 1] (src/view/scene_gl.cc), the floor's and the panel's exact.
#include <gtest/gtest.h>
#include <stb_image.h>

#include <signal.h>

#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "analysis/tap_experiment.h"
#include "cli/cli_util.h"
#include "io/device_record.h"
#include "view/camera.h"

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
  // the colour c times a light factor k in [0.4, 1], each channel to within 2 of rounding
  bool IsShadeOf(int x, int y, const int c[3]) const {
    if (x < 0 || y < 0 || x >= w || y >= h) return false;
    const unsigned char* p = &rgb[3 * (static_cast<std::size_t>(y) * w + x)];
    const int m = c[0] >= c[1] && c[0] >= c[2] ? 0 : c[1] >= c[2] ? 1 : 2;
    const double k = static_cast<double>(p[m]) / c[m];
    if (k < 0.4 || k > 1.0 + 1e-9) return false;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(p[i] - k * c[i]) > 2.0) return false;
    }
    return true;
  }
  // whether any pixel within `r` of (x, y) is a shade of c
  bool AnyShadeNear(int x, int y, const int c[3], int r = 2) const {
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        if (IsShadeOf(x + dx, y + dy, c)) return true;
      }
    }
    return false;
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

Blob Find(const Image& im, int r, int g, int b, int x0 = 0, bool shaded = false) {
  Blob out;
  const int c[3] = {r, g, b};
  for (int y = 0; y < im.h; ++y) {
    for (int x = x0; x < im.w; ++x) {
      if (!(shaded ? im.IsShadeOf(x, y, c) : im.Is(x, y, r, g, b))) continue;
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

// runs the viewer for `frames` frames at 60 Hz off-screen and loads the last one
Image View(const std::string& args, const std::string& png, int frames = 60) {
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x720x24' " + std::string(RIGIDTOUCH_CLI) +
                          " view --frames " + std::to_string(frames) + " --screenshot " + png +
                          " " + args + " --json >" + png + ".json 2>" + png + ".err";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(status, 0) << cmd << "\n" << ReadAll(png + ".err");
  return Load(png);
}

constexpr int kTool[3] = {255, 140, 0}, kFloor[3] = {90, 90, 90}, kImpulsive[3] = {255, 0, 0};
constexpr int kStatic[3] = {150, 160, 175};
// the tool's height cue (a line to the plane below it, a ring and a label), drawn over the scene
constexpr int kHeight[3] = {170, 150, 255};

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
  const Blob a = Find(still, kTool[0], kTool[1], kTool[2], 480, true);
  const Blob b = Find(moved, kTool[0], kTool[1], kTool[2], 480, true);
  ASSERT_GT(a.count, 200);  // the 5 mm sphere seen from 0.2 m: a disc of about 20 px radius
  ASSERT_GT(b.count, 200);
  EXPECT_NEAR(a.cx, 640.0, 5.0);  // under the cursor
  EXPECT_NEAR(a.cy, 360.0, 5.0);
  // the handle lags the cursor by 20 ms (about one frame): nearly all of the 300 px
  EXPECT_GT(b.cx - a.cx, 250.0);
  EXPECT_LT(b.cx - a.cx, 310.0);
  EXPECT_NEAR(b.cy, a.cy, 5.0);
  // the depth cue: the tool's height over the wall below it, a line, a ring and a label, below
  // the tool on the screen (the wall plane lies under it)
  const Blob cue = Find(still, kHeight[0], kHeight[1], kHeight[2], 480, true);
  EXPECT_GT(cue.count, 20);
  EXPECT_GT(cue.cy, a.cy);
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

// the model as `view` builds it (the tool's start above the wall, as for a tap) and the viewer's
// camera for it in a 1280 x 720 window
Model ViewModel(const std::string& scene) {
  analysis::TapExperimentConfig c;
  c.scene_path = scene;
  c.load.device.coupling = Coupling::kDirect;
  c.aim_below_tool = true;  // as the viewer does: the hand starts above what lies below the tool
  return analysis::PrepareTap(c).model;
}

struct SceneView {
  Model model;
  view::Camera cam;
  explicit SceneView(const std::string& scene)
      : model(ViewModel(scene)), cam(view::ViewerCamera(view::FrameScene(model), 1280, 720)) {}
  // the pixel of a point in the world, right of the panel (which covers x < 480)
  std::pair<int, int> Pixel(const Vec3& p) const {
    double x = 0.0, y = 0.0;
    EXPECT_TRUE(cam.Project(p, x, y));
    EXPECT_GT(x, 490.0);
    return {static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y))};
  }
  const GeomModel& Geom(const std::string& name) const {
    for (const GeomModel& g : model.geoms) {
      if (g.name == name) return g;
    }
    throw Error("no geom " + name);
  }
  // a point on the circle (in the view plane) of the geom's bounding sphere, at angle a from
  // the screen's right, and scaled by s: where the bounding sphere's outline was drawn at s = 1
  Vec3 OnBound(const GeomModel& g, double a_deg, double s) const {
    const double a = a_deg * std::numbers::pi / 180.0;
    return g.pos_B + s * g.rbound_m * (std::cos(a) * cam.r + std::sin(a) * cam.u);
  }
};

// a cylinder, an ellipsoid and a mesh (tests/scenes/view_shapes.xml) are drawn as their shapes: on
// the screen where the shape is, and not over the rest of their bounding sphere's disc (nor on its
// outline, where the viewer once drew them)
TEST(ViewCliTest, CylinderEllipsoidAndMeshAreDrawnAsTheirShapes) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_shapes");
  const std::string scene = std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/view_shapes.xml";
  const Image im = View("--scene " + scene, (dir / "shapes.png").string());
  ASSERT_EQ(im.w, 1280);
  const SceneView sv(scene);
  const auto on = [&](const Vec3& p, const char* what) {
    const auto [x, y] = sv.Pixel(p);
    EXPECT_TRUE(im.IsShadeOf(x, y, kStatic)) << what << " at " << x << "," << y;
  };
  const auto off = [&](const Vec3& p, const char* what) {
    const auto [x, y] = sv.Pixel(p);
    EXPECT_FALSE(im.AnyShadeNear(x, y, kStatic)) << what << " at " << x << "," << y;
  };
  // the cylinder: radius 4 mm, 8 cm long along x, centred at (0.05, 0, 0.05); its bounding sphere
  // has a radius of 4 cm
  const GeomModel& cyl = sv.Geom("cylinder");
  for (double t = -0.9; t <= 0.9 + 1e-9; t += 0.15) {
    on(cyl.pos_B + Vec3(0.04 * t, 0.0, 0.0), "cylinder's axis");
  }
  for (const double a : {45.0, 90.0, 135.0, 225.0, 270.0, 315.0}) {
    off(sv.OnBound(cyl, a, 0.6), "inside the cylinder's bounding disc, off its axis");
  }
  // (straight above and below, its bounding circle reaches the ellipsoid and the prism)
  for (const double a : {30.0, 45.0, 135.0, 150.0, 210.0, 225.0, 315.0, 330.0}) {
    off(sv.OnBound(cyl, a, 1.0), "the cylinder's bounding circle, off its axis");
  }
  // the ellipsoid: half-axes 30, 8, 8 mm at (0.05, 0, 0.1)
  const GeomModel& ell = sv.Geom("ellipsoid");
  for (const double x : {-0.024, -0.012, 0.0, 0.012, 0.024})
    on(ell.pos_B + Vec3(x, 0, 0), "ellipsoid");
  for (const double a : {45.0, 90.0, 135.0, 225.0, 270.0, 315.0}) {
    off(sv.OnBound(ell, a, 0.6), "inside the ellipsoid's bounding disc, off the ellipsoid");
    off(sv.OnBound(ell, a, 1.0), "the ellipsoid's bounding circle, off the ellipsoid");
  }
  // the prism: a triangle 6 cm wide and 3 cm high (apex up) in the x-z plane, 6 mm thick, its
  // base's centre at (0.05, 0, -0.015); the mesh's centre (pos_B) is the triangle's centroid
  const GeomModel& prism = sv.Geom("prism");
  const Vec3 base(0.05, 0.0, -0.015);
  for (const Vec3& d : {Vec3(0, 0, 0.01), Vec3(-0.02, 0, 0.004), Vec3(0.02, 0, 0.004),
                        Vec3(0, 0, 0.025), Vec3(0, 0, 0.002)}) {
    on(base + d, "prism");
  }
  // over the triangle's slopes: the corners of its bounding square above the base
  for (const double x : {-0.025, 0.025}) off(base + Vec3(x, 0, 0.027), "beside the prism's apex");
  for (const double a : {45.0, 135.0})
    off(sv.OnBound(prism, a, 1.0), "the prism's bounding circle");
  std::filesystem::remove_all(dir);
}

// a nearer geom hides a farther one wherever they overlap on the screen, whatever the order they
// are drawn in: tests/scenes/view_depth.xml puts a static box (drawn first) in front of the
// tool's larger box
TEST(ViewCliTest, NearerBoxHidesTheOneBehind) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_depth");
  const std::string scene = std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/view_depth.xml";
  const Image im = View("--scene " + scene, (dir / "depth.png").string());
  ASSERT_EQ(im.w, 1280);
  const SceneView sv(scene);
  // the front box's front face (y = -0.025, x in [-0.02, 0.02], z in [0.01, 0.05]) on the screen,
  // 3 px inside its edges
  const auto [left_top, top] = sv.Pixel(Vec3(-0.02, -0.025, 0.05));
  const auto [right_top, top2] = sv.Pixel(Vec3(0.02, -0.025, 0.05));
  const auto [left_bottom, bottom] = sv.Pixel(Vec3(-0.02, -0.025, 0.01));
  const auto [right_bottom, bottom2] = sv.Pixel(Vec3(0.02, -0.025, 0.01));
  const int x0 = std::max(left_top, left_bottom) + 3, x1 = std::min(right_top, right_bottom) - 3;
  const int y0 = std::max(top, top2) + 3, y1 = std::min(bottom, bottom2) - 3;
  ASSERT_GT(x1 - x0, 50);
  ASSERT_GT(y1 - y0, 50);
  long front = 0, back = 0, cue = 0, n = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      ++n;
      front += im.IsShadeOf(x, y, kStatic) ? 1 : 0;
      back += im.IsShadeOf(x, y, kTool) ? 1 : 0;
      // the tool's height cue is an overlay: its thin line crosses the box, blended into it
      cue += !im.IsShadeOf(x, y, kStatic) && im.AnyShadeNear(x, y, kHeight, 2) ? 1 : 0;
    }
  }
  EXPECT_EQ(back, 0) << "of " << n << " pixels";  // the tool's box is behind all of it
  EXPECT_GE(front + cue, n - n / 50);  // the cue's blended edge pixels are neither colour
  EXPECT_LT(cue, n / 20);              // a thin line, not a hole
  // and the tool's box shows where nothing is in front of it: above the front box
  const auto [ax, ay] = sv.Pixel(Vec3(0.0, 0.025, 0.055));
  EXPECT_TRUE(im.IsShadeOf(ax, ay, kTool)) << ax << "," << ay;
  std::filesystem::remove_all(dir);
}

// the links of a kinematic tree are drawn where the tree holds them, in the link colour, as their
// own shapes (the door's box panel, the arm's capsules), and the viewer reports every joint; they
// were once drawn at their link-frame offsets from the world's origin, in the static colour
constexpr int kLink[3] = {60, 170, 110};

TEST(ViewCliTest, TreeLinksAreDrawnWhereTheirJointsHoldThem) {
  if (!HaveXvfb())
    GTEST_SKIP()
        << "no X server can be started (xvfb-run missing or failing; apt-get install xvfb xauth)";
  const auto dir = TempDir("view_trees");
  const std::string door = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/door.xml";
  const std::string png = (dir / "door.png").string();
  const Image im = View("--scene " + door, png, 10);
  ASSERT_EQ(im.w, 1280);
  const SceneView sv(door);
  // the panel's -y face (x from 0.02 to 0.82, z from 0.1 to 1.9, y = -0.02), at rest on its stop:
  // a grid of points well inside it, clear of the knob (x = 0.74)
  for (const double x : {0.15, 0.3, 0.5}) {
    for (const double z : {0.4, 1.0, 1.6}) {
      const auto [px, py] = sv.Pixel(Vec3(x, -0.02, z));
      EXPECT_TRUE(im.IsShadeOf(px, py, kLink)) << "panel at " << x << ", " << z;
    }
  }
  const auto j = nlohmann::json::parse(ReadAll(png + ".json"));
  ASSERT_EQ(j["joints"].size(), 1u) << j.dump();
  EXPECT_EQ(j["joints"][0]["name"], "hinge");
  EXPECT_LT(std::abs(j["joints"][0]["position"].get<double>()), 1e-3);  // closed

  const std::string arm = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/arm.xml";
  const std::string arm_png = (dir / "arm.png").string();
  const Image a = View("--scene " + arm, arm_png, 10);
  ASSERT_EQ(a.w, 1280);
  const SceneView av(arm);
  // the arm straight out along +x: points on the axes of the upper arm (z = 0.25, x from 0 to 0.3,
  // radius 35 mm) and the forearm (x from 0.34 to 0.58, radius 30 mm); gravity sags them under
  // the servos by under 0.02 rad (measured after 1 s), under 15 mm at the forearm's end, inside
  // the capsules
  for (const double x : {0.08, 0.15, 0.22, 0.4, 0.46}) {
    const auto [px, py] = av.Pixel(Vec3(x, 0.0, 0.25));
    EXPECT_TRUE(a.AnyShadeNear(px, py, kLink, 1)) << "arm at x = " << x;
  }
  const auto ja = nlohmann::json::parse(ReadAll(arm_png + ".json"));
  ASSERT_EQ(ja["joints"].size(), 6u) << ja.dump();
  for (const auto& joint : ja["joints"]) {
    EXPECT_EQ(joint["type"], "hinge");
    EXPECT_LT(std::abs(joint["position"].get<double>()), 0.1) << joint.dump();  // held out
  }
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
