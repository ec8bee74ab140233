// Kinematic trees in joint space: model validation, kinematics, CRBA, RNEA, Jacobians, LDL^T and
// the semi-implicit step (docs/method.md, "Joint space"). Spatial vectors are Plucker coordinates
// in the world frame about the world origin, [angular; linear]: a motion's linear part is the
// velocity of the material point at the origin, a force's angular part the torque about the
// origin. In one fixed frame the composite inertias are plain sums and no transforms are needed.
#include "dynamics/tree.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

namespace rigidtouch::dynamics {
namespace {

Mat3 CrossMatrix(const Vec3& v) {
  Mat3 s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// Spatial motion cross product V x S (the rate of a motion S fixed in a frame moving with V).
Vec6 CrossMotion(const Vec6& V, const Vec6& S) {
  Vec6 out;
  out.head<3>() = V.head<3>().cross(S.head<3>());
  out.tail<3>() = V.head<3>().cross(S.tail<3>()) + V.tail<3>().cross(S.head<3>());
  return out;
}

// Spatial force cross product V x* F.
Vec6 CrossForce(const Vec6& V, const Vec6& F) {
  Vec6 out;
  out.head<3>() = V.head<3>().cross(F.head<3>()) + V.tail<3>().cross(F.tail<3>());
  out.tail<3>() = V.head<3>().cross(F.tail<3>());
  return out;
}

int DofCount(JointType t) {
  return t == JointType::kFree ? 6 : t == JointType::kBall ? 3 : 1;
}
int QposCount(JointType t) {
  return t == JointType::kFree ? 7 : t == JointType::kBall ? 4 : 1;
}

void CheckBody(const std::vector<TreeBody>& bodies, int i) {
  const TreeBody& b = bodies[i];
  const std::string name = "tree body " + std::to_string(i);
  if (b.parent < -1 || b.parent >= i) throw Error(name + ": parent must be -1 or an earlier body");
  if (!(b.mass_kg > 0.0) || !std::isfinite(b.mass_kg)) throw Error(name + ": mass must be > 0");
  const Mat3& I = b.inertia_kgm2;
  if (!I.allFinite() || (I - I.transpose()).cwiseAbs().maxCoeff() > 1e-12 * I.norm() ||
      !(I.ldlt().vectorD().minCoeff() > 0.0)) {
    throw Error(name + ": inertia must be finite, symmetric and positive definite");
  }
  if (std::abs(b.quat.norm() - 1.0) > 1e-9) throw Error(name + ": quaternion must be unit");
  for (const TreeJoint& j : b.joints) {
    if (j.type == JointType::kFree && (b.joints.size() != 1 || b.parent != -1)) {
      throw Error(name + ": a free joint must be alone in a child of the world (as in MuJoCo)");
    }
    if ((j.type == JointType::kHinge || j.type == JointType::kSlide) &&
        std::abs(j.axis.norm() - 1.0) > 1e-9) {
      throw Error(name + ": joint axis must be unit");
    }
    if (!(j.damping >= 0.0 && j.armature >= 0.0 && j.stiffness >= 0.0 && j.frictionloss >= 0.0 &&
          std::isfinite(j.frictionloss))) {
      throw Error(name + ": joint damping, armature, stiffness and frictionloss must be >= 0");
    }
    if (j.stiffness != 0.0 && j.type == JointType::kFree) {
      throw Error(name + ": a free joint has no spring here (stiffness must be 0)");
    }
    if (j.type == JointType::kBall && std::abs(j.spring_quat.norm() - 1.0) > 1e-9) {
      throw Error(name + ": a ball joint's spring quaternion must be unit");
    }
  }
}

// Appends the joint's qpos0: the coordinates at which the body sits at its given offset.
void AppendQpos0(const TreeBody& b, const TreeJoint& j, std::vector<double>& q0) {
  switch (j.type) {
    case JointType::kFree:
      q0.insert(q0.end(), {b.pos_m.x(), b.pos_m.y(), b.pos_m.z(), b.quat.w(), b.quat.x(),
                           b.quat.y(), b.quat.z()});
      break;
    case JointType::kBall:
      q0.insert(q0.end(), {1.0, 0.0, 0.0, 0.0});
      break;
    default:
      q0.push_back(j.ref);
  }
}

// Quaternion stored at qpos[adr] as (w, x, y, z), normalised in place.
Quat NormalizedQuat(Eigen::VectorXd& qpos, int adr) {
  Quat q(qpos[adr], qpos[adr + 1], qpos[adr + 2], qpos[adr + 3]);
  const double n = q.norm();
  q = n > 0.0 ? Quat(q.coeffs() / n) : Quat::Identity();
  qpos[adr] = q.w();
  qpos[adr + 1] = q.x();
  qpos[adr + 2] = q.y();
  qpos[adr + 3] = q.z();
  return q;
}

// The rotation vector (axis times angle, the angle wrapped into [-pi, pi]) of spring_quat^-1 q for
// the ball joint's quaternion at qpos[adr], in the frame after the joint: what MuJoCo 2.2.2's
// ball spring pulls back (mj_passive with mju_subQuat), written here from its definition.
Vec3 BallSpringRotation(const TreeJoint& jt, const Eigen::VectorXd& qpos, int adr) {
  const Quat q = Quat(qpos[adr], qpos[adr + 1], qpos[adr + 2], qpos[adr + 3]).normalized();
  const Quat d = jt.spring_quat.conjugate() * q;
  const Vec3 v = d.vec();
  const double s = v.norm();
  if (!(s > 0.0)) return Vec3::Zero();
  double angle = 2.0 * std::atan2(s, d.w());  // in [0, 2 pi]
  if (angle > M_PI) angle -= 2.0 * M_PI;      // the shorter way round
  return v / s * angle;
}

// Spatial inertia about the world origin of a body with mass m, centre c and inertia Ic (world).
Mat6 InertiaAboutOrigin(double m, const Vec3& c, const Mat3& Ic) {
  const Mat3 C = CrossMatrix(c);
  Mat6 I;
  I.topLeftCorner<3, 3>() = Ic - m * C * C;
  I.topRightCorner<3, 3>() = m * C;
  I.bottomLeftCorner<3, 3>() = -m * C;
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
  return I;
}

// Rotation motion about the world axis a through the point c.
Vec6 Rotation(const Vec3& a, const Vec3& c) {
  Vec6 s;
  s << a, c.cross(a);
  return s;
}

// Applies joint j of body i to the running pose (R, x), writing its axes and dof motions.
void ApplyJoint(const TreeModel& model, TreeData& data, int j, Mat3& R, Vec3& x) {
  const TreeJoint& jt = model.joint(j);
  const int qa = model.joint_qadr[j], da = model.joint_dadr[j];
  Eigen::VectorXd& q = data.qpos;
  const Vec3 axis_W = R * jt.axis;
  const Vec3 anchor_W = x + R * jt.pos_m;
  data.joint_axis_W[j] = axis_W;
  data.joint_anchor_W[j] = anchor_W;
  switch (jt.type) {
    case JointType::kFree: {
      x = q.segment<3>(qa);
      R = NormalizedQuat(q, qa + 3).toRotationMatrix();
      data.joint_axis_W[j] = Vec3::UnitZ();  // MuJoCo's xaxis of a free joint
      data.joint_anchor_W[j] = x;
      for (int k = 0; k < 3; ++k) {
        data.S.col(da + k) << Vec3::Zero(), Vec3::Unit(k);  // world translations
        data.S.col(da + 3 + k) = Rotation(R.col(k), x);     // rotations about body axes
      }
      break;
    }
    case JointType::kBall:
      // the angular velocity is in the frame after the joint (q' = q [0, w] / 2)
      R = R * NormalizedQuat(q, qa).toRotationMatrix();
      x = anchor_W - R * jt.pos_m;
      for (int k = 0; k < 3; ++k) data.S.col(da + k) = Rotation(R.col(k), anchor_W);
      break;
    case JointType::kHinge:
      R = R * Eigen::AngleAxisd(q[qa] - jt.ref, jt.axis).toRotationMatrix();
      x = anchor_W - R * jt.pos_m;  // the anchor stays where it was
      data.S.col(da) = Rotation(axis_W, anchor_W);
      break;
    case JointType::kSlide:
      x += axis_W * (q[qa] - jt.ref);
      data.S.col(da) << Vec3::Zero(), axis_W;
      break;
  }
}

}  // namespace

TreeModel MakeTree(std::vector<TreeBody> bodies, const Vec3& gravity_mps2) {
  TreeModel m;
  if (!gravity_mps2.allFinite()) throw Error("tree gravity must be finite");
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) CheckBody(bodies, i);
  m.bodies = std::move(bodies);
  m.gravity_mps2 = gravity_mps2;
  const int nb = static_cast<int>(m.bodies.size());
  m.body_joint_begin.assign(nb, 0);
  m.body_joint_end.assign(nb, 0);
  m.body_last_dof.assign(nb, -1);
  std::vector<double> q0;
  for (int i = 0; i < nb; ++i) {
    const TreeBody& b = m.bodies[i];
    int last = b.parent < 0 ? -1 : m.body_last_dof[b.parent];
    m.body_joint_begin[i] = static_cast<int>(m.joint_body.size());
    for (int k = 0; k < static_cast<int>(b.joints.size()); ++k) {
      const TreeJoint& jt = b.joints[k];
      const int j = static_cast<int>(m.joint_body.size());
      m.joint_body.push_back(i);
      m.joint_index.push_back(k);
      m.joint_qadr.push_back(m.nq);
      m.joint_dadr.push_back(m.nv);
      AppendQpos0(b, jt, q0);
      m.nq += QposCount(jt.type);
      for (int d = 0; d < DofCount(jt.type); ++d) {
        m.dof_body.push_back(i);
        m.dof_joint.push_back(j);
        m.dof_parent.push_back(last);
        if (jt.frictionloss > 0.0) m.friction_dofs.push_back(m.nv);
        last = m.nv++;
      }
    }
    m.body_joint_end[i] = static_cast<int>(m.joint_body.size());
    m.body_last_dof[i] = last;
  }
  m.qpos0 = Eigen::Map<const Eigen::VectorXd>(q0.data(), m.nq);
  return m;
}

TreeData MakeTreeData(const TreeModel& model) {
  TreeData d;
  const int nb = static_cast<int>(model.bodies.size());
  const int nj = static_cast<int>(model.joint_body.size());
  const int nv = model.nv;
  d.qpos = model.qpos0;
  d.qvel = Eigen::VectorXd::Zero(nv);
  d.R_WB.assign(nb, Mat3::Identity());
  d.x_W.assign(nb, Vec3::Zero());
  d.com_W.assign(nb, Vec3::Zero());
  d.joint_axis_W.assign(nj, Vec3::Zero());
  d.joint_anchor_W.assign(nj, Vec3::Zero());
  d.S = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, nv);
  d.inertia_O.assign(nb, Mat6::Zero());
  d.kin_qpos = Eigen::VectorXd::Zero(model.nq);
  d.kin_scratch = Eigen::VectorXd::Zero(model.nq);
  d.V.assign(nb, Vec6::Zero());
  d.A.assign(nb, Vec6::Zero());
  d.F.assign(nb, Vec6::Zero());
  d.composite.assign(nb, Mat6::Zero());
  d.M = Eigen::MatrixXd::Zero(nv, nv);
  d.bias = Eigen::VectorXd::Zero(nv);
  d.passive = Eigen::VectorXd::Zero(nv);
  d.factor = Eigen::MatrixXd::Zero(nv, nv);
  d.scratch_v = Eigen::VectorXd::Zero(nv);
  d.scratch_w = Eigen::VectorXd::Zero(nv);
  const int nf = static_cast<int>(model.friction_dofs.size());
  d.friction_A = Eigen::MatrixXd::Zero(nf, nf);
  d.friction_v = Eigen::VectorXd::Zero(nf);
  d.friction_lambda = Eigen::VectorXd::Zero(nf);
  TreeKinematics(model, d);
  return d;
}

