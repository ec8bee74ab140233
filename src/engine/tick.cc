// One haptic tick (docs/architecture.md): a list of stage calls, each stage in the folder of its
// kind. Nothing here allocates, locks, does I/O or throws; problems are counted in data.warnings.
#include "contact/contact_forces.h"
#include "contact/impulse_stage.h"
#include "contact/phases.h"
#include "dynamics/kinematics.h"
#include "dynamics/velocities.h"
#include "engine/workspace.h"
#include "geometry/collision.h"
#include "render/coupling.h"
#include "render/output.h"
#include "render/passivity.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {

DeviceCommand Tick(const Model& model, Data& data, const TickInput& input) {
  Workspace& ws = *data.workspace;
  data.nimpulse = 0;
  data.tool_impulse_W.setZero();
  data.tool_coupling_force_W.setZero();

  // 1. coupling: the device's state sets the tool's pose (direct) or pulls it (virtual)
  const render::CouplingResult coupling = render::CoupleDevice(model, data, input);
  // a repeated reading (the device stopped updating, or has not yet) carries no new motion: an
  // impulse computed from it would push against a hand that may have moved or gone, and the
  // train's later impulses grow (Eq. 8), so such a tick starts no window and applies no impulse
  // no usable reading at all (the watchdog tripped, or non-finite or implausible) is no motion too
  const bool stale =
      (model.device.coupling != Coupling::kNone && !input.device.fresh) || coupling.hold_tool;
  // kinematics: the bodies' rotations, read by every stage until 7 moves the bodies
  dynamics::ComputeKinematics(data);

  // 2. geometry: contact points, normals, depths, identities across ticks
  geometry::DetectContacts(model, data, ws.collision, ws.worker.get());
  if (stale) {
    for (int ci = 0; ci < data.ncontact; ++ci) data.contacts[ci].is_new = false;  // no onset
  }

  // 3. groups and windows: contact groups, laws, stick or slip, collision windows and phases;
  // 4. penalty: explicit contacts (tool contacts, Eq. 1's penalty term), scene contacts
  // linearised for the implicit solve. Both group by group, each group's whole on one thread;
  // stage 4's gravity, gyroscopic and user forces alongside the building of the groups (they
  // read only the bodies, which nothing writes before the groups are built and the forces done)
  // 5. dynamics: the new velocities, implicit per group (backward Euler), free elsewhere; each
  // group solved right after its stage 3 and 4, on the same thread, while its contacts are in
  // that thread's cache (groups share no body or contact)
  dynamics::FreeMotionForces free{model, data, coupling.user, ws.velocity};
  const contact::Groups& groups = ws.contact.groups;
  dynamics::GroupSolves solves{
      model, data, {groups.body_start, groups.bodies, groups.slot}, ws.velocity};
  dynamics::BeginVelocities(ws.velocity);
  const bool shared = contact::ClassifyAndForces(model, data, ws.contact, ws.velocity,
                                                 ws.worker.get(), free.AsTask(), solves.AsTask());
  dynamics::EndVelocities(model, data, ws.velocity, shared);

  // 6. impulses: Eq. 5 (single impulse) or Eq. 8 (train) where the window's schedule (Eq. 6-7)
  // says one is due, on the velocities after stage 5
  if (!stale) {
    contact::CollisionImpulses(model, data, ws.contact.groups, ws.impulse, ws.worker.get());
  }

  // 7. integrate positions with the new velocities
  dynamics::IntegratePositions(model, data);
  render::HoldTool(model, data, coupling);

  // 8. render: penalty (or coupling) + Eq. 9, the device's force limit, the passivity
  // controller, the safety guards
  DeviceCommand out = render::DeviceWrench(model, data, ws.contact, input.device.sequence);
  // the passivity observer and controller at the port, over whatever the renderer asked for
  render::PassivityControl(model, data, input.device, coupling.device_ok, out);
  if (!render::Safeguard(data, coupling.device_ok, out)) ResetState(model, data);

  ++data.step;
  data.time_s = static_cast<double>(data.step) * model.timestep_s;
  return out;
}

}  // namespace rigidtouch
