#include "view/viewer.h"
#include "io/config.h"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "io/output_file.h"
#include "rigidtouch/data.h"
#include "view/camera.h"
#include "view/scene_gl.h"

namespace rigidtouch::view {
namespace {

// colours the screenshot tests look for (docs/viewer.md): the tool, the impulsive-force trace
constexpr ImU32 kToolColor = IM_COL32(255, 140, 0, 255);
constexpr ImU32 kImpulsiveColor = IM_COL32(255, 0, 0, 255);
constexpr ImU32 kPenaltyColor = IM_COL32(0, 160, 255, 255);
constexpr ImU32 kTotalColor = IM_COL32(255, 255, 255, 255);
constexpr ImU32 kPenetrationColor = IM_COL32(255, 220, 0, 255);
constexpr ImU32 kFloorColor = IM_COL32(90, 90, 90, 255);
constexpr ImU32 kStaticColor = IM_COL32(150, 160, 175, 255);
constexpr ImU32 kBodyColor = IM_COL32(70, 110, 200, 255);
constexpr ImU32 kLinkColor = IM_COL32(60, 170, 110, 255);
constexpr ImU32 kContactColor = IM_COL32(255, 0, 255, 255);
constexpr ImU32 kNormalColor = IM_COL32(255, 255, 0, 255);
constexpr ImU32 kForceColor = IM_COL32(0, 255, 0, 255);
constexpr ImU32 kHeightColor = IM_COL32(170, 150, 255, 255);

ImVec2 Pixel(double x, double y) {
  return ImVec2(static_cast<float>(x), static_cast<float>(y));
}

bool Project(const Camera& cam, const Vec3& p, ImVec2& out) {
  double x = 0.0, y = 0.0;
  if (!cam.Project(p, x, y)) return false;
  out = Pixel(x, y);
  return true;
}

void Line(ImDrawList* dl, const Camera& cam, const Vec3& a, const Vec3& b, ImU32 c, float w) {
  ImVec2 pa, pb;
  if (Project(cam, a, pa) && Project(cam, b, pb)) dl->AddLine(pa, pb, c, w);
}

void Arrow(ImDrawList* dl, const Camera& cam, const Vec3& from, const Vec3& to, ImU32 c) {
  ImVec2 a, b;
  if (!Project(cam, from, a) || !Project(cam, to, b)) return;
  dl->AddLine(a, b, c, 3.0f);
  const float dx = b.x - a.x, dy = b.y - a.y, n = std::sqrt(dx * dx + dy * dy);
  if (n < 4.0f) return;
  const float ux = dx / n, uy = dy / n, s = std::min(12.0f, 0.4f * n);
  dl->AddTriangleFilled(b, ImVec2(b.x - s * ux + 0.5f * s * uy, b.y - s * uy - 0.5f * s * ux),
                        ImVec2(b.x - s * ux - 0.5f * s * uy, b.y - s * uy + 0.5f * s * ux), c);
}

Rgb ToRgb(ImU32 c) {
  const auto ch = [&](int shift) { return static_cast<float>((c >> shift) & 0xff) / 255.0f; };
  return {ch(IM_COL32_R_SHIFT), ch(IM_COL32_G_SHIFT), ch(IM_COL32_B_SHIFT)};
}

struct Scope {
  std::vector<ScopeSample> ring;  // the last window, oldest first from `head`
  std::size_t head = 0, count = 0;
  std::vector<ScopeSample> pending;
  std::vector<float> penalty, impulsive, total, penetration_mm;

  explicit Scope(std::size_t n)
      : ring(n), pending(4096), penalty(n), impulsive(n), total(n), penetration_mm(n) {}

