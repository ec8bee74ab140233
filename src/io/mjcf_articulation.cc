// Articulated trees from a compiled MJCF scene (src/io/mjcf_articulation.h).
#include "io/mjcf_articulation.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <utility>

#include "dynamics/tree.h"

namespace rigidtouch::io {
namespace {

// a keyframe may leave a limited joint outside its range by this much (rad or m): MuJoCo writes
// keyframes with 6 to 9 significant digits
constexpr double kKeyLimitTolerance = 1e-6;

std::string MjElementName(const mjModel* m, int type, int id) {
  const char* name = mj_id2name(m, type, id);
  if (name != nullptr && name[0] != '\0') return std::string("'") + name + "'";
  return "'#" + std::to_string(id) + "'";
}

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

Quat QuatAt(const mjtNum* q) {
  return Quat(q[0], q[1], q[2], q[3]).normalized();
}

Vec3 Vec3At(const mjtNum* v) {
  return Vec3(v[0], v[1], v[2]);
}

// (pos, quat) in body b's frame carried into the frame of its ancestor `root` (0: the world)
void IntoAncestorFrame(const mjModel* m, int b, int root, Vec3* pos, Quat* quat) {
  for (; b != root && b != 0; b = m->body_parentid[b]) {
    const Quat bq = QuatAt(m->body_quat + 4 * b);
    *pos = Vec3At(m->body_pos + 3 * b) + bq * *pos;
    *quat = bq * *quat;
  }
}

struct Loader {
  const mjModel* m;
  const std::string& path;
  Model& model;
  int key = -1;  // keyframe 'initial', or -1

