// Kinematic trees in joint space (issue 45, part 1): bodies joined by hinge, slide, ball and free
// joints, their generalized coordinates, forward kinematics, the joint-space mass matrix (composite
// rigid body algorithm), bias forces (recursive Newton-Euler), point Jacobians, a dense LDL^T of
// the mass matrix kept between calls, and a semi-implicit step. Coordinates and frames follow
// MuJoCo 2.2.2 so that a tree read from an mjModel (src/io/mjcf_tree.h) has MuJoCo's qpos and
// qvel (docs/decisions.md, "Kinematic trees in joint space").
//
// Every per-tick function works in a TreeData sized once by MakeTreeData and never allocates.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::dynamics {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Joint kinds, with MuJoCo's coordinates: free = 3 position (world) + 4 quaternion (w, x, y, z)
/// in qpos, linear velocity of the body origin (world) + angular velocity (body frame) in qvel;
/// ball = quaternion / angular velocity in the frame after the joint; hinge and slide = 1 / 1.
enum class JointType { kFree, kBall, kSlide, kHinge };

struct TreeJoint {
  JointType type = JointType::kHinge;
  Vec3 axis = Vec3::UnitZ();  // hinge and slide axis in the body frame (unit)
  Vec3 pos_m = Vec3::Zero();  // anchor in the body frame (hinge and ball rotate about it)
  double ref = 0.0;           // hinge [rad] / slide [m] coordinate of the body's given offset
  double spring_ref = 0.0;    // coordinate at which the joint spring is relaxed
  Quat spring_quat = Quat::Identity();  // ball: the orientation at which its spring is relaxed
  double stiffness = 0.0;     // N m/rad (hinge, ball) or N/m (slide); a free joint has none here
  double damping = 0.0;       // N m s/rad or N s/m, per degree of freedom
  double armature = 0.0;      // kg m^2 or kg, added to the mass matrix's diagonal
  double frictionloss = 0.0;  // N m or N, dry friction bound per degree of freedom (>= 0)
};

struct TreeBody {
  int parent = -1;               // index of an earlier body, -1 for the world
  Vec3 pos_m = Vec3::Zero();     // body frame origin in the parent frame
  Quat quat = Quat::Identity();  // body frame orientation in the parent frame
  double mass_kg = 0.0;
  Vec3 com_m = Vec3::Zero();         // centre of mass in the body frame
  Mat3 inertia_kgm2 = Mat3::Zero();  // about the centre of mass, body frame axes
  std::vector<TreeJoint> joints;     // applied in order, as MuJoCo does
};

/// A validated tree with its coordinate addresses. Built by MakeTree; never changed afterwards.
struct TreeModel {
  std::vector<TreeBody> bodies;
  Vec3 gravity_mps2 = Vec3(0, 0, -9.81);
  int nq = 0;  // qpos size
  int nv = 0;  // qvel size (degrees of freedom)
  // per joint, in body order then the body's order (MuJoCo's joint order)
  std::vector<int> joint_body, joint_index, joint_qadr, joint_dadr;
  std::vector<int> body_joint_begin, body_joint_end;
  std::vector<int> dof_body;
  std::vector<int> dof_joint;
  std::vector<int> dof_parent;     // previous dof on the path to the root, -1 at the root
  std::vector<int> body_last_dof;  // last dof moving the body (own or an ancestor's), or -1
  std::vector<int> friction_dofs;  // the dofs with frictionloss > 0, ascending
  Eigen::VectorXd qpos0;           // coordinates of the bodies' given offsets
  const TreeJoint& joint(int j) const { return bodies[joint_body[j]].joints[joint_index[j]]; }
};

/// Validates (parents before children, unit axes, positive masses, symmetric positive inertias,
/// a free joint only alone in a child of the world) and computes the addresses. Throws Error.
TreeModel MakeTree(std::vector<TreeBody> bodies, const Vec3& gravity_mps2);