void TreeKinematics(const TreeModel& model, TreeData& data) {
  const int nb = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nb; ++i) {
    const TreeBody& b = model.bodies[i];
    Mat3 R = b.quat.toRotationMatrix();
    Vec3 x = b.pos_m;
    if (b.parent >= 0) {
      x = data.x_W[b.parent] + data.R_WB[b.parent] * b.pos_m;
      R = data.R_WB[b.parent] * R;
    }
    for (int j = model.body_joint_begin[i]; j < model.body_joint_end[i]; ++j) {
      ApplyJoint(model, data, j, R, x);
    }
    data.R_WB[i] = R;
    data.x_W[i] = x;
    data.com_W[i] = x + R * b.com_m;
    data.inertia_O[i] =
        InertiaAboutOrigin(b.mass_kg, data.com_W[i], R * b.inertia_kgm2 * R.transpose());
  }
  data.kin_qpos = data.qpos;  // same size: no allocation
  data.kin_model = &model;
}

void TreeUpdateKinematics(const TreeModel& model, TreeData& data) {
  const int nq = static_cast<int>(data.qpos.size());
  bool same =
      data.kin_model == &model && data.kin_qpos.size() == nq && data.kin_scratch.size() == nq;
  if (same) {
    // the qpos TreeKinematics would compute from: its quaternions normalised by NormalizedQuat
    Eigen::VectorXd& q = data.kin_scratch;
    q = data.qpos;
    const int nj = static_cast<int>(model.joint_body.size());
    for (int j = 0; j < nj; ++j) {
      const JointType type = model.joint(j).type;
      if (type == JointType::kFree) NormalizedQuat(q, model.joint_qadr[j] + 3);
      if (type == JointType::kBall) NormalizedQuat(q, model.joint_qadr[j]);
    }
    // bit for bit (a signed zero or a NaN differs)
    same = std::memcmp(q.data(), data.kin_qpos.data(), sizeof(double) * nq) == 0;
  }
  if (!same) {
    TreeKinematics(model, data);
    return;
  }
  data.qpos = data.kin_scratch;
}

