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
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "io/output_file.h"
#include "rigidtouch/data.h"

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
constexpr ImU32 kContactColor = IM_COL32(255, 0, 255, 255);
constexpr ImU32 kNormalColor = IM_COL32(255, 255, 0, 255);
constexpr ImU32 kForceColor = IM_COL32(0, 255, 0, 255);

// a fixed perspective camera looking at the tool's start from the front and above
struct Camera {
  Vec3 eye, f, r, u;
  double focal_px = 1.0, cx = 0.0, cy = 0.0;

  Camera(const Vec3& target, double distance_m, double width, double height) {
    const double elevation = 25.0 * std::numbers::pi / 180.0;
    eye = target + distance_m * Vec3(0.0, -std::cos(elevation), std::sin(elevation));
    f = (target - eye).normalized();
    r = f.cross(Vec3::UnitZ()).normalized();
    u = r.cross(f);
    cx = 0.5 * width;
    cy = 0.5 * height;
    focal_px = cy / std::tan(0.5 * 45.0 * std::numbers::pi / 180.0);
  }
  double Depth(const Vec3& p) const { return (p - eye).dot(f); }
  // false behind the near plane
  bool Project(const Vec3& p, ImVec2& out) const {
    const Vec3 v = p - eye;
    const double z = v.dot(f);
    if (z < 0.01) return false;
    out = ImVec2(static_cast<float>(cx + focal_px * v.dot(r) / z),
                 static_cast<float>(cy - focal_px * v.dot(u) / z));
    return true;
  }
  // the point at depth `z` under pixel (x, y)
  Vec3 Unproject(double x, double y, double z) const {
    return eye + z * f + ((x - cx) * z / focal_px) * r - ((y - cy) * z / focal_px) * u;
  }
};

ImU32 Shade(ImU32 c, double k) {
  const auto ch = [&](int shift) {
    return static_cast<ImU32>(std::clamp(((c >> shift) & 0xff) * k, 0.0, 255.0)) << shift;
  };
  return ch(IM_COL32_R_SHIFT) | ch(IM_COL32_G_SHIFT) | ch(IM_COL32_B_SHIFT) | (c & IM_COL32_A_MASK);
}

void Line(ImDrawList* dl, const Camera& cam, const Vec3& a, const Vec3& b, ImU32 c, float w) {
  ImVec2 pa, pb;
  if (cam.Project(a, pa) && cam.Project(b, pb)) dl->AddLine(pa, pb, c, w);
}

void Arrow(ImDrawList* dl, const Camera& cam, const Vec3& from, const Vec3& to, ImU32 c) {
  ImVec2 a, b;
  if (!cam.Project(from, a) || !cam.Project(to, b)) return;
  dl->AddLine(a, b, c, 3.0f);
  const float dx = b.x - a.x, dy = b.y - a.y, n = std::sqrt(dx * dx + dy * dy);
  if (n < 4.0f) return;
  const float ux = dx / n, uy = dy / n, s = std::min(12.0f, 0.4f * n);
  dl->AddTriangleFilled(b, ImVec2(b.x - s * ux + 0.5f * s * uy, b.y - s * uy - 0.5f * s * ux),
                        ImVec2(b.x - s * ux - 0.5f * s * uy, b.y - s * uy + 0.5f * s * ux), c);
}

void Disc(ImDrawList* dl, const Camera& cam, const Vec3& centre, double radius_m, ImU32 c,
          bool filled) {
  ImVec2 p;
  if (!cam.Project(centre, p)) return;
  const float r = static_cast<float>(cam.focal_px * radius_m / cam.Depth(centre));
  if (filled) {
    dl->AddCircleFilled(p, r, c, 32);
    // a highlight towards the light, so a sphere reads as one
    dl->AddCircleFilled(ImVec2(p.x - 0.3f * r, p.y - 0.3f * r), 0.35f * r, Shade(c, 1.25), 16);
  } else {
    dl->AddCircle(p, r, c, 32, 1.5f);
  }
}