  void Drain(ViewFeed& feed) {
    std::size_t got = 0;
    while ((got = feed.PopScope(pending.data(), pending.size())) > 0) {
      for (std::size_t k = 0; k < got; ++k) {
        ring[(head + count) % ring.size()] = pending[k];
        if (count < ring.size()) {
          ++count;
        } else {
          head = (head + 1) % ring.size();
        }
      }
    }
    // the arrays the plots read: the window, oldest first, zero before the first tick
    const std::size_t n = ring.size(), missing = n - count;
    for (std::size_t k = 0; k < n; ++k) {
      ScopeSample s;
      if (k >= missing) s = ring[(head + k - missing) % n];
      penalty[k] = static_cast<float>(s.penalty_N);
      impulsive[k] = static_cast<float>(s.impulsive_N);
      total[k] = static_cast<float>(s.total_N);
      penetration_mm[k] = static_cast<float>(1e3 * s.penetration_m);
    }
  }
};

void PlotScope(const char* label, const std::vector<float>& v, ImU32 color, float max,
               const char* text) {
  ImGui::PushStyleColor(ImGuiCol_PlotLines, color);
  ImGui::PlotLines(label, v.data(), static_cast<int>(v.size()), 0, text, 0.0f, max,
                   ImVec2(360.0f, 70.0f));
  ImGui::PopStyleColor();
}

void WritePng(const std::string& path, int w, int h) {
  std::vector<unsigned char> rgba(static_cast<std::size_t>(w) * h * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  // OpenGL's rows run bottom up, PNG's top down
  std::vector<unsigned char> flipped(rgba.size());
  const std::size_t row = static_cast<std::size_t>(w) * 4;
  for (int y = 0; y < h; ++y) {
    std::copy_n(rgba.data() + static_cast<std::size_t>(h - 1 - y) * row, row,
                flipped.data() + static_cast<std::size_t>(y) * row);
  }
  std::string png;
  stbi_write_png_to_func(
      [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data),
                                                   static_cast<std::size_t>(size));
      },
      &png, w, h, 4, flipped.data(), static_cast<int>(row));
  if (png.empty()) throw Error("view: could not encode the screenshot as PNG");
  io::WriteFileAtomically(path, png, "screenshot");
}

// the window with its OpenGL 3.3 context (a depth buffer too: the window's back buffer is what
// --screenshot reads, hidden or not) and Dear ImGui on it; each part undone by its destructor, in
// reverse order, also when a later one fails
struct GlfwLibrary {
  GlfwLibrary() {
    if (!glfwInit()) {
      throw Error("view: cannot open a window (no display? set DISPLAY or run under xvfb-run)");
    }
  }
  ~GlfwLibrary() { glfwTerminate(); }
};

struct GlfwWindow {
  GLFWwindow* w = nullptr;
  explicit GlfwWindow(const ViewerOptions& o) {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_DEPTH_BITS, 24);
    glfwWindowHint(GLFW_VISIBLE, o.hidden ? GLFW_FALSE : GLFW_TRUE);
    w = glfwCreateWindow(o.width_px, o.height_px, "rigidtouch view", nullptr, nullptr);
    if (w == nullptr) throw Error("view: cannot create an OpenGL 3.3 window with a depth buffer");
    glfwMakeContextCurrent(w);
    glfwSwapInterval(0);  // RunViewer paces the frames
  }
  ~GlfwWindow() { glfwDestroyWindow(w); }
};

struct ImGuiSession {
  explicit ImGuiSession(GLFWwindow* window) {
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGuiStyle& style = ImGui::GetStyle();
    // exact colours in the screenshots: no blending of lines or of the panel with the scene
    style.AntiAliasedLines = false;
    style.AntiAliasedLinesUseTex = false;
    style.AntiAliasedFill = false;
    style.Colors[ImGuiCol_WindowBg].w = 1.0f;
    style.Colors[ImGuiCol_FrameBg] = ImVec4(0.12f, 0.14f, 0.18f, 1.0f);
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330");
  }
  ~ImGuiSession() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
};

// what the viewer carries from frame to frame besides the scope
struct FrameState {
  Vec3 target = Vec3::Zero();  // the handle's target
  double target_depth = 0.0;   // its depth from the camera (the wheel moves it)
  bool pending = false;        // a switch was asked for and waits for no contact
  RendererKind pending_kind = RendererKind::kTrain;
  std::string switch_message;
};