void TreeMassMatrix(const TreeModel& model, TreeData& data) {
  const int nb = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nb; ++i) data.composite[i] = data.inertia_O[i];
  // children come after parents, so one backward sweep sums every subtree
  for (int i = nb - 1; i >= 0; --i) {
    const int p = model.bodies[i].parent;
    if (p >= 0) data.composite[p] += data.composite[i];
  }
  data.M.setZero();
  for (int d = 0; d < model.nv; ++d) {
    // dof d moves its body's whole subtree: its force on every dof at or above it
    const Vec6 F = data.composite[model.dof_body[d]] * data.S.col(d);
    for (int e = d; e >= 0; e = model.dof_parent[e]) {
      const double m_de = data.S.col(e).dot(F);
      data.M(e, d) = m_de;
      data.M(d, e) = m_de;
    }
    const TreeJoint& jt = model.joint(model.dof_joint[d]);
    data.M(d, d) += jt.armature;
  }
}

void TreeBiasForces(const TreeModel& model, TreeData& data) {
  const int nb = static_cast<int>(model.bodies.size());
  Vec6 a_world;
  a_world << Vec3::Zero(), -model.gravity_mps2;  // gravity as an upward acceleration of the base
  for (int i = 0; i < nb; ++i) {
    const int p = model.bodies[i].parent;
    Vec6 V = p >= 0 ? data.V[p] : Vec6::Zero();
    Vec6 A = p >= 0 ? data.A[p] : a_world;
    for (int j = model.body_joint_begin[i]; j < model.body_joint_end[i]; ++j) {
      const JointType type = model.joint(j).type;
      const int da = model.joint_dadr[j];
      const int n = DofCount(type);
      // A dof's motion is fixed in the frame before its joint, except the free joint's
      // translations (fixed in the world) and its rotations (fixed in the frame after the
      // translation). Within a ball joint the terms S_k x S_l w_k w_l cancel in pairs, so the
      // velocity before the joint serves all three.
      int first_rate = 0;
      if (type == JointType::kFree) {
        V += data.S.middleCols<3>(da) * data.qvel.segment<3>(da);
        first_rate = 3;
      }
      for (int k = first_rate; k < n; ++k) {
        A += CrossMotion(V, data.S.col(da + k)) * data.qvel[da + k];
      }
      for (int k = first_rate; k < n; ++k) V += data.S.col(da + k) * data.qvel[da + k];
    }
    data.V[i] = V;
    data.A[i] = A;
    data.F[i] = data.inertia_O[i] * A + CrossForce(V, data.inertia_O[i] * V);
  }
  for (int i = nb - 1; i >= 0; --i) {
    const int p = model.bodies[i].parent;
    if (p >= 0) data.F[p] += data.F[i];
  }
  for (int d = 0; d < model.nv; ++d) data.bias[d] = data.S.col(d).dot(data.F[model.dof_body[d]]);
}

