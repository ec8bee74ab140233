// Contact groups with articulated trees in the tick (issue 45; docs/architecture.md, stages 4-5;
// docs/method.md, "Joint space: contact and impulses"). A group that holds a tree (Groups,
// ngroup .. ngroup + ntree_group) is solved in joint space by JointGroupSolver instead of the
// free-body group solver: its contacts are rows on bodies and links, its trees' hinge and slide
// joints at or beyond a limit of their range are unilateral limit rows, and its onset impulse or
// train goes through ApplyJointImpulses with the same window and schedule (Eq. 6-7) as a group
// of free bodies.
//
// Stage 4 (SolveTreeGroups, on the tick's thread once the free-body groups are done): every
// tree's step is prepared (dynamics::PrepareTreeStep); each group's contacts get their law, their
// approach speed with the links' velocities, and the group its window and phase; then its bodies
// and trees move freely and the implicit penalty with friction adds the rows' forces (the tool's
// contacts explicit, as with a free body). Stage 5 (TreeGroupImpulses): the impulse due, if any.
// Stage 7 (dynamics::StepTrees) moves the trees' positions with the final velocities.
//
// Friction: a scene contact's row carries the stick anchor's spring (anchors kept in the frames
// of the contact's bodies and link geoms, placed after the solve as free bodies' are) with
// implicit tangential damping, bounded by the Coulomb cone; the tool's is explicit damping within
// the cone (docs/decisions.md, "Links collide with static geometry and with other links").
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "contact/groups.h"
#include "contact/joint_group.h"
#include "dynamics/velocities.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

struct ContactScratch;

/// Rows of one tree group: at most this many (contacts and limits); a group with more counts
/// Warning::kGroupTooLarge and its members move without contact forces this step.
inline constexpr int kMaxTreeGroupRows = 128;

/// Scratch of the tree groups, sized once by Reserve (nothing when the model has no tree).
struct TreeGroupScratch {
  std::unique_ptr<JointGroupSolver> solver;
  std::vector<SolverBody> bodies;      // (nbody) one group's bodies
  std::vector<Vec3> body_com_W;        // (nbody) their centres of mass
  std::vector<GroupTree> trees;        // (ntree) one group's trees
  std::vector<JointRow> rows;          // (ntree x kMaxTreeGroupRows) every tree group's rows
  std::vector<int> row_contact;        // (same) a row's contact, -1 for a limit
  std::vector<int> row_start;          // (ntree + 1) tree group k's rows
  std::vector<Eigen::VectorXd> force;  // (ntree) x (nv) the actuators' joint forces
  // (ntree) x (njoint): the limit a joint was at last step: +1 lower, -1 upper, 0 none
  std::vector<std::vector<signed char>> limit_engaged;
  long solves = 0;  // SolveJointPenalty calls since Reserve

  /// Sizes every buffer for `model`; the only allocating call.
  void Reserve(const Model& model);
  /// Forgets the limits' state (ResetState).
  void Reset();
};

/// The stiffness [N m/rad or N/m] and damping [N m s/rad or N s/m] of a limit row on a degree of
/// freedom whose mass-matrix diagonal is m_jj (kg m^2 or kg): the spring that gives m_jj a
/// natural period of kLimitPeriodSteps steps, critically damped (docs/decisions.md, "Joint
/// limits as rows").
inline constexpr int kLimitPeriodSteps = 40;
void LimitLaw(double m_jj, double h_s, double& k, double& b);

/// Stage 4 for the groups with trees (after the free-body groups; the force sums of
/// dynamics::AddFreeMotionForces must be done). Never allocates or throws.
void SolveTreeGroups(const Model& model, Data& data, ContactScratch& scratch,
                     dynamics::VelocityScratch& velocity);

/// Stage 5 for the groups with trees: each group's impulse due this step (contacts by
/// RenderParams::renderer and the schedule, limits by RenderParams::joint_limit_renderer),
/// recorded as for free-body groups (data.impulses, the contacts' impulse_Ns,
/// data.tool_impulse_Ns_W, the window's impulses_done).
void TreeGroupImpulses(const Model& model, Data& data, const Groups& groups,
                       TreeGroupScratch& scratch);

}  // namespace rigidtouch::contact
