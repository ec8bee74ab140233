// Contact groups whose members may be kinematic trees (issue 45, "Contact groups over trees"):
// implicit penalty with Coulomb friction, and the collision impulses of Eq. 5 and Eq. 8, in the
// stacked generalized velocities of the group's members (docs/method.md, "Joint space: contact
// and impulses").
//
// A member is a free rigid body (the tool or a free body: SolverBody, 6 velocities [v; w] at its
// centre of mass, world frame) or a tree (dynamics::TreeModel / TreeData: its qvel). A row is a
// contact between two sides (static geometry, a body, a link of a tree) at a world point with a
// unit normal, or a joint limit: a unilateral row on one degree of freedom of a tree, the unit
// row +e_dof (lower limit) or -e_dof (upper limit). The row's Jacobian over the stacked velocity
// u is n^T J_a - n^T J_b, with J = [I3, -(r x)] for a body and the point Jacobian
// dynamics::TreePointJacobian for a link, so that a normal force f acts on the members through
// J^T f. The group's inverse mass is block diagonal: 1/m and I^-1 for a body, (M + h D)^-1 of the
// factor kept by dynamics::TreeFactor for a tree; the effective inverse mass of the rows is
// W = J M^-1 J^T, the matrix Eq. 5 and Eq. 8 work with.
//
// Everything runs on buffers sized by the JointGroupSolver constructor: no call allocates or
// throws; a problem that does not fit or is not finite returns an error and changes no velocity.
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "contact/impulse.h"
#include "dynamics/tree.h"

namespace rigidtouch::contact {

/// A kinematic tree as a member of a group. `data` must hold the kinematics at the step's
/// positions, the mass matrix and the factor of M + h D (dynamics::TreeFactor); the group
/// functions change only its qvel.
struct GroupTree {
  const dynamics::TreeModel* model = nullptr;
  dynamics::TreeData* data = nullptr;
};

/// What one side of a row moves.
enum class RowSideKind {
  kStatic,  ///< static geometry: no velocity, infinite mass
  kBody,    ///< a free rigid body: `member` indexes JointGroup::bodies
  kLink,    ///< a link of a tree: `member` indexes JointGroup::trees, `index` its body
  kJoint,   ///< a joint limit: `member` indexes JointGroup::trees, `index` its degree of freedom
};

/// One side of a row.
struct RowSide {
  RowSideKind kind = RowSideKind::kStatic;
  int member = -1;
  int index = -1;
};

/// One unilateral row of a group: a contact, or a joint limit (side a of kind kJoint, side b
/// static). Its normal force (N; N m for a hinge limit) at the new velocity is
/// phi_n - c_n u_n, u_n the row's new normal velocity (negative: approaching); while it sticks,
/// its tangential force is phi_t - c_t u_t. A limit has no tangential force.
struct JointRow {
  RowSide a, b;
  Vec3 n_W = Vec3::UnitZ();  // unit normal from b towards a (contacts only)
  Vec3 p_W = Vec3::Zero();   // contact point, world [m] (contacts only)
  double limit_sign = 1.0;   // a limit: +1 lower (row +e_dof), -1 upper (row -e_dof)
  // penalty law (the caller's spring-damper, linearised as in dynamics::ImplicitContact)
  double phi_n_N = 0.0;         // normal force independent of the new velocity
  double c_n_Ns_per_m = 0.0;    // h k + b; 0 makes the normal force explicit
  bool stick = false;           // tangential rows present (contacts only)
  Vec3 phi_t_W = Vec3::Zero();  // the stick anchor's force, in the tangent plane
  double c_t_Ns_per_m = 0.0;
  double mu_static = 0.0;   // Coulomb cone while sticking
  double mu_kinetic = 0.0;  // kinetic friction once slipping
  // the impulse due this tick: (1 + e) / (N - i + 1) of the row's schedule (Eq. 5, Eq. 8), in
  // [0, 2]; 0: no impulse on this row this tick
  double impulse_scale = 0.0;
  // outputs
  double normal_force_N = 0.0;             // SolveJointPenalty, >= 0
  Vec3 friction_force_N_W = Vec3::Zero();  // SolveJointPenalty, |f_t| <= mu normal_force_N
  bool slipped = false;                    // SolveJointPenalty: the row's friction slipped
  double impulse_Ns = 0.0;                 // ApplyJointImpulses, >= 0 (N m s for a hinge limit)
};

/// One group: its members and rows. Bodies' velocities and trees' qvel are read and written.
struct JointGroup {
  std::span<SolverBody> bodies;
  std::span<const Vec3> body_com_W;  // each body's centre of mass, world [m]
  std::span<GroupTree> trees;
  std::span<JointRow> rows;
};

/// Why a call changed nothing.
enum class JointGroupError {
  kNone = 0,
  kTooManyRows,  ///< more rows than the solver's capacity
  kTooManyDofs,  ///< more stacked velocities than the solver's capacity
  kBadRow,       ///< a side names a missing member, link or dof, or a limit is not on side a
  kNotFactored,  ///< a tree has no kept factor (dynamics::TreeFactor)
  kNonFinite,    ///< NaN or infinity in the velocities, rows or result
  kBadScale,     ///< an impulse scale outside [0, 2]
};

/// What SolveJointPenalty did.
struct JointPenaltyStats {
  JointGroupError error = JointGroupError::kNone;
  int passes = 0;                      // solves of the implicit system
  int dropped_rows = 0;                // rows that would pull, solved again without them
  int slipped_rows = 0;                // rows whose friction slipped
  bool frictionless_fallback = false;  // the passes ran out; solved again without friction
};

/// What ApplyJointImpulses did.
struct JointImpulseStats {
  JointGroupError error = JointGroupError::kNone;
  int solves = 0;                 // one per distinct impulse scale
  int iterations = 0;             // active-set changes, summed
  bool converged = true;          // every solve met its stopping test
  double max_approach_mps = 0.0;  // largest plastic approach left on a row with scale 1 or more
};

/// Preallocated solver of joint-space groups. One per thread.
class JointGroupSolver {
 public:
  /// Sizes the buffers for groups of up to `max_rows` rows and `max_dofs` stacked velocities
  /// (6 per body plus each tree's nv). Throws rigidtouch::Error if either is below 1.
  JointGroupSolver(int max_rows, int max_dofs);

