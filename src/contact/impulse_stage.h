// Impulse stage (tick stage 6): where a group's collision window says an impulse is due (Eq. 6-7),
// the group is packed into solver rows and given the plastic impulse scaled for Eq. 5 (single
// impulse) or Eq. 8 (one impulse of a train), and the impulse is applied to its velocities.
#pragma once

#include <memory>
#include <vector>

#include "contact/groups.h"
#include "contact/impulse.h"
#include "contact/impulse_reference.h"
#include "contact/impulse_solver.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// Scratch of stage 6, sized once by Reserve.
struct ImpulseScratch {
  std::vector<SolverBody> bodies;  // (nbody) one group's bodies
  std::vector<SolverRow> rows;     // (max_contacts) one group's rows
  std::vector<double> impulses;    // (max_contacts) one group's normal impulses  [N s]
  std::unique_ptr<ImpulseSolver> solver;
  std::unique_ptr<ReferenceSolver> reference;  // only when RenderParams::reference_solver

  /// Sizes every buffer; the only allocating call. The reference solver is made only when the
  /// model asks for it.
  void Reserve(const Model& model);
};

/// Stage 6 over every group: the impulse that is due, if any (Warning::kSolverFailed and none
/// when a solver fails), recorded in data.impulses, the contacts' impulse_Ns and
/// data.tool_impulse_W, and the group's window advanced.
void CollisionImpulses(const Model& model, Data& data, const Groups& groups,
                       ImpulseScratch& scratch);

}  // namespace rigidtouch::contact