// the handle's target: the scripted path or the cursor, in the view plane; wheel: depth; T: tap
void SteerMouse(device::MouseDevice& mouse, const ViewerOptions& o, int frame, const Camera& cam,
                int w, int h, FrameState& st) {
  const ImGuiIO& io = ImGui::GetIO();
  bool have = false;
  double mx = 0.0, my = 0.0;
  if (!o.mouse_path.empty()) {
    const double s = o.frames > 1 ? static_cast<double>(frame) / (o.frames - 1) : 1.0;
    const double at = s * static_cast<double>(o.mouse_path.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(at), o.mouse_path.size() - 1);
    const std::size_t j = std::min(i + 1, o.mouse_path.size() - 1);
    const double a = at - static_cast<double>(i);
    mx = (1 - a) * o.mouse_path[i].first + a * o.mouse_path[j].first;
    my = (1 - a) * o.mouse_path[i].second + a * o.mouse_path[j].second;
    have = true;
  } else if (!io.WantCaptureMouse && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    mx = io.MousePos.x * (static_cast<double>(w) / io.DisplaySize.x);
    my = io.MousePos.y * (static_cast<double>(h) / io.DisplaySize.y);
    have = true;
  }
  if (!io.WantCaptureMouse && io.MouseWheel != 0.0f) {
    st.target_depth += 0.005 * io.MouseWheel;  // 5 mm per notch, into the screen
  }
  if (have) st.target = cam.Unproject(mx, my, st.target_depth);
  mouse.SetTarget(st.target);
  if (frame == o.tap_frame || (!io.WantCaptureKeyboard && ImGui::IsKeyPressed(GLFW_KEY_T))) {
    mouse.RequestTap();
  }
}

// a renderer switch, asked for by the script or the panel, happens between ticks while no
// contact is active
void SwitchWhenFree(const ViewerOptions& o, int frame, ViewFeed& feed,
                    const RendererSwitch& switch_renderer, FrameState& st, ViewerResult& result) {
  if (frame == o.switch_frame || (o.switch_at_contact && result.renderer_switches == 0 &&
                                  !st.pending && feed.Latest().sample.tool_contacts > 0)) {
    st.pending = true;
    st.pending_kind = o.switch_to;
  }
  if (st.pending && feed.Latest().sample.tool_contacts > 0) ++result.switch_wait_frames;
  if (st.pending && switch_renderer && feed.Latest().sample.tool_contacts == 0) {
    const std::optional<std::string> done = switch_renderer(st.pending_kind);
    if (done) {
      st.switch_message = *done;
      if (done->empty()) ++result.renderer_switches;
      st.pending = false;
    }
  }
}

// every geom, shaded, in its current pose (the initial one before the first tick), with depth
// testing: no order to sort; the tool in its own colour
void DrawGeoms(SceneRenderer& scene, const Model& model, const ViewSnapshot& snap) {
  for (std::size_t gi = 0; gi < model.geoms.size(); ++gi) {
    const GeomModel& g = model.geoms[gi];
    Vec3 pos;
    Mat3 R;
    const int link = g.tree >= 0 ? FirstViewLink(model, g.tree) + g.link : -1;
    if (g.tree >= 0 && snap.step >= 0 && link < snap.nlink) {
      // a tree's link geom where the trees stage put its link
      pos = snap.link_x_W[link] + snap.link_R_WB[link] * g.pos_L;
      R = snap.link_R_WB[link] * g.quat_L.toRotationMatrix();
    } else if (g.body < 0) {  // static, or a link geom at its initial pose
      pos = g.pos_B;
      R = g.quat_B.toRotationMatrix();
    } else if (snap.step < 0 || g.body >= snap.nbody) {
      const BodyState& b = model.initial[g.body];
      pos = b.x_W + b.q_WB * g.pos_B;
      R = (b.q_WB * g.quat_B).toRotationMatrix();
    } else {
      pos = snap.x_W[g.body] + snap.q_WB[g.body] * g.pos_B;
      R = (snap.q_WB[g.body] * g.quat_B).toRotationMatrix();
    }
    const ImU32 c = g.body == model.tool ? kToolColor
                    : g.tree >= 0        ? kLinkColor
                    : g.body < 0         ? kStaticColor
                                         : kBodyColor;
    scene.DrawGeom(static_cast<int>(gi), pos, R, ToRgb(c));
  }
}