void TreePassiveForces(const TreeModel& model, TreeData& data) {
  const int nj = static_cast<int>(model.joint_body.size());
  for (int j = 0; j < nj; ++j) {
    const TreeJoint& jt = model.joint(j);
    const int da = model.joint_dadr[j];
    for (int k = 0; k < DofCount(jt.type); ++k) {
      data.passive[da + k] = -jt.damping * data.qvel[da + k];
    }
    if (jt.stiffness == 0.0) continue;
    if (jt.type == JointType::kHinge || jt.type == JointType::kSlide) {
      data.passive[da] -= jt.stiffness * (data.qpos[model.joint_qadr[j]] - jt.spring_ref);
    } else if (jt.type == JointType::kBall) {
      data.passive.segment<3>(da) -=
          jt.stiffness * BallSpringRotation(jt, data.qpos, model.joint_qadr[j]);
    }
  }
}

void TreePointJacobian(const TreeModel& model, const TreeData& data, int body, const Vec3& p_W,
                       Eigen::Ref<Eigen::MatrixXd> jac_trans, Eigen::Ref<Eigen::MatrixXd> jac_rot) {
  jac_trans.setZero();
  jac_rot.setZero();
  for (int e = model.body_last_dof[body]; e >= 0; e = model.dof_parent[e]) {
    const Vec3 w = data.S.col(e).head<3>();
    jac_rot.col(e) = w;
    jac_trans.col(e) = data.S.col(e).tail<3>() + w.cross(p_W);  // origin velocity moved to p
  }
}

