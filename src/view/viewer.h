// The live viewer's window (GLFW, OpenGL 3.3, Dear ImGui): the scene, contacts and the device
// force drawn from the haptic thread's snapshots, a panel with the renderer, the loop's rate and
// period error and the warnings, and a scope of the last 0.5 s of forces and penetration. It runs
// on the calling thread and only reads the ViewFeed: it never blocks or locks the haptic thread.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "device/mouse_device.h"
#include "rigidtouch/model.h"
#include "view/feed.h"

namespace rigidtouch::view {

/// How the viewer runs.
struct ViewerOptions {
  int width_px = 1280;
  int height_px = 720;
  double display_hz = 60.0;  // frames per second (the window's own pacing; no vsync)
  int frames = 0;            // > 0: draw this many frames, then return (headless runs)
  bool hidden = false;       // no visible window (off-screen drawing, e.g. under Xvfb)
  std::string screenshot;    // write the last frame here as PNG
  /// Scripted cursor, in window pixels: followed point to point, evenly over the frames, instead
  /// of the real cursor.
  std::vector<std::pair<double, double>> mouse_path;
  int tap_frame = -1;       // press the tap key at this frame (scripted)
  double rate_hz = 1000.0;  // the haptic loop's requested rate, for the panel
  std::string device;       // what drives the handle, for the panel
  double scope_window_s = 0.5;
  const std::atomic<bool>* stop = nullptr;  // when set (SIGINT, SIGTERM), the viewer returns
  /// Scripted renderer switch: asked for at this frame (as a click on the panel would).
  int switch_frame = -1;
  bool switch_at_contact = false;  // ... or at the first frame that shows a tool contact
  RendererKind switch_to = RendererKind::kPenalty;
};

/// Switches the renderer between ticks (the haptic loop paused). Returns "" when done, a reason
/// when it cannot be done (shown on the panel), or nothing when a contact had become active: the
/// viewer asks again once no contact is.
using RendererSwitch = std::function<std::optional<std::string>(RendererKind)>;

/// What a run of the viewer saw.
struct ViewerResult {
  int frames = 0;
  double elapsed_s = 0.0;
  bool closed_by_user = false;
  int renderer_switches = 0;
  int switch_wait_frames = 0;  // frames switches waited for a contact to end
};

/// Opens the window and draws until it is closed or `options.frames` are drawn. `mouse`, when
/// given, receives the cursor's target and the tap key (T). Throws Error when no window can be
/// opened (no display) or the screenshot cannot be written (io::OutputError).
ViewerResult RunViewer(const Model& model, ViewFeed& feed, device::MouseDevice* mouse,
                       const ViewerOptions& options, const RendererSwitch& switch_renderer = {});

}  // namespace rigidtouch::view
