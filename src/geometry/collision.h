// Collision detection adapter (tick stage 2): MuJoCo's narrow phase at the current poses, turned
// into rigidtouch contacts with persistent identity across ticks.
#pragma once

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

struct mjData_;

namespace rigidtouch::geometry {

/// Detects contacts at the poses in `data.bodies` into data.contacts (first data.ncontact valid),
/// matching each to last tick's contacts (data.previous) to keep ids, friction anchors and to mark
/// new contacts. `scratch` is the backend's preallocated mjData. Never allocates or throws; a full
/// contact list counts Warning::kContactFull.
void DetectContacts(const Model& model, Data& data, mjData_* scratch);

/// Stores this tick's contacts as `previous`, sorted for matching.
void RememberContacts(Data& data);

/// Distance within which a contact point (in the first body's frame) is the same contact as one
/// of last tick on the same geom pair.
inline constexpr double kMatchDistance_m = 0.005;

}  // namespace rigidtouch::geometry