bool TreeFactor(const TreeModel& model, TreeData& data, double h_s) {
  const int n = model.nv;
  Eigen::MatrixXd& L = data.factor;
  L = data.M;  // same size: no allocation
  for (int d = 0; d < n; ++d) L(d, d) += h_s * model.joint(model.dof_joint[d]).damping;
  data.factored = false;
  // dense LDL^T, column by column: D on the diagonal, unit L below it
  for (int j = 0; j < n; ++j) {
    double dj = L(j, j);
    for (int k = 0; k < j; ++k) dj -= L(j, k) * L(j, k) * L(k, k);
    if (!(dj > 0.0)) return false;
    L(j, j) = dj;
    for (int i = j + 1; i < n; ++i) {
      double s = L(i, j);
      for (int k = 0; k < j; ++k) s -= L(i, k) * L(j, k) * L(k, k);
      L(i, j) = s / dj;
    }
  }
  data.factored = true;
  return true;
}

void TreeSolve(const TreeData& data, Eigen::Ref<Eigen::VectorXd> x) {
  const Eigen::MatrixXd& L = data.factor;
  const int n = static_cast<int>(x.size());
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) x[i] -= L(i, k) * x[k];
  }
  for (int i = 0; i < n; ++i) x[i] /= L(i, i);
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) x[i] -= L(k, i) * x[k];
  }
}