/// Everything that changes, sized once for the model: the state, kinematics and every scratch.
struct TreeData {
  Eigen::VectorXd qpos, qvel;
  // kinematics (TreeKinematics)
  std::vector<Mat3> R_WB;          // body rotations
  std::vector<Vec3> x_W;           // body origins
  std::vector<Vec3> com_W;         // centres of mass
  std::vector<Vec3> joint_axis_W;  // hinge and slide axes (z of the body for ball and free)
  std::vector<Vec3> joint_anchor_W;
  Eigen::Matrix<double, 6, Eigen::Dynamic> S;  // dof motions [w; velocity of the world origin]
  std::vector<Mat6> inertia_O;  // spatial inertia of each body about the world origin
  // the (normalised) qpos and the model the kinematics above were computed from, for
  // TreeUpdateKinematics; kin_scratch is its nq scratch
  Eigen::VectorXd kin_qpos, kin_scratch;
  const TreeModel* kin_model = nullptr;
  // velocities and dynamics
  std::vector<Vec6> V, A, F;    // body velocities, bias accelerations, forces (RNEA)
  std::vector<Mat6> composite;  // composite inertias (CRBA)
  Eigen::MatrixXd M;            // joint-space mass matrix with armature
  Eigen::VectorXd bias;         // gravity + Coriolis/centrifugal (MuJoCo's qfrc_bias)
  Eigen::VectorXd passive;      // spring and damper forces at the state
  Eigen::MatrixXd factor;       // LDL^T of M + h D: L below the diagonal, D on it
  Eigen::VectorXd scratch_v, scratch_w;
  bool factored = false;
  // dry joint friction (TreeFrictionImpulse), sized for the model's friction dofs F
  Eigen::MatrixXd friction_A;       // (M + h D)^-1 restricted to F x F
  Eigen::VectorXd friction_v;       // velocities of F before the friction impulse
  Eigen::VectorXd friction_lambda;  // friction impulses on F [N m s or N s]
  int friction_sweeps = 0;          // Gauss-Seidel sweeps of the last solve
};

/// State at qpos0 with zero velocity, every array sized for the model.
TreeData MakeTreeData(const TreeModel& model);

/// Body poses, joint axes and anchors, dof motions and spatial inertias at qpos. Normalises the
/// quaternions of qpos in place (as MuJoCo's mj_kinematics does).
void TreeKinematics(const TreeModel& model, TreeData& data);

/// TreeKinematics, skipped when it would recompute what data already holds: when qpos with its
/// quaternions normalised is bit for bit the qpos of the last TreeKinematics on this data with
/// this model (kinematics depend on nothing else), only qpos is normalised in place, exactly as
/// TreeKinematics would. Otherwise runs TreeKinematics. Never allocates.
void TreeUpdateKinematics(const TreeModel& model, TreeData& data);

/// Joint-space mass matrix into data.M (composite rigid body algorithm) plus armature. Needs
/// TreeKinematics.
void TreeMassMatrix(const TreeModel& model, TreeData& data);

/// Bias forces into data.bias: the joint forces that give zero acceleration at qvel under gravity
/// (recursive Newton-Euler with qacc = 0), MuJoCo's qfrc_bias. Needs TreeKinematics.
void TreeBiasForces(const TreeModel& model, TreeData& data);

/// Spring and damper forces into data.passive: -k (q - spring_ref) on hinges and slides, -k r on
/// a ball's three dofs with r the rotation vector of spring_quat^-1 q (angle wrapped into
/// [-pi, pi], in the frame after the joint: MuJoCo 2.2.2's ball spring), -d qdot on every dof.
void TreePassiveForces(const TreeModel& model, TreeData& data);

/// Jacobians of the world point p_W moving with `body`: jac_trans (3 x nv) maps qvel to the
/// point's velocity, jac_rot (3 x nv) to the body's angular velocity. Needs TreeKinematics.
void TreePointJacobian(const TreeModel& model, const TreeData& data, int body, const Vec3& p_W,
                       Eigen::Ref<Eigen::MatrixXd> jac_trans, Eigen::Ref<Eigen::MatrixXd> jac_rot);

