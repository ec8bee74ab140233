// Scratch owned by Data: each stage's buffers, sized once by MakeData and reused every tick.
#pragma once

#include <memory>

#include "contact/impulse_stage.h"
#include "contact/phases.h"
#include "dynamics/tree_stage.h"
#include "dynamics/velocities.h"
#include "geometry/collision.h"
#include "parallel/worker.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch {

struct Workspace {
  geometry::CollisionScratch collision;  // stage 2: broad and narrow phase
  contact::ContactScratch contact;       // stages 3-4: groups, laws, friction anchors
  dynamics::VelocityScratch velocity;    // stages 4-5: force sums, implicit contacts, group solver
  contact::ImpulseScratch impulse;       // stage 5: solver rows and the impulse solvers
  dynamics::TreeStageScratch trees;      // stage 7: the trees' actuator forces
  // Model::threads 2: the second thread, shared by stages 2 (narrow phase) and 5 (group solves);
  // null with one thread
  std::unique_ptr<parallel::Worker> worker;
  // the compiled scene of the model MakeData sized everything for (DataFitsModel); not owned, so
  // that a Data does not keep its model's MuJoCo model alive
  std::weak_ptr<mjModel_> made_for;
};

/// Puts the simulated state back to the model's initial state (bodies, contacts and their
/// identities, groups, windows, the tool's outputs, the collision order and the group solver's
/// kept factor) and keeps the step, the time and the warnings. ResetData is this plus step, time
/// and warnings set to zero; the tick's non-finite-state guard calls it alone, so that the run
/// goes on from the initial state at the current time with the warning counted.
void ResetState(const Model& model, Data& data);

}  // namespace rigidtouch