void TreeSolveRows(const TreeData& data, Eigen::Ref<Eigen::MatrixXd> xt) {
  // TreeSolve with x[i] the column xt.col(i): the same operations per row, in the same order
  const Eigen::MatrixXd& L = data.factor;
  const int n = static_cast<int>(xt.cols());
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) xt.col(i) -= L(i, k) * xt.col(k);
  }
  for (int i = 0; i < n; ++i) xt.col(i) /= L(i, i);
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) xt.col(i) -= L(k, i) * xt.col(k);
  }
}

void TreeEffectiveInverseMass(TreeData& data, const Eigen::Ref<const Eigen::MatrixXd>& J,
                              Eigen::Ref<Eigen::MatrixXd> out) {
  for (int r = 0; r < J.rows(); ++r) {
    data.scratch_v = J.row(r).transpose();
    TreeSolve(data, data.scratch_v);
    out.col(r).noalias() = J * data.scratch_v;
  }
}

void TreeIntegratePositions(const TreeModel& model, TreeData& data, double h_s) {
  const int nj = static_cast<int>(model.joint_body.size());
  for (int j = 0; j < nj; ++j) {
    const JointType type = model.joint(j).type;
    int qa = model.joint_qadr[j];
    int da = model.joint_dadr[j];
    if (type == JointType::kHinge || type == JointType::kSlide) {
      data.qpos[qa] += h_s * data.qvel[da];
      continue;
    }
    if (type == JointType::kFree) {
      data.qpos.segment<3>(qa) += h_s * data.qvel.segment<3>(da);
      qa += 3;
      da += 3;
    }
    // q <- q exp(h w), w in the frame after the joint
    const Vec3 w = data.qvel.segment<3>(da);
    const double angle = h_s * w.norm();
    Quat dq = Quat::Identity();
    if (angle > 0.0) dq = Quat(Eigen::AngleAxisd(angle, w.normalized()));
    const Quat q = NormalizedQuat(data.qpos, qa) * dq;
    data.qpos.segment<4>(qa) << q.w(), q.x(), q.y(), q.z();
    NormalizedQuat(data.qpos, qa);
  }
}

bool TreeStep(const TreeModel& model, TreeData& data, double h_s,
              const Eigen::Ref<const Eigen::VectorXd>& tau) {
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  TreeBiasForces(model, data);
  TreePassiveForces(model, data);
  if (!TreeFactor(model, data, h_s)) return false;
  TreeFreeVelocity(model, data, h_s, tau);
  TreeIntegratePositions(model, data, h_s);
  return true;
}

double TreeKineticEnergy(TreeData& data) {
  data.scratch_v.noalias() = data.M * data.qvel;
  return 0.5 * data.qvel.dot(data.scratch_v);
}

double TreePotentialEnergy(const TreeModel& model, const TreeData& data) {
  double U_J = 0.0;
  for (int i = 0; i < static_cast<int>(model.bodies.size()); ++i) {
    U_J -= model.bodies[i].mass_kg * model.gravity_mps2.dot(data.com_W[i]);
  }
  for (int j = 0; j < static_cast<int>(model.joint_body.size()); ++j) {
    const TreeJoint& jt = model.joint(j);
    if (jt.type == JointType::kBall) {
      U_J +=
          0.5 * jt.stiffness * BallSpringRotation(jt, data.qpos, model.joint_qadr[j]).squaredNorm();
    }
    if (jt.type != JointType::kHinge && jt.type != JointType::kSlide) continue;
    const double dq = data.qpos[model.joint_qadr[j]] - jt.spring_ref;
    U_J += 0.5 * jt.stiffness * dq * dq;
  }
  return U_J;
}

}  // namespace rigidtouch::dynamics
