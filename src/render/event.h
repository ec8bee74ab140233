// Render (tick stage 8): the event renderer's open-loop contact transient (Kuchenbecker, Fiene
// and Niemeyer, IEEE T-VCG 2006), the decaying sinusoid of Okamura, Cutkosky and Dennerlein
// (IEEE/ASME T-Mech 2001), superimposed on penalty feedback at contact onset.
#pragma once

#include <span>

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::render {

/// The transient lasts until its envelope e^(-B t) falls below this fraction (0.1 %).
inline constexpr double kEventEnvelopeEnd = 1e-3;

/// The transient force on the device this tick [N], zero for other renderers: at a collision
/// onset of the tool (the window's onset step) it starts with v_in the fastest approach speed of
/// the tool's new contacts and n the deepest contact's normal, then
///   F = A v_in e^(-B t) sin(2 pi f t) n,   t = (k + 1/2) h after onset
/// (the midpoint of the tick the force is held over), while the tool stays in contact and until
/// e^(-B t) < kEventEnvelopeEnd. Open loop: it does not depend on the motion after onset, so it can
/// give the user energy (docs/renderers.md). Reads the tool's contacts as DeviceWrench summed
/// them; `normal_velocity` is each contact's approach speed as stage 3 measured it before the
/// dynamics (contact::ContactScratch::normal_velocity). Never allocates or throws.
Vec3 EventTransient(const Model& model, Data& data, std::span<const double> normal_velocity);

}  // namespace rigidtouch::render