  /// The implicit penalty step of the group's rows over h (Eq. 1 with backward Euler on the
  /// rows' velocity terms): the members' velocities, which must already hold the step's free
  /// motion, become u+ = u + M^-1 J^T h f(u+). A row whose normal force would pull is dropped and
  /// the group solved again; a sticking row whose force leaves mu_static times its normal force
  /// slips (kinetic friction mu_kinetic f_n along its trial force, explicit) and the group is
  /// solved again; a slipping row's friction is kept within mu_kinetic times the normal force of
  /// the final solve. If the passes run out, the group is solved without friction. Writes each
  /// row's forces and the trees' joint forces (TreeContactForce). M^-1 is (M + h D)^-1 for a
  /// tree, the kept factor.
  JointPenaltyStats SolveJointPenalty(const JointGroup& group, double h_s) noexcept;

  /// The group's collision impulses this tick: the rows with impulse_scale > 0, one non-negative
  /// plastic solve (min 1/2 p^T W p + p^T J u, p >= 0) per distinct scale s, smallest first, each
  /// applied as s p through M^-1 J^T (Eq. 2); s = 1 + e is Eq. 5, s = 1 / (N - i + 1) Eq. 8.
  JointImpulseStats ApplyJointImpulses(const JointGroup& group) noexcept;

  /// J^T f of the last SolveJointPenalty on tree `tree` (nv entries: N or N m per dof): the joint
  /// forces of the group's contact and limit forces.
  Eigen::Ref<const Eigen::VectorXd> TreeContactForce(int tree) const;

  /// Capacity in rows (contacts and limits).
  int max_rows() const { return max_rows_; }
  /// Capacity in stacked velocities.
  int max_dofs() const { return max_dofs_; }

 private:
  JointGroupError Assemble(const JointGroup& group);
  JointGroupError AddSide(const JointGroup& group, const RowSide& side, double sign,
                          const JointRow& row, int first);
  void ApplyBodyInverseMass(const JointGroup& group, int column);
  void ApplyTreeInverseMass(const JointGroup& group);
  void Gather(const JointGroup& group);
  void Scatter(const JointGroup& group) const;
  bool SolveImplicit(double h_s);
  bool UpdateRowStates(const JointGroup& group, JointPenaltyStats& stats, bool last_pass);
  bool SolveNonNegative(int m, int& iterations);
  bool SolveFreeSet(int m, int& f);

  int max_rows_ = 0;
  int max_dofs_ = 0;
  int rows_ = 0;  // internal rows, 3 per group row: normal, tangent 1, tangent 2
  int dofs_ = 0;
  double inv_h_ = 0.0;  // 1 / h of the penalty solve: a row's force is phi + lambda / h
  std::vector<int> body_offset_, tree_offset_;
  std::vector<int> tree_dofs_;
  Eigen::MatrixXd jac_t_;    // (max_dofs x 3 max_rows) the rows' Jacobians, one per column
  Eigen::MatrixXd y_;        // (max_dofs x 3 max_rows) M^-1 J^T
  Eigen::MatrixXd yt_;       // (3 max_rows x max_dofs) a tree's block of Y^T, solved row by row
  std::vector<char> solve_;  // per internal row: its Jacobian is not zero (Y gets M^-1 J^T)
  Eigen::MatrixXd w_;        // (3 max_rows)^2 W = J M^-1 J^T
  Eigen::MatrixXd point_trans_, point_rot_;  // (3 x max_dofs) a point's Jacobians
  Eigen::VectorXd u_;                        // stacked velocity
  Eigen::VectorXd force_;                    // stacked J^T f of the last penalty solve
  Eigen::VectorXd b_;                        // J u at the start of a solve (internal rows)
  Eigen::VectorXd phi_, c_, lambda_, rhs_;   // per internal row
  std::vector<char> active_;                 // per internal row: takes part in the solve
  std::vector<int> index_;                   // rows of the current small system
  Eigen::MatrixXd k_;                        // its matrix, then its Cholesky factor
  Eigen::VectorXd p_, z_, g_;                // the non-negative solve's impulse, trial, gradient
  std::vector<char> in_set_;
  std::vector<int> free_;
  std::vector<double> scales_;
};

/// Kinetic energy of the group's members [J]: 1/2 m |v|^2 + 1/2 w^T I w per body and
/// 1/2 qvel^T M qvel per tree (M as last computed). Does not allocate.
double JointGroupKineticEnergy(const JointGroup& group);

}  // namespace rigidtouch::contact