/// Factors M + h diag(damping) into data.factor (LDL^T); h = 0 factors M itself. Needs
/// TreeMassMatrix. Returns false when a pivot is not positive (then data.factored is false).
bool TreeFactor(const TreeModel& model, TreeData& data, double h_s);

/// x <- (M + h D)^-1 x with the kept factor.
void TreeSolve(const TreeData& data, Eigen::Ref<Eigen::VectorXd> x);

/// TreeSolve on every row of xt (m x nv) at once: row r <- ((M + h D)^-1 row r^T)^T. Each row
/// gets TreeSolve's operations in TreeSolve's order (bit-identical results); the rows are
/// processed together so that one pass over the factor serves them all.
void TreeSolveRows(const TreeData& data, Eigen::Ref<Eigen::MatrixXd> xt);

/// The effective inverse mass J (M + h D)^-1 J^T (k x k) of k constraint rows J (k x nv) with the
/// kept factor: the matrix Eq. 5 and Eq. 8 pseudo-invert in joint space. Uses data.scratch_v.
void TreeEffectiveInverseMass(TreeData& data, const Eigen::Ref<const Eigen::MatrixXd>& J,
                              Eigen::Ref<Eigen::MatrixXd> out);

/// Dry joint friction over a step of length h (docs/decisions.md, "Dry joint friction"): the
/// generalized impulse lambda on the friction dofs F with |lambda_i| <= h frictionloss_i that
/// minimizes 1/2 lambda^T A lambda + lambda^T v_F, A = (M + h D)^-1 on F x F (the kept factor),
/// v_F the dofs' velocities before it; then qvel += (M + h D)^-1 lambda. At the minimum a dof
/// whose impulse is inside its bound ends with zero velocity (it sticks) and one at its bound
/// slides with the full friction opposing its velocity. Solved by projected Gauss-Seidel (at most
/// kFrictionMaxSweeps sweeps, stopping when no impulse changes by more than 1e-12 of its bound);
/// when it converged, the sticking dofs' velocities are set to exactly 0. Needs TreeFactor at
/// this h. Never allocates or throws; does nothing without friction dofs. Returns the sweeps.
int TreeFrictionImpulse(const TreeModel& model, TreeData& data, double h_s);
inline constexpr int kFrictionMaxSweeps = 200;

/// The velocity update of a step, after TreeFactor at h: qvel += h (M + h D)^-1 (tau - bias +
/// passive) (damping implicit), then the dry friction impulse (TreeFrictionImpulse).
void TreeFreeVelocity(const TreeModel& model, TreeData& data, double h_s,
                      const Eigen::Ref<const Eigen::VectorXd>& tau);

/// One semi-implicit step of length h with joint forces tau (nv): kinematics, mass matrix, bias,
/// passive forces, factor, TreeFreeVelocity; then the positions move with the new velocities
/// (quaternions by the exponential map, renormalised). Returns false (state unchanged) when the
/// factorisation fails.
bool TreeStep(const TreeModel& model, TreeData& data, double h_s,
              const Eigen::Ref<const Eigen::VectorXd>& tau);

/// qpos <- qpos integrated over h with qvel (hinge, slide linear; ball and free quaternions by
/// q exp(h w / 2) with w in the body frame, as MuJoCo's mj_integratePos).
void TreeIntegratePositions(const TreeModel& model, TreeData& data, double h_s);

/// 1/2 qvel^T M qvel (armature included) [J]. Needs TreeMassMatrix at the current state.
double TreeKineticEnergy(TreeData& data);

/// Gravity potential -sum m g.com plus joint springs 1/2 k (q - spring_ref)^2 (a ball's 1/2 k
/// |r|^2, r as in TreePassiveForces) [J]. Needs TreeKinematics.
double TreePotentialEnergy(const TreeModel& model, const TreeData& data);

}  // namespace rigidtouch::dynamics
