// Impulse stage (tick stage 6): where a group's collision window says an impulse is due (Eq. 6-7),
// the group is packed into solver rows and given the plastic impulse scaled for Eq. 5 (single
// impulse) or Eq. 8 (one impulse of a train), and the impulse is applied to its velocities.
// With a worker (threads 2) the groups that have an impulse due are shared between the two
// threads, each with buffers and a solver of its own; the events, the tool's impulse and the
// warnings are then recorded in group order, so the results are those of one thread, bit for bit.
#pragma once

#include <memory>
#include <vector>

#include "contact/groups.h"
#include "contact/impulse.h"
#include "contact/impulse_reference.h"
#include "contact/impulse_solver.h"
#include "contact/tree_groups.h"
#include "parallel/worker.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// One thread's buffers of stage 6, for groups of up to rows.size() rows.
struct ImpulseLane {
  std::vector<SolverBody> bodies;  // (nbody) one group's bodies
  std::vector<SolverRow> rows;     // (the lane's rows) one group's rows
  std::vector<double> impulses;    // (the lane's rows) one group's normal impulses  [N s]
  std::unique_ptr<ImpulseSolver> solver;
};

/// Scratch of stage 6, sized once by Reserve.
struct ImpulseScratch {
  /// A group with an impulse due this tick, and what its solve gave.
  struct Due {
    int group = -1;
    int index = 0;      // i, the impulse's 1-based place in the train
    int remaining = 0;  // N - i + 1
    bool solved = false;
    bool left = false;      // too large for the worker's lane: left to the tick's thread
    bool interior = false;  // the solve used the interior-point method (WindowState::interior)
    ImpulseEvent event;     // when solved
  };
  /// What the worker's part of the shared groups needs.
  struct Job {
    const Model* model = nullptr;
    Data* data = nullptr;
    const Groups* groups = nullptr;
    ImpulseScratch* scratch = nullptr;
  };

  /// Rows of the worker's lane: its solver's buffers take about 0.4 kB a row, and a lane as
  /// large as the tick's (every contact the scene can have) would add tens of megabytes to a
  /// large scene for groups that are rarely that large. A larger group is solved by the tick's
  /// thread.
  static constexpr int kWorkerLaneRows = 4096;

  ImpulseLane lane;                            // the tick's thread: every contact
  ImpulseLane worker_lane;                     // the worker's (Model::threads 2 only)
  std::unique_ptr<ReferenceSolver> reference;  // only when RenderParams::reference_solver
  std::vector<Due> due;                        // (nbody) the groups with an impulse due, in order
  int ndue = 0;
  parallel::TwoEndedRange shared;  // places in `due` the two threads take
  Job job;
  long shared_steps = 0;      // steps whose impulses were shared between the threads
  long solved_on_worker = 0;  // groups the worker solved
  long left_by_worker = 0;    // groups the worker left for being too large (all since Reserve)

  /// Sizes every buffer; the only allocating call. The reference solver is made only when the
  /// model asks for it, the worker's lane only with two threads, for at most `worker_rows` rows.
  void Reserve(const Model& model, int worker_rows = kWorkerLaneRows);
};

/// Stage 6 over every group: the impulse that is due, if any (Warning::kSolverFailed and none
/// when a solver fails), recorded in data.impulses, the contacts' impulse_Ns and
/// data.tool_impulse_Ns_W, and the group's window advanced. With a worker, the groups with an
/// impulse due are shared with it when there are enough of them.
/// The groups with trees (Groups::ntree_group) take their impulses from `trees`
/// (TreeGroupImpulses, on the tick's thread), whatever the renderer: a joint limit's mode is its
/// own (RenderParams::joint_limit_renderer).
void CollisionImpulses(const Model& model, Data& data, const Groups& groups,
                       ImpulseScratch& scratch, parallel::Worker* worker = nullptr,
                       TreeGroupScratch* trees = nullptr);

}  // namespace rigidtouch::contact