// the depth cue under the tool: a line along the normal of the nearest static plane below it to
// its foot there, a ring at the foot (where the tool would land) and the height in millimetres,
// so a tool hovering over a grid shows how far above it is
void DrawHeightCue(ImDrawList* dl, const Camera& cam, const Model& model, const Vec3& tool) {
  double height_m = std::numeric_limits<double>::infinity();
  Vec3 foot = tool;
  for (const GeomModel& g : model.geoms) {
    if (g.type != GeomType::kPlane || g.body >= 0 || g.tree >= 0) continue;
    const Vec3 n = g.quat_B * Vec3::UnitZ();
    const double h = (tool - g.pos_B).dot(n);
    if (!(h >= 0.0) || h >= height_m) continue;
    height_m = h;
    foot = tool - h * n;
  }
  if (!std::isfinite(height_m)) return;
  Line(dl, cam, tool, foot, kHeightColor, 1.0f);
  ImVec2 q;
  if (!Project(cam, foot, q)) return;
  dl->AddCircle(q, 6.0f, kHeightColor, 16, 1.5f);
  char label[32];
  std::snprintf(label, sizeof label, "%.1f mm", 1e3 * height_m);
  dl->AddText(ImVec2(q.x + 9.0f, q.y - 7.0f), kHeightColor, label);
}

// over the shaded scene, never hidden by it: the tool's height over the plane below it,
// contacts and their normals (1 cm), then the device force (1 cm per N)
void DrawOverlays(const Camera& cam, const Model& model, const ViewSnapshot& snap) {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  if (snap.step >= 0) DrawHeightCue(dl, cam, model, snap.sample.tool_position_m);
  for (int k = 0; k < snap.ncontact; ++k) {
    const ContactView& cv = snap.contacts[k];
    ImVec2 q;
    if (Project(cam, cv.p_W, q)) dl->AddCircleFilled(q, 3.0f, kContactColor, 8);
    Line(dl, cam, cv.p_W, cv.p_W + 0.01 * cv.n_W, kNormalColor, 1.5f);
  }
  if (snap.step >= 0) {
    const Vec3 tool = snap.sample.tool_position_m;
    Arrow(dl, cam, tool, tool + 0.01 * snap.sample.device_force_N, kForceColor);
  }
}

void PanelSwitch(const Model& model, const ViewSnapshot& snap, FrameState& st) {
  const bool contact = snap.sample.tool_contacts > 0;
  ImGui::Text(contact ? "switch (after the contact)" : "switch to");
  for (const RendererKind k :
       {RendererKind::kPenalty, RendererKind::kImpulse, RendererKind::kTrain}) {
    ImGui::SameLine();
    if (ImGui::RadioButton(text::RendererName(k), model.render.renderer == k)) {
      st.pending = true;
      st.pending_kind = k;
    }
  }
  if (st.pending) ImGui::TextDisabled("waiting for no contact to switch");
  if (!st.switch_message.empty()) {
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "%s", st.switch_message.c_str());
  }
}

void PanelWarnings(const ViewSnapshot& snap) {
  bool any = false;
  for (int k = 0; k < static_cast<int>(Warning::kCount) && k < 32; ++k) {
    if ((snap.warnings >> k) & 1u) {
      ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "warning: %s",
                         WarningName(static_cast<Warning>(k)));
      any = true;
    }
  }
  if (snap.scope_dropped > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "scope dropped %llu ticks",
                       static_cast<unsigned long long>(snap.scope_dropped));
    any = true;
  }
  if (!any) ImGui::Text("no warnings");
}