  [[noreturn]] void Refuse(const std::string& what) const {
    throw Error("scene file '" + path + "': " + what);
  }
  void Warn(const std::string& what) const {
    model.load_warnings.push_back("scene file '" + path + "': " + what);
  }
  std::string Joint(int j) const {
    return "<joint> " + MjElementName(m, mjOBJ_JOINT, j) + " of body " +
           MjElementName(m, mjOBJ_BODY, m->jnt_bodyid[j]);
  }
  const mjtNum* Qpos() const { return key >= 0 ? m->key_qpos + key * m->nq : m->qpos0; }
};

// the mass, centre of mass and inertia (about the centre, in b's frame) of jointed body b with
// every body welded into it (MuJoCo's body_weldid b)
void MergedInertia(const mjModel* m, int b, dynamics::TreeBody& body) {
  double mass = 0.0;
  Vec3 moment = Vec3::Zero();
  for (int c = b; c < m->nbody; ++c) {
    if (m->body_weldid[c] != b) continue;
    Vec3 com = Vec3At(m->body_ipos + 3 * c);
    Quat axes = QuatAt(m->body_iquat + 4 * c);
    IntoAncestorFrame(m, c, b, &com, &axes);
    mass += m->body_mass[c];
    moment += m->body_mass[c] * com;
  }
  body.mass_kg = mass;
  body.com_m = mass > 0.0 ? Vec3(moment / mass) : Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
  for (int c = b; c < m->nbody; ++c) {
    if (m->body_weldid[c] != b) continue;
    Vec3 com = Vec3At(m->body_ipos + 3 * c);
    Quat axes = QuatAt(m->body_iquat + 4 * c);
    IntoAncestorFrame(m, c, b, &com, &axes);
    const Mat3 R = axes.toRotationMatrix();
    const Vec3 d = com - body.com_m;
    inertia += R * Vec3At(m->body_inertia + 3 * c).asDiagonal() * R.transpose() +
               m->body_mass[c] * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  body.inertia_kgm2 = 0.5 * (inertia + inertia.transpose());
}

JointKind JointKindOf(int mj_type) {
  switch (mj_type) {
    case mjJNT_FREE:
      return JointKind::kFree;
    case mjJNT_BALL:
      return JointKind::kBall;
    case mjJNT_SLIDE:
      return JointKind::kSlide;
    default:
      return JointKind::kHinge;
  }
}

// joint j's dynamics and its public record, refused where a tree cannot simulate it
dynamics::TreeJoint TreeJointOf(const Loader& L, int j, JointModel& out) {
  const mjModel* m = L.m;
  const int qa = m->jnt_qposadr[j], da = m->jnt_dofadr[j];
  out.name = MjElementName(m, mjOBJ_JOINT, j).substr(1);
  out.name.pop_back();
  out.type = JointKindOf(m->jnt_type[j]);
  const bool scalar = out.type == JointKind::kHinge || out.type == JointKind::kSlide;
  const int ndof = out.type == JointKind::kFree ? 6 : out.type == JointKind::kBall ? 3 : 1;
  if (out.type == JointKind::kFree && m->jnt_stiffness[j] != 0.0) {
    L.Refuse(L.Joint(j) + " is a free joint with stiffness=\"" + Number(m->jnt_stiffness[j]) +
             "\": rigidtouch's joint springs act on hinge, slide and ball joints only");
  }
  if (!(m->dof_frictionloss[da] >= 0.0 && m->dof_frictionloss[da] <= 1e9)) {
    L.Refuse(L.Joint(j) + " has frictionloss=\"" + Number(m->dof_frictionloss[da]) +
             "\": it must be within [0, 1e9] N or N m");
  }
  const Vec3 axis = Vec3At(m->jnt_axis + 3 * j);
  if (scalar && !(std::abs(axis.norm() - 1.0) < 1e-6)) {
    L.Refuse(L.Joint(j) + " has a zero or non-finite axis");
  }
  out.limited = m->jnt_limited[j] != 0 && out.type != JointKind::kFree;
  out.range_lo_rad_or_m = m->jnt_range[2 * j];
  out.range_hi_rad_or_m = m->jnt_range[2 * j + 1];
  if (out.limited && !(out.range_lo_rad_or_m <= out.range_hi_rad_or_m)) {
    L.Refuse(L.Joint(j) + " has range=\"" + Number(out.range_lo_rad_or_m) + " " +
             Number(out.range_hi_rad_or_m) + "\" with min > max");
  }
  if (out.limited && out.type == JointKind::kBall) out.range_lo_rad_or_m = 0.0;
  dynamics::TreeJoint jt;
  jt.type = static_cast<dynamics::JointType>(static_cast<int>(out.type));
  jt.axis = scalar ? axis.normalized() : axis;
  jt.pos_m = Vec3At(m->jnt_pos + 3 * j);
  if (scalar) {
    jt.ref = m->qpos0[qa];
    jt.spring_ref = m->qpos_spring[qa];
    jt.stiffness = m->jnt_stiffness[j];
  } else if (out.type == JointKind::kBall) {
    jt.stiffness = m->jnt_stiffness[j];
    jt.spring_quat = QuatAt(m->qpos_spring + qa);
  }
  jt.damping = m->dof_damping[da];
  jt.armature = m->dof_armature[da];
  jt.frictionloss = m->dof_frictionloss[da];
  for (int k = 1; k < ndof; ++k) {
    if (m->dof_damping[da + k] != jt.damping || m->dof_armature[da + k] != jt.armature ||
        m->dof_frictionloss[da + k] != jt.frictionloss) {
      L.Refuse(L.Joint(j) + ": its degrees of freedom differ in damping, armature or frictionloss");
    }
  }
  return jt;
}

// the keyframe's (or the default) coordinates of tree joint `tj` at MuJoCo's joint j, checked
// against the joint's range
void InitialJointState(const Loader& L, int j, const JointModel& jm, ArticulatedTree& tree) {
  const mjModel* m = L.m;
  const int nq = jm.type == JointKind::kFree ? 7 : jm.type == JointKind::kBall ? 4 : 1;
  const int nv = jm.type == JointKind::kFree ? 6 : jm.type == JointKind::kBall ? 3 : 1;
  const mjtNum* q = L.Qpos() + m->jnt_qposadr[j];
  const mjtNum* v = (L.key >= 0 ? m->key_qvel + L.key * m->nv : nullptr);
  const std::string from = L.key >= 0 ? "keyframe 'initial'" : "the default pose";
  for (int k = 0; k < nq; ++k) {
    if (!std::isfinite(q[k]) || std::abs(q[k]) > 1e4) {
      L.Refuse(L.Joint(j) + ": its position in " + from + " is " + Number(q[k]) +
               ", not finite or beyond 1e4");
    }
    tree.initial_qpos[jm.qpos_adr + k] = q[k];
  }
  for (int k = 0; k < nv; ++k) {
    const double w = v != nullptr ? v[m->jnt_dofadr[j] + k] : 0.0;
    if (!std::isfinite(w) || std::abs(w) > 1e4) {
      L.Refuse(L.Joint(j) + ": its velocity in " + from + " is " + Number(w) +
               ", not finite or beyond 1e4");
    }
    tree.initial_qvel[jm.dof_adr + k] = w;
  }
  const bool scalar = jm.type == JointKind::kHinge || jm.type == JointKind::kSlide;
  if (jm.limited && scalar &&
      (q[0] < jm.range_lo_rad_or_m - kKeyLimitTolerance ||
       q[0] > jm.range_hi_rad_or_m + kKeyLimitTolerance)) {
    L.Refuse(L.Joint(j) + ": its position " + Number(q[0]) + " in " + from +
             " is outside its range [" + Number(jm.range_lo_rad_or_m) + ", " +
             Number(jm.range_hi_rad_or_m) + "] by more than " + Number(kKeyLimitTolerance));
  }
  if (jm.limited && jm.type == JointKind::kBall) {
    const double norm = Vec3At(q + 1).norm(), w = std::abs(q[0]);
    const double angle = 2.0 * std::atan2(norm, w);
    if (angle > jm.range_hi_rad_or_m + kKeyLimitTolerance) {
      L.Refuse(L.Joint(j) + ": its rotation of " + Number(angle) + " rad in " + from +
               " is beyond its range " + Number(jm.range_hi_rad_or_m) + " rad");
    }
  }
}

// actuator u on a joint of a tree, or refused naming it
void CopyActuator(const Loader& L, int u, const std::vector<LinkOf>& link_of,
                  const std::vector<int>& tree_joint) {
  const mjModel* m = L.m;
  const std::string who = "<actuator> " + MjElementName(m, mjOBJ_ACTUATOR, u);
  const int trn = m->actuator_trntype[u];
  const int j = m->actuator_trnid[2 * u];
  if (trn != mjTRN_JOINT && trn != mjTRN_JOINTINPARENT) {
    L.Refuse(who +
             " drives a tendon, site, body or slider-crank: rigidtouch's actuators act on "
             "hinge and slide joints only");
  }
  const int b = m->jnt_bodyid[j];
  if (link_of[b].tree < 0 || (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE)) {
    L.Refuse(who + " drives " + L.Joint(j) +
             ": rigidtouch's actuators act on hinge and slide joints of articulated bodies only");
  }
  const int gt = m->actuator_gaintype[u], bt = m->actuator_biastype[u];
  double ctrl = L.key >= 0 && m->nu > 0 ? m->key_ctrl[L.key * m->nu + u] : 0.0;
  if (m->actuator_ctrllimited[u]) {
    ctrl = std::clamp(ctrl, m->actuator_ctrlrange[2 * u], m->actuator_ctrlrange[2 * u + 1]);
  }
  const int dyn = m->actuator_dyntype[u];
  if (dyn != mjDYN_NONE) {
    // MuJoCo 2.2 keeps the activations of the last na actuators (the stateful ones come last)
    const int act = u - (m->nu - m->na);
    const double act0 =
        L.key >= 0 && act >= 0 && act < m->na ? m->key_act[L.key * m->na + act] : 0.0;
    // integrator (act' = ctrl) or filter (act' = (ctrl - act) / tau) from 0 at control 0 keeps
    // act = 0, and a force gain(l, v) act without bias is then 0 for the whole run
    const bool idle = (dyn == mjDYN_INTEGRATOR || dyn == mjDYN_FILTER) && ctrl == 0.0 &&
                      act0 == 0.0 && (gt == mjGAIN_FIXED || gt == mjGAIN_AFFINE) &&
                      bt == mjBIAS_NONE;
    if (!idle) {
      L.Refuse(who +
               " has activation dynamics (dyntype integrator, filter, muscle or user): "
               "rigidtouch applies actuators at a constant control without activation state");
    }
    L.Warn(who +
           " has activation dynamics, which rigidtouch does not simulate; at its constant "
           "control 0 from activation 0 with no bias it exerts no force, so it is left out");
    return;
  }
  if ((gt != mjGAIN_FIXED && gt != mjGAIN_AFFINE) || (bt != mjBIAS_NONE && bt != mjBIAS_AFFINE)) {
    L.Refuse(who +
             " has a muscle or user gain or bias: rigidtouch supports fixed and affine "
             "gains and biases only");
  }
  ActuatorModel a;
  a.name = MjElementName(m, mjOBJ_ACTUATOR, u).substr(1);
  a.name.pop_back();
  a.joint = tree_joint[j];
  a.gear = m->actuator_gear[6 * u];
  const mjtNum* g = m->actuator_gainprm + mjNGAIN * u;
  const mjtNum* bias = m->actuator_biasprm + mjNBIAS * u;
  a.gain[0] = g[0];
  a.gain[1] = gt == mjGAIN_AFFINE ? g[1] : 0.0;
  a.gain[2] = gt == mjGAIN_AFFINE ? g[2] : 0.0;
  for (int k = 0; k < 3; ++k) a.bias[k] = bt == mjBIAS_AFFINE ? bias[k] : 0.0;
  a.ctrl = ctrl;
  a.force_limited = m->actuator_forcelimited[u] != 0;
  a.force_lo = m->actuator_forcerange[2 * u];
  a.force_hi = m->actuator_forcerange[2 * u + 1];
  bool finite = std::isfinite(a.gear) && std::isfinite(a.ctrl);
  for (int k = 0; k < 3; ++k)
    finite = finite && std::isfinite(a.gain[k]) && std::isfinite(a.bias[k]);
  if (!finite || (a.force_limited && !(a.force_lo <= a.force_hi))) {
    L.Refuse(who + " has a non-finite gear, gain, bias or control, or forcerange min > max");
  }
  L.model.trees[link_of[b].tree].actuators.push_back(a);
}

// tree t: its bodies (the jointed bodies whose root is `root`, in MuJoCo's order), joints and
// initial state
void BuildTree(const Loader& L, int root, std::vector<LinkOf>& link_of,
               std::vector<int>& tree_joint) {
  const mjModel* m = L.m;
  const int t = static_cast<int>(L.model.trees.size());
  L.model.trees.emplace_back();
  ArticulatedTree& tree = L.model.trees.back();
  tree.name = MjElementName(m, mjOBJ_BODY, root).substr(1);
  tree.name.pop_back();
  std::vector<dynamics::TreeBody> bodies;
  for (int b = root; b < m->nbody; ++b) {
    if (m->body_jntnum[b] == 0) continue;
    const int p = m->body_weldid[m->body_parentid[b]];
    if (b != root && (p == 0 || link_of[p].tree != t)) continue;  // not below root
    link_of[b] = LinkOf{t, static_cast<int>(bodies.size())};
    dynamics::TreeBody body;
    body.parent = b == root ? -1 : link_of[p].link;
    IntoAncestorFrame(m, b, b == root ? 0 : p, &body.pos_m, &body.quat);
    body.quat.normalize();
    MergedInertia(m, b, body);
    if (!(body.mass_kg > 0.0) || !body.inertia_kgm2.allFinite() ||
        !(body.inertia_kgm2.ldlt().vectorD().minCoeff() > 0.0)) {
      L.Refuse("body " + MjElementName(m, mjOBJ_BODY, b) +
               " (with the bodies welded into it) has no positive mass and inertia; give its "
               "geoms a mass or density");
    }
    for (int j = m->body_jntadr[b]; j < m->body_jntadr[b] + m->body_jntnum[b]; ++j) {
      JointModel jm;
      body.joints.push_back(TreeJointOf(L, j, jm));
      jm.link = link_of[b].link;
      tree_joint[j] = static_cast<int>(tree.joints.size());
      tree.joints.push_back(jm);
    }
    tree.link_names.push_back(MjElementName(m, mjOBJ_BODY, b).substr(1));
    tree.link_names.back().pop_back();
    tree.link_mj_body.push_back(b);
    tree.link_parent.push_back(body.parent);
    bodies.push_back(std::move(body));
  }
  try {
    tree.dynamics = std::make_shared<const dynamics::TreeModel>(dynamics::MakeTree(
        std::move(bodies), Vec3(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2])));
  } catch (const Error& e) {
    L.Refuse("the articulated body '" + tree.name + "': " + e.what());
  }
  const dynamics::TreeModel& dyn = *tree.dynamics;
  if (m->opt.disableflags & mjDSBL_GRAVITY) {
    auto copy = std::make_shared<dynamics::TreeModel>(dyn);
    copy->gravity_mps2.setZero();
    tree.dynamics = copy;
  }
  tree.nq = dyn.nq;
  tree.nv = dyn.nv;
  tree.initial_qpos.assign(tree.nq, 0.0);
  tree.initial_qvel.assign(tree.nv, 0.0);
  for (std::size_t k = 0; k < tree.joints.size(); ++k) {
    tree.joints[k].qpos_adr = dyn.joint_qadr[k];
    tree.joints[k].dof_adr = dyn.joint_dadr[k];
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (link_of[m->jnt_bodyid[j]].tree == t)
      InitialJointState(L, j, tree.joints[tree_joint[j]], tree);
  }
}

// limits' softness and margins, which the contact stages replace with their own: one warning
// naming the first three joints and the count of the others (a file of 22 humanoids has 462)
void WarnLimitSoftness(const Loader& L) {
  const mjModel* m = L.m;
  mjtNum solref[mjNREF], solimp[mjNIMP];
  mj_defaultSolRefImp(solref, solimp);
  std::string named;
  int tuned_joints = 0;
  for (int j = 0; j < m->njnt; ++j) {
    bool tuned = m->jnt_margin[j] != 0.0;
    for (int k = 0; k < mjNREF; ++k) tuned = tuned || m->jnt_solref[mjNREF * j + k] != solref[k];
    for (int k = 0; k < mjNIMP; ++k) tuned = tuned || m->jnt_solimp[mjNIMP * j + k] != solimp[k];
    if (!tuned || !m->jnt_limited[j]) continue;
    if (tuned_joints++ < 3) named += (named.empty() ? "" : ", ") + L.Joint(j);
  }
  if (tuned_joints == 0) return;
  L.Warn(named + (tuned_joints > 3 ? " and " + std::to_string(tuned_joints - 3) + " more" : "") +
         ": solreflimit, solimplimit and margin are ignored; rigidtouch's contact stages make "
         "joint limits hard");
}

}  // namespace

bool IsLoneFreeBody(const mjModel* m, int b) {
  if (m->body_jntnum[b] != 1 || m->jnt_type[m->body_jntadr[b]] != mjJNT_FREE) return false;
  if (m->body_parentid[b] != 0) return false;
  for (int c = b + 1; c < m->nbody; ++c) {
    if (m->body_weldid[c] == b || m->body_jntnum[c] == 0) continue;
    for (int a = m->body_parentid[c]; a != 0; a = m->body_parentid[a]) {
      if (a == b) return false;  // a jointed body below b
    }
  }
  return true;
}

std::vector<LinkOf> CopyTrees(const mjModel* m, const std::string& path, Model& model) {
  Loader L{m, path, model, mj_name2id(m, mjOBJ_KEY, "initial")};
  std::vector<LinkOf> link_of(m->nbody);
  std::vector<int> tree_joint(m->njnt, -1);
  for (int b = 1; b < m->nbody; ++b) {
    const bool root = m->body_jntnum[b] > 0 && m->body_weldid[m->body_parentid[b]] == 0;
    if (root && !IsLoneFreeBody(m, b)) BuildTree(L, b, link_of, tree_joint);
  }
  for (int b = 1; b < m->nbody; ++b) {
    if (m->body_jntnum[b] == 0 && m->body_weldid[b] != 0) link_of[b] = link_of[m->body_weldid[b]];
  }
  for (int u = 0; u < m->nu; ++u) CopyActuator(L, u, link_of, tree_joint);
  WarnLimitSoftness(L);
  // hinge and slide ranges are unilateral rows of the contact stages; a ball's is only reported
  int limited = 0, first = -1;
  for (int j = 0; j < m->njnt; ++j) {
    if (link_of[m->jnt_bodyid[j]].tree < 0 || !m->jnt_limited[j]) continue;
    if (m->jnt_type[j] != mjJNT_BALL) continue;
    if (limited++ == 0) first = j;
  }
  if (limited > 0) {
    L.Warn(L.Joint(first) + (limited > 1 ? " and " + std::to_string(limited - 1) + " more" : "") +
           ": a ball joint's range is reported (at_limit) but not enforced; the joint can pass "
           "its limit");
  }
  return link_of;
}

void PlaceLinkGeomsAtStart(Model& model) {
  std::vector<dynamics::TreeData> start;
  for (const ArticulatedTree& tree : model.trees) {
    start.push_back(dynamics::MakeTreeData(*tree.dynamics));
    for (int i = 0; i < tree.nq; ++i) start.back().qpos[i] = tree.initial_qpos[i];
    dynamics::TreeKinematics(*tree.dynamics, start.back());
  }
  for (GeomModel& g : model.geoms) {
    if (g.tree < 0) continue;
    const dynamics::TreeData& d = start[g.tree];
    g.pos_B = d.x_W[g.link] + d.R_WB[g.link] * g.pos_L;
    g.quat_B = (Quat(d.R_WB[g.link]) * g.quat_L).normalized();
  }
}

}  // namespace rigidtouch::io