void DrawBox(ImDrawList* dl, const Camera& cam, const Vec3& pos, const Mat3& R, const Vec3& half,
             ImU32 c) {
  Vec3 corner[8];
  for (int k = 0; k < 8; ++k) {
    const Vec3 s((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
    corner[k] = pos + R * s.cwiseProduct(half);
  }
  // faces as corner indices, counter-clockwise seen from outside, with their outward axes
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  static constexpr int kAxis[6] = {-1, 1, -2, 2, -3, 3};
  const Vec3 light = Vec3(0.3, -0.5, 1.0).normalized();
  for (int i = 0; i < 6; ++i) {
    const int a = std::abs(kAxis[i]) - 1;
    const Vec3 n = (kAxis[i] > 0 ? 1.0 : -1.0) * R.col(a);
    const Vec3 centre = pos + n * half[a];
    if ((centre - cam.eye).dot(n) >= 0.0) continue;  // faces away from the camera
    ImVec2 p[4];
    bool ok = true;
    for (int k = 0; k < 4; ++k) ok = ok && cam.Project(corner[kFaces[i][k]], p[k]);
    if (!ok) continue;
    dl->AddQuadFilled(p[0], p[1], p[2], p[3], Shade(c, 0.55 + 0.45 * std::max(0.0, n.dot(light))));
    dl->AddQuad(p[0], p[1], p[2], p[3], Shade(c, 0.4), 1.0f);
  }
}

void DrawCapsule(ImDrawList* dl, const Camera& cam, const Vec3& pos, const Mat3& R, double radius,
                 double half_length, ImU32 c) {
  const Vec3 a = pos - half_length * R.col(2), b = pos + half_length * R.col(2);
  ImVec2 pa, pb;
  if (!cam.Project(a, pa) || !cam.Project(b, pb)) return;
  const float w = static_cast<float>(2.0 * cam.focal_px * radius / cam.Depth(pos));
  dl->AddLine(pa, pb, c, w);
  Disc(dl, cam, a, radius, c, true);
  Disc(dl, cam, b, radius, c, true);
}

void DrawPlane(ImDrawList* dl, const Camera& cam, const Vec3& pos, const Mat3& R, const Vec3& size,
               const Vec3& around, double half) {
  // a grid of 1 cm cells (5 cm for large scenes) around the scene (an MJCF plane of size 0 is
  // infinite)
  const double step = half > 0.3 ? 0.05 : 0.01;
  const Vec3 local = R.transpose() * (around - pos);
  const double hx = size.x() > 0.0 ? std::min(size.x(), half) : half;
  const double hy = size.y() > 0.0 ? std::min(size.y(), half) : half;
  const double ox = std::round(local.x() / step) * step, oy = std::round(local.y() / step) * step;
  for (double t = -half; t <= half + 1e-9; t += step) {
    const float w = std::abs(std::fmod(std::abs(t + ox) + 1e-9, 5 * step)) < 2e-9 ? 2.0f : 1.0f;
    Line(dl, cam, pos + R * Vec3(ox + t, oy - hy, 0), pos + R * Vec3(ox + t, oy + hy, 0),
         kFloorColor, w);
    Line(dl, cam, pos + R * Vec3(ox - hx, oy + t, 0), pos + R * Vec3(ox + hx, oy + t, 0),
         kFloorColor, w);
  }
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

void Plot(const char* label, const std::vector<float>& v, ImU32 color, float max,
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

}  // namespace

ViewerResult RunViewer(const Model& model, ViewFeed& feed, device::MouseDevice* mouse,
                       const ViewerOptions& o, const RendererSwitch& switch_renderer) {
  if (!o.screenshot.empty()) io::CheckOutputPath(o.screenshot, "screenshot");
  if (!glfwInit()) {
    throw Error("view: cannot open a window (no display? set DISPLAY or run under xvfb-run)");
  }
  struct GlfwGuard {
    ~GlfwGuard() { glfwTerminate(); }
  } glfw_guard;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_VISIBLE, o.hidden ? GLFW_FALSE : GLFW_TRUE);
  GLFWwindow* window =
      glfwCreateWindow(o.width_px, o.height_px, "rigidtouch view", nullptr, nullptr);
  if (window == nullptr) throw Error("view: cannot create an OpenGL 3.3 window");
  struct WindowGuard {
    GLFWwindow* w;
    ~WindowGuard() { glfwDestroyWindow(w); }
  } window_guard{window};
  glfwMakeContextCurrent(window);
  glfwSwapInterval(0);  // the loop below paces the frames

  ImGui::CreateContext();
  struct ImGuiGuard {
    ~ImGuiGuard() {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
  };
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini next to the user's files
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
  ImGuiGuard imgui_guard;

  const Vec3 start = model.initial[model.tool].x_W;
  // the camera frames every geom but planes: their bounding sphere, seen from at least 0.2 m
  Vec3 lo = start, hi = start;
  for (const GeomModel& g : model.geoms) {
    if (g.type == GeomType::kPlane) continue;
    const Vec3 c = g.body < 0
                       ? g.pos_B
                       : Vec3(model.initial[g.body].x_W + model.initial[g.body].q_WB * g.pos_B);
    lo = lo.cwiseMin(c - Vec3::Constant(g.rbound_m));
    hi = hi.cwiseMax(c + Vec3::Constant(g.rbound_m));
  }
  const Vec3 centre = 0.5 * (lo + hi);
  const double scene_radius = 0.5 * (hi - lo).norm();
  const double distance = std::max(0.2, 3.0 * scene_radius);
  const double grid_half = std::max(0.15, 1.5 * scene_radius);
  double target_depth = 0.0;
  Vec3 target = start;
  Scope scope(static_cast<std::size_t>(std::max(2.0, std::round(o.scope_window_s * o.rate_hz))));
  const double force_scale = model.device.max_force_N > 0.0 ? model.device.max_force_N : 5.0;

  ViewerResult result;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const auto frame_period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / o.display_hz));
  auto next_frame = t0;
  std::vector<int> order;
  bool pending = false;  // a switch was asked for and waits for no contact
  RendererKind pending_kind = RendererKind::kTrain;
  std::string switch_message;
  for (int frame = 0; o.frames <= 0 || frame < o.frames; ++frame) {
    glfwPollEvents();
    if (glfwWindowShouldClose(window) || (o.stop != nullptr && o.stop->load())) {
      result.closed_by_user = true;
      break;
    }
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    const Camera cam(centre, distance, w, h);
    if (target_depth == 0.0) target_depth = cam.Depth(start);

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();

    // the handle's target: the scripted path or the cursor, in the view plane; wheel: depth
    if (mouse != nullptr) {
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
        target_depth += 0.005 * io.MouseWheel;  // 5 mm per notch, into the screen
      }
      if (have) target = cam.Unproject(mx, my, target_depth);
      mouse->SetTarget(target);
      if (frame == o.tap_frame || (!io.WantCaptureKeyboard && ImGui::IsKeyPressed(GLFW_KEY_T))) {
        mouse->RequestTap();
      }
    }

    if (frame == o.switch_frame || (o.switch_at_contact && result.renderer_switches == 0 &&
                                    !pending && feed.Latest().sample.tool_contacts > 0)) {
      pending = true;
      pending_kind = o.switch_to;
    }
    // a renderer switch happens between ticks while no contact is active
    if (pending && feed.Latest().sample.tool_contacts > 0) ++result.switch_wait_frames;
    if (pending && switch_renderer && feed.Latest().sample.tool_contacts == 0) {
      const std::optional<std::string> done = switch_renderer(pending_kind);
      if (done) {
        switch_message = *done;
        if (done->empty()) ++result.renderer_switches;
        pending = false;
      }
    }
    const ViewSnapshot& snap = feed.Latest();
    scope.Drain(feed);
    ImDrawList* dl = ImGui::GetBackgroundDrawList();

    // geoms far to near (painter's order), the tool's in its own colour
    order.resize(model.geoms.size());
    for (std::size_t g = 0; g < order.size(); ++g) order[g] = static_cast<int>(g);
    const auto pose = [&](const GeomModel& g, Vec3& pos, Mat3& R) {
      if (g.body < 0 || snap.step < 0 || g.body >= snap.nbody) {
        const BodyState& b = g.body < 0 ? BodyState{} : model.initial[g.body];
        pos = g.body < 0 ? g.pos_B : b.x_W + b.q_WB * g.pos_B;
        R = (g.body < 0 ? g.quat_B : b.q_WB * g.quat_B).toRotationMatrix();
        return;
      }
      pos = snap.x_W[g.body] + snap.q_WB[g.body] * g.pos_B;
      R = (snap.q_WB[g.body] * g.quat_B).toRotationMatrix();
    };
    std::vector<double> depth(model.geoms.size());
    for (std::size_t g = 0; g < model.geoms.size(); ++g) {
      Vec3 p;
      Mat3 R;
      pose(model.geoms[g], p, R);
      depth[g] = model.geoms[g].type == GeomType::kPlane ? 1e9 : cam.Depth(p);
    }
    std::sort(order.begin(), order.end(), [&](int a, int b) { return depth[a] > depth[b]; });
    for (const int gi : order) {
      const GeomModel& g = model.geoms[gi];
      Vec3 p;
      Mat3 R;
      pose(g, p, R);
      const ImU32 c = g.body == model.tool ? kToolColor : g.body < 0 ? kStaticColor : kBodyColor;
      switch (g.type) {
        case GeomType::kPlane:
          DrawPlane(dl, cam, p, R, g.size, centre, grid_half);
          break;
        case GeomType::kSphere:
          Disc(dl, cam, p, g.size.x(), c, true);
          break;
        case GeomType::kCapsule:
          DrawCapsule(dl, cam, p, R, g.size.x(), g.size.y(), c);
          break;
        case GeomType::kBox:
          DrawBox(dl, cam, p, R, g.size, c);
          break;
        case GeomType::kMesh:
          // drawn as its bounding sphere's outline (the viewer does not keep the mesh's faces)
          Disc(dl, cam, p, g.rbound_m, c, false);
          break;
      }
    }
    // contacts and their normals (1 cm), then the device force (1 cm per N)
    for (int k = 0; k < snap.ncontact; ++k) {
      const ContactView& cv = snap.contacts[k];
      ImVec2 q;
      if (cam.Project(cv.p_W, q)) dl->AddCircleFilled(q, 3.0f, kContactColor, 8);
      Line(dl, cam, cv.p_W, cv.p_W + 0.01 * cv.n_W, kNormalColor, 1.5f);
    }
    if (snap.step >= 0) {
      const Vec3 tool = snap.sample.tool_position_m;
      Arrow(dl, cam, tool, tool + 0.01 * snap.sample.device_force_N, kForceColor);
    }

    // the panel
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_Always);
    ImGui::SetNextWindowSize(ImVec2(470, 0), ImGuiCond_Always);
    ImGui::Begin("rigidtouch", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize);
    ImGui::Text("device %s", o.device.c_str());
    ImGui::Text("renderer %s  e %.2f  t_c %.0f ms  f %.0f Hz",
                io::RendererName(model.render.renderer), model.render.restitution,
                1e3 * model.render.t_collision_s, model.render.frequency_hz);
    if (switch_renderer) {
      const bool contact = snap.sample.tool_contacts > 0;
      ImGui::Text(contact ? "switch (after the contact)" : "switch to");
      for (const RendererKind k :
           {RendererKind::kPenalty, RendererKind::kImpulse, RendererKind::kTrain}) {
        ImGui::SameLine();
        if (ImGui::RadioButton(io::RendererName(k), model.render.renderer == k)) {
          pending = true;
          pending_kind = k;
        }
      }
      if (pending) ImGui::TextDisabled("waiting for no contact to switch");
      if (!switch_message.empty()) {
        ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "%s", switch_message.c_str());
      }
    }
    ImGui::Text("wall k %.0f N/m  b %.2f N s/m  force limit %.2f N",
                model.contact.stiffness_N_per_m, model.contact.damping_Ns_per_m,
                model.device.max_force_N);
    ImGui::Text("loop %.0f Hz asked, %.1f Hz measured", o.rate_hz, snap.measured_rate_hz);
    ImGui::Text("period error over 1 s: mean %.1f us, max %.1f us", 1e6 * snap.period_error_mean_s,
                1e6 * snap.period_error_max_s);
    ImGui::Text("t %.3f s  tool contacts %d  penetration %.2f mm", snap.time_s,
                snap.sample.tool_contacts, 1e3 * snap.sample.penetration_m);
    ImGui::Text("force %.2f N (penalty %.2f, impulsive %.2f)", snap.sample.device_force_N.norm(),
                snap.sample.penalty_force_N.norm(), snap.sample.impulsive_force_N.norm());
    ImGui::Separator();
    ImGui::Text("last %.1f s", o.scope_window_s);
    Plot("total N", scope.total, kTotalColor, static_cast<float>(force_scale), nullptr);
    Plot("penalty N", scope.penalty, kPenaltyColor, static_cast<float>(force_scale), nullptr);
    Plot("impulsive N", scope.impulsive, kImpulsiveColor, static_cast<float>(force_scale), nullptr);
    Plot("penetr. mm", scope.penetration_mm, kPenetrationColor, 5.0f, nullptr);
    ImGui::Separator();
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
    if (mouse != nullptr) ImGui::TextDisabled("drag: move the tool  wheel: depth  T: tap");
    ImGui::End();

    ImGui::Render();
    glViewport(0, 0, w, h);
    glClearColor(0.08f, 0.09f, 0.11f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++result.frames;
    const bool last = o.frames > 0 && frame + 1 == o.frames;
    if (last && !o.screenshot.empty()) WritePng(o.screenshot, w, h);
    glfwSwapBuffers(window);
    next_frame += frame_period;
    std::this_thread::sleep_until(next_frame);
    if (o.frames > 0) {
      // a scripted run is paced by the loop's time as well: frame k shows the world at k / 60 s
      // of loop time however slowly a loaded machine draws, so a tap scripted at a frame lands
      // at the same place in the scope every run; a loop that has ended (or stalls for 0.2 s)
      // is not waited for
      const double frame_time_s = static_cast<double>(frame + 1) / o.display_hz;
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
      next_frame = std::max(next_frame, Clock::now());
    }
  }
  result.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace rigidtouch::view