// every hinge's angle (degrees) and slide's position (mm), with its range, as the last tick
// left them (the initial state before it)
void PanelJoints(const Model& model, const ViewSnapshot& snap) {
  int k = 0;
  for (std::size_t t = 0; t < model.trees.size(); ++t) {
    const ArticulatedTree& tree = model.trees[t];
    for (const JointModel& j : tree.joints) {
      if (j.type != JointKind::kHinge && j.type != JointKind::kSlide) continue;
      if (k == kMaxViewJoints) return;
      const double q =
          snap.step >= 0 && k < snap.njoint ? snap.joint_q[k] : tree.initial_qpos[j.qpos_adr];
      ++k;
      const bool hinge = j.type == JointKind::kHinge;
      const double unit = hinge ? 180.0 / std::numbers::pi : 1e3;
      const char* name = hinge ? "deg" : "mm";
      if (j.limited) {
        ImGui::Text("%s %.1f %s  [%.1f, %.1f]", j.name.c_str(), unit * q, name,
                    unit * j.range_lo_rad_or_m, unit * j.range_hi_rad_or_m);
      } else {
        ImGui::Text("%s %.1f %s", j.name.c_str(), unit * q, name);
      }
    }
  }
}

// the panel: device, renderer (switchable), wall, loop timing, the tick's numbers, the joints, the
// scope and the warnings
void DrawPanel(const Model& model, const ViewerOptions& o, const ViewSnapshot& snap,
               const Scope& scope, bool can_switch, bool has_mouse, FrameState& st) {
  const float force_scale = static_cast<float>(
      model.device.limits.max_force_N > 0.0 ? model.device.limits.max_force_N : 5.0);
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(static_cast<float>(kPanelRightPx) - 20.0f, 0), ImGuiCond_Always);
  ImGui::Begin("rigidtouch", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize);
  ImGui::Text("device %s", o.device.c_str());
  ImGui::Text("renderer %s  e %.2f  t_c %.0f ms  f %.0f Hz",
              text::RendererName(model.render.renderer), model.render.restitution,
              1e3 * model.render.t_collision_s, model.render.frequency_hz);
  if (can_switch) PanelSwitch(model, snap, st);
  if (model.device.limits.max_force_N > 0.0) {
    ImGui::Text("wall k %.0f N/m  b %.2f N s/m  force limit %.2f N",
                model.contact.stiffness_N_per_m, model.contact.damping_Ns_per_m,
                model.device.limits.max_force_N);
  } else {
    ImGui::Text("wall k %.0f N/m  b %.2f N s/m  no force limit", model.contact.stiffness_N_per_m,
                model.contact.damping_Ns_per_m);
  }
  if (snap.measured_rate_hz > 0.0) {
    ImGui::Text("loop %.0f Hz asked, %.1f Hz measured", o.rate_hz, snap.measured_rate_hz);
    ImGui::Text("period error over 1 s: mean %.1f us, max %.1f us", 1e6 * snap.period_error_mean_s,
                1e6 * snap.period_error_max_s);
  } else {  // the haptic thread reports its rate and period error once a second
    ImGui::Text("loop %.0f Hz asked", o.rate_hz);
    ImGui::Text("rate and period error: after the first second");
  }
  ImGui::Text("t %.3f s  tool contacts %d  penetration %.2f mm", snap.time_s,
              snap.sample.tool_contacts, 1e3 * snap.sample.penetration_m);
  ImGui::Text("force %.2f N (penalty %.2f, impulsive %.2f)", snap.sample.device_force_N.norm(),
              snap.sample.penalty_force_N.norm(), snap.sample.impulsive_force_N.norm());
  if (!model.trees.empty()) {
    ImGui::Separator();
    ImGui::Text("joints (joint-limit renderer %s)",
                text::RendererName(model.render.joint_limit_renderer));
    PanelJoints(model, snap);
  }
  ImGui::Separator();
  ImGui::Text("last %.1f s", o.scope_window_s);
  // each trace's full scale written over it: the force panels span 0 to the device's limit
  char force_range[48];
  std::snprintf(force_range, sizeof force_range, "0 to %.2f N", force_scale);
  PlotScope("total N", scope.total, kTotalColor, force_scale, force_range);
  PlotScope("penalty N", scope.penalty, kPenaltyColor, force_scale, force_range);
  PlotScope("impulsive N", scope.impulsive, kImpulsiveColor, force_scale, force_range);
  PlotScope("penetr. mm", scope.penetration_mm, kPenetrationColor, 5.0f, "0 to 5 mm");
  ImGui::Separator();
  PanelWarnings(snap);
  if (has_mouse) ImGui::TextDisabled("drag: move the tool  wheel: depth  T: tap");
  ImGui::End();
}

