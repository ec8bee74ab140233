// One haptic tick (docs/architecture.md): one call per stage, each stage in the folder of its
// kind; the stages that share work with the worker thread keep their interleaving inside the
// call. Nothing here allocates, locks, does I/O or throws; problems are counted in data.warnings.
#include "contact/contact_forces.h"
#include "contact/impulse_stage.h"
#include "dynamics/kinematics.h"
#include "dynamics/tree_stage.h"
#include "dynamics/velocities.h"
#include "engine/workspace.h"
#include "geometry/collision.h"
#include "render/coupling.h"
#include "render/output.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {

DeviceCommand Tick(const Model& model, Data& data, const TickInput& input) {
  Workspace& ws = *data.workspace;
  data.nimpulse = 0;
  data.tool_impulse_Ns_W.setZero();
  data.tool_coupling_force_N_W.setZero();

  // 1. coupling: the device's state sets the tool's pose (direct) or pulls it (virtual), and
  // says whether the reading carries new motion (the stale-reading policy, new_motion)
  const render::CouplingResult coupling = render::CoupleDevice(model, data, input);

  // 2. kinematics: the bodies' rotations, read by every stage until 6 moves the bodies
  dynamics::ComputeKinematics(data);

  // 3. geometry: contact points, normals, depths, identities across ticks
  geometry::DetectContacts(model, data, ws.collision, ws.worker.get());

  // 4. groups and velocities: groups, laws, stick or slip, windows and phases; penalty forces
  // (explicit tool contacts, scene contacts linearised); each group's implicit solve right after
  // its forces on the same thread; free motion elsewhere
  contact::GroupsAndVelocities(model, data, ws.contact, ws.velocity, coupling.user,
                               coupling.new_motion, ws.worker.get());

  // 5. impulses: Eq. 5 (single impulse) or Eq. 8 (train) where the window's schedule (Eq. 6-7)
  // says one is due, on the velocities after stage 4; none from a reading without new motion
  if (coupling.new_motion) {
    contact::CollisionImpulses(model, data, ws.contact.groups, ws.impulse, ws.worker.get(),
                               &ws.contact.trees);
  }

  // 6. integrate positions with the new velocities
  dynamics::IntegratePositions(model, data);

  // 7. trees: each articulated tree stepped in joint space with its actuators' forces; the
  // links' geoms moved for the next collision stage
  dynamics::StepTrees(model, data, ws.trees, ws.collision);

  // 8. render: penalty (or coupling) + Eq. 9, the device's force limit, the passivity
  // controller, the safety guards; a non-finite state is put back to initial
  bool state_ok = true;
  DeviceCommand out =
      render::DeviceOutput(model, data, ws.contact, input.device, coupling, state_ok);
  if (!state_ok) ResetState(model, data);

  ++data.step;
  data.time_s = static_cast<double>(data.step) * model.timestep_s;
  return out;
}

}  // namespace rigidtouch
