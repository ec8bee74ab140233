#include "render/event.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rigidtouch::render {

Vec3 EventTransient(const Model& model, Data& data, std::span<const double> normal_velocity) {
  if (model.render.renderer != RendererKind::kEvent) return Vec3::Zero();
  EventState& e = data.event;
  const int tool = model.tool;
  if (data.window[tool].onset_step == data.step && data.tool_contacts > 0) {
    // a collision onset of the tool's group this tick (GroupWindow): the approach speed of its
    // new contacts, as phases measured it before the dynamics
    const std::span<const double> vn = normal_velocity;
    double v_in = 0.0;
    for (int ci = 0; ci < data.ncontact; ++ci) {
      const Contact& c = data.contacts[ci];
      if (!c.is_new || (c.body_a != tool && c.body_b != tool)) continue;
      v_in = std::max(v_in, -vn[ci]);
    }
    e.onset_step = data.step;
    e.approach_speed_mps = v_in;
    e.normal_W = data.tool_normal_W;
  }
  if (e.onset_step < 0) return Vec3::Zero();
  if (data.tool_contacts == 0) {
    e.onset_step = -1;  // the tool left: a contact force ends with the contact
    return Vec3::Zero();
  }
  const Material& m = model.render.material;
  const double t = (static_cast<double>(data.step - e.onset_step) + 0.5) * model.timestep_s;
  const double envelope = std::exp(-m.decay_per_s * t);
  if (envelope < kEventEnvelopeEnd) {
    e.onset_step = -1;
    return Vec3::Zero();
  }
  return (m.amplitude_Ns_per_m * e.approach_speed_mps * envelope *
          std::sin(2.0 * std::numbers::pi * m.frequency_hz * t)) *
         e.normal_W;
}

}  // namespace rigidtouch::render