// A scripted run is paced by the loop's time as well: frame k shows the world at k / 60 s of loop
// time however slowly a loaded machine draws, so a tap scripted at a frame lands at the same place
// in the scope every run; a loop that has ended (or stalls for 0.2 s) is not waited for.
void WaitForLoop(ViewFeed& feed, double frame_time_s) {
  using Clock = std::chrono::steady_clock;
  double seen_s = feed.Latest().sample.time_s;
  auto seen_at = Clock::now();
  while (seen_s < frame_time_s && Clock::now() - seen_at < std::chrono::milliseconds(200)) {
    std::this_thread::sleep_for(std::chrono::microseconds(500));
    const double now_s = feed.Latest().sample.time_s;
    if (now_s != seen_s) {
      seen_s = now_s;
      seen_at = Clock::now();
    }
  }
}

}  // namespace

ViewerResult RunViewer(const Model& model, ViewFeed& feed, device::MouseDevice* mouse,
                       const ViewerOptions& o, const RendererSwitch& switch_renderer) {
  if (!o.screenshot.empty()) io::CheckOutputPath(o.screenshot, "screenshot");
  const GlfwLibrary glfw;
  const GlfwWindow window(o);
  const ImGuiSession imgui(window.w);
  const SceneFrame frame_of = FrameScene(model);
  SceneRenderer scene(model, frame_of);
  FrameState st;
  st.target = model.initial[model.tool].x_W;
  Scope scope(static_cast<std::size_t>(std::max(2.0, std::round(o.scope_window_s * o.rate_hz))));

  ViewerResult result;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const auto frame_period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / o.display_hz));
  auto next_frame = t0;
  for (int frame = 0; o.frames <= 0 || frame < o.frames; ++frame) {
    glfwPollEvents();
    if (glfwWindowShouldClose(window.w) || (o.stop != nullptr && o.stop->load())) {
      result.closed_by_user = true;
      break;
    }
    int w = 0, h = 0;
    glfwGetFramebufferSize(window.w, &w, &h);
    const Camera cam = ViewerCamera(frame_of, w, h);
    if (st.target_depth == 0.0) st.target_depth = cam.Depth(model.initial[model.tool].x_W);

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    if (mouse != nullptr) SteerMouse(*mouse, o, frame, cam, w, h, st);
    SwitchWhenFree(o, frame, feed, switch_renderer, st, result);
    const ViewSnapshot& snap = feed.Latest();
    scope.Drain(feed);
    DrawOverlays(cam, model, snap);
    DrawPanel(model, o, snap, scope, static_cast<bool>(switch_renderer), mouse != nullptr, st);
    ImGui::Render();

    glViewport(0, 0, w, h);
    glClearColor(0.08f, 0.09f, 0.11f, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    scene.Begin(cam, frame_of.far_m);
    DrawGeoms(scene, model, snap);
    scene.End(ToRgb(kFloorColor));
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++result.frames;
    const bool last = o.frames > 0 && frame + 1 == o.frames;
    if (last && !o.screenshot.empty()) WritePng(o.screenshot, w, h);
    glfwSwapBuffers(window.w);
    next_frame += frame_period;
    std::this_thread::sleep_until(next_frame);
    if (o.frames > 0) {
      WaitForLoop(feed, static_cast<double>(frame + 1) / o.display_hz);
      next_frame = std::max(next_frame, Clock::now());
    }
  }
  result.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace rigidtouch::view
