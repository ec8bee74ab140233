// Contact groups with articulated trees in the tick (tree_groups.h).
#include "contact/tree_groups.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "contact/phases.h"
#include "contact/schedule.h"
#include "dynamics/kinematics.h"
#include "dynamics/rigid_body.h"
#include "dynamics/tree_stage.h"

namespace rigidtouch::contact {
namespace {

// one side of contact c's row: its body, the link its geom is on, or static
RowSide SideOf(const Model& model, const Groups& G, int body, int geom) {
  if (body >= 0) return {RowSideKind::kBody, G.slot[body], -1};
  const int t = geom >= 0 ? G.geom_tree[geom] : -1;
  if (t >= 0) return {RowSideKind::kLink, G.tree_slot[t], model.geoms[geom].link};
  return {};
}

// velocity of the material point at p_W of a contact side (before this step's update)
Vec3 SideVelocity(const Model& model, const Data& data, const Groups& G, int body, int geom,
                  const Vec3& p_W) {
  if (body >= 0) {
    const BodyState& s = data.bodies[body];
    return dynamics::PointVelocity(s, p_W - s.x_W);
  }
  const int t = geom >= 0 ? G.geom_tree[geom] : -1;
  if (t < 0) return Vec3::Zero();
  return dynamics::LinkPointVelocity(*data.trees[t], model.geoms[geom].link, p_W);
}

// the world position of a point kept in a contact side's frame: its body's, its link geom's
// (from the tree's kinematics at this step's positions, as the collision stage placed the geom),
// or the world's
Vec3 SideWorldPoint(const Model& model, const Data& data, const Groups& G, int body, int geom,
                    const Vec3& p) {
  if (body >= 0) return dynamics::WorldPoint(data, body, p);
  const int t = geom >= 0 ? G.geom_tree[geom] : -1;
  if (t < 0) return p;
  const GeomModel& gm = model.geoms[geom];
  const dynamics::TreeData& d = *data.trees[t];
  return d.x_W[gm.link] + d.R_WB[gm.link] * (gm.pos_L + gm.quat_L * p);
}

// SideWorldPoint's inverse: a world point in the side's frame
Vec3 SideLocalPoint(const Model& model, const Data& data, const Groups& G, int body, int geom,
                    const Vec3& p_W) {
  if (body >= 0) return dynamics::LocalPoint(data, body, p_W);
  const int t = geom >= 0 ? G.geom_tree[geom] : -1;
  if (t < 0) return p_W;
  const GeomModel& gm = model.geoms[geom];
  const dynamics::TreeData& d = *data.trees[t];
  return gm.quat_L.conjugate() * (d.R_WB[gm.link].transpose() * (p_W - d.x_W[gm.link]) - gm.pos_L);
}

Vec3 ContactVelocity(const Model& model, const Data& data, const Groups& G, const Contact& c) {
  return SideVelocity(model, data, G, c.body_a, c.geom_a, c.p_W) -
         SideVelocity(model, data, G, c.body_b, c.geom_b, c.p_W);
}

// the limit joint j of tree t is at this step: +1 lower, -1 upper, 0 none (hinge and slide)
int LimitSide(const JointModel& j, const dynamics::TreeData& d, double& depth) {
  depth = 0.0;
  if (!j.limited || (j.type != JointKind::kHinge && j.type != JointKind::kSlide)) return 0;
  const double q = d.qpos[j.qpos_adr];
  if (q <= j.range_lo_rad_or_m) {
    depth = j.range_lo_rad_or_m - q;
    return 1;
  }
  if (q >= j.range_hi_rad_or_m) {
    depth = q - j.range_hi_rad_or_m;
    return -1;
  }
  return 0;
}

// a contact row of tree group g from contact ci (false: not penetrating, no row)
bool ContactRow(const Model& model, Data& data, ContactScratch& cs, int ci, JointRow& row) {
  const Groups& G = cs.groups;
  Contact& c = data.contacts[ci];
  const PenaltyLaw& law = cs.laws[ci];
  c.normal_force_N = 0.0;
  c.friction_force_N_W.setZero();
  c.sticking = false;
  if (!(c.depth_m > 0.0) || !law.implicit) {
    c.anchor_A = c.p_A;  // no load, or the tool's explicit law: no anchor spring
    c.anchor_B = c.p_B;
  }
  if (!(c.depth_m > 0.0)) return false;
  const double h = model.timestep_s;
  row = JointRow{};
  row.a = SideOf(model, G, c.body_a, c.geom_a);
  row.b = SideOf(model, G, c.body_b, c.geom_b);
  row.n_W = c.n_W;
  row.p_W = c.p_W;
  row.mu_static = law.mu_static;
  row.mu_kinetic = law.mu_kinetic;
  row.stick = true;
  if (law.implicit) {
    // backward Euler on the normal spring-damper; the stick anchor's spring (its stretch since
    // last step, as for free bodies: contact_forces.cc) with implicit tangential damping
    row.phi_n_N = law.k_N_per_m * c.depth_m;
    row.c_n_Ns_per_m = h * law.k_N_per_m + law.b_Ns_per_m;
    row.c_t_Ns_per_m = h * law.kt_N_per_m + law.bt_Ns_per_m;
    const Vec3 d = SideWorldPoint(model, data, G, c.body_a, c.geom_a, c.anchor_A) -
                   SideWorldPoint(model, data, G, c.body_b, c.geom_b, c.anchor_B);
    const Vec3 stretch = d - d.dot(c.n_W) * c.n_W;
    cs.anchor_displacement[ci] = stretch;
    row.phi_t_W = -law.kt_N_per_m * stretch;
    return true;
  }
  // the tool's contact: explicit from this step's state, as ExplicitContact renders it
  const Vec3 u = ContactVelocity(model, data, G, c);
  const double un = u.dot(c.n_W);
  row.phi_n_N = NormalForce(law, c.depth_m, un);
  Vec3 ft = -law.bt_Ns_per_m * (u - un * c.n_W);
  const double ft_norm = ft.norm();
  if (ft_norm > law.mu_static * row.phi_n_N) {
    ft *= ft_norm > 0.0 ? law.mu_kinetic * row.phi_n_N / ft_norm : 0.0;
  }
  row.phi_t_W = ft;
  return true;
}

// tree group k's contacts classified (law, approach speed), its window and phase; its rows
// (contacts, then limits) into scratch.rows from row_start[k]; returns the row count or -1 when
// the group has more than kMaxTreeGroupRows
int ClassifyTreeGroup(const Model& model, Data& data, ContactScratch& cs, int k) {
  Groups& G = cs.groups;
  TreeGroupScratch& s = cs.trees;
  const int g = G.ngroup + k;
  const double h = model.timestep_s;
  const double onset = model.contact.onset_speed_mps;
  WindowState w;
  for (int i = G.body_start[g]; i < G.body_start[g + 1]; ++i) {
    if (data.window[G.bodies[i]].onset_step > w.onset_step) w = data.window[G.bodies[i]];
  }
  for (int i = G.tree_start[k]; i < G.tree_start[k + 1]; ++i) {
    if (data.tree_window[G.trees[i]].onset_step > w.onset_step) w = data.tree_window[G.trees[i]];
  }
  bool starts = false;
  const int first = s.row_start[k];
  int n = 0;
  bool full = false;
  for (int i = G.contact_start[g]; i < G.contact_start[g + 1]; ++i) {
    const int ci = G.contacts[i];
    Contact& c = data.contacts[ci];
    cs.laws[ci] = LawFor(model, c);
    cs.normal_velocity[ci] = c.is_new ? ContactVelocity(model, data, G, c).dot(c.n_W) : 0.0;
    cs.anchor_displacement[ci].setZero();
    c.group = g;
    starts = starts || (model.render.renderer != RendererKind::kPenalty && c.is_new &&
                        cs.normal_velocity[ci] < -onset);
    if (n >= kMaxTreeGroupRows) {
      full = true;
      continue;
    }
    if (ContactRow(model, data, cs, ci, s.rows[first + n])) s.row_contact[first + n++] = ci;
  }
  for (int i = G.tree_start[k]; i < G.tree_start[k + 1]; ++i) {
    const int t = G.trees[i];
    const dynamics::TreeData& d = *data.trees[t];
    const std::vector<JointModel>& joints = model.trees[t].joints;
    for (std::size_t j = 0; j < joints.size(); ++j) {
      double depth = 0.0;
      const int side = LimitSide(joints[j], d, depth);
      const int dof = joints[j].dof_adr;
      if (side != 0 && s.limit_engaged[t][j] != side &&
          model.render.joint_limit_renderer != RendererKind::kPenalty &&
          side * d.qvel[dof] < -onset) {
        starts = true;  // a limit reached faster than the onset speed: a collision onset
      }
      s.limit_engaged[t][j] = static_cast<signed char>(side);
      if (side == 0) continue;
      if (n >= kMaxTreeGroupRows) {
        full = true;
        continue;
      }
      JointRow& row = s.rows[first + n];
      row = JointRow{};
      row.a = {RowSideKind::kJoint, G.tree_slot[t], dof};
      row.limit_sign = side;
      double k_lim = 0.0, b_lim = 0.0;
      LimitLaw(d.M(dof, dof), h, k_lim, b_lim);
      row.phi_n_N = k_lim * depth;
      row.c_n_Ns_per_m = h * k_lim + b_lim;
      s.row_contact[first + n++] = -1;
    }
  }
  if (starts) {
    w.onset_step = data.step;
    w.impulses_done = 0;
  }
  w.interior = false;
  for (int i = G.body_start[g]; i < G.body_start[g + 1]; ++i) data.window[G.bodies[i]] = w;
  for (int i = G.tree_start[k]; i < G.tree_start[k + 1]; ++i) data.tree_window[G.trees[i]] = w;
  const std::int64_t since = data.step - w.onset_step;
  const bool limit_window = model.render.joint_limit_renderer == RendererKind::kTrain
                                ? since < model.joint_limit_schedule.window_steps
                                : since == 0;
  const ContactPhase phase = InWindow(model, w, data.step) || (w.onset_step >= 0 && limit_window)
                                 ? ContactPhase::kColliding
                                 : ContactPhase::kResting;
  for (int i = G.contact_start[g]; i < G.contact_start[g + 1]; ++i) {
    data.contacts[G.contacts[i]].phase = phase;
  }
  return full ? -1 : n;
}

// group k's members as JointGroup spans over the scratch (bodies packed from data.bodies)
JointGroup PackTreeGroup(const Model& model, const Data& data, const Groups& G, TreeGroupScratch& s,
                         int k, int nrows) {
  const int g = G.ngroup + k;
  const int nb = G.body_start[g + 1] - G.body_start[g];
  for (int i = 0; i < nb; ++i) {
    const int b = G.bodies[G.body_start[g] + i];
    const BodyState& state = data.bodies[b];
    SolverBody& sb = s.bodies[i];
    sb.inv_mass = 1.0 / model.bodies[b].mass_kg;
    sb.inv_inertia_W = dynamics::WorldInverseInertia(model.bodies[b], data.R_WB[b]);
    sb.v_W = state.v_W;
    sb.w_W = state.w_W;
    s.body_com_W[i] = state.x_W;
  }
  const int nt = G.tree_start[k + 1] - G.tree_start[k];
  for (int i = 0; i < nt; ++i) {
    const int t = G.trees[G.tree_start[k] + i];
    s.trees[i] = {model.trees[t].dynamics.get(), data.trees[t].get()};
  }
  return {std::span<SolverBody>(s.bodies.data(), nb),
          std::span<const Vec3>(s.body_com_W.data(), nb), std::span<GroupTree>(s.trees.data(), nt),
          std::span<JointRow>(s.rows.data() + s.row_start[k], nrows)};
}

// the anchors of scene contact ci after its row's solve, as free bodies' PlaceAnchors and
// SlideAnchor place them: a's at the contact point, b's behind it by the stretch, which is the
// step's own while the row sticks and, once it slipped, the stretch whose spring alone exerts the
// friction the row got
void PlaceRowAnchors(const Model& model, Data& data, const ContactScratch& cs, int ci,
                     const JointRow& row) {
  Contact& c = data.contacts[ci];
  const double kt = cs.laws[ci].kt_N_per_m;
  const Vec3 stretch =
      row.slipped && kt > 0.0 ? Vec3(-row.friction_force_N_W / kt) : cs.anchor_displacement[ci];
  c.sticking = !row.slipped;
  c.anchor_A = c.p_A;
  c.anchor_B = SideLocalPoint(model, data, cs.groups, c.body_b, c.geom_b, c.p_W - stretch);
}

void UnpackBodies(Data& data, const Groups& G, int k, const JointGroup& group) {
  const int g = G.ngroup + k;
  for (int i = 0; i < static_cast<int>(group.bodies.size()); ++i) {
    BodyState& state = data.bodies[G.bodies[G.body_start[g] + i]];
    state.v_W = group.bodies[i].v_W;
    state.w_W = group.bodies[i].w_W;
  }
}

}  // namespace

void LimitLaw(double m_jj, double h_s, double& k, double& b) {
  const double omega = 2.0 * std::numbers::pi / (kLimitPeriodSteps * h_s);
  k = m_jj * omega * omega;
  b = 2.0 * m_jj * omega;
}

void TreeGroupScratch::Reserve(const Model& model) {
  const int ntree = static_cast<int>(model.trees.size());
  solver.reset();
  rows.clear();
  force.clear();
  limit_engaged.clear();
  solves = 0;
  if (ntree == 0) return;
  const int nbody = static_cast<int>(model.bodies.size());
  int dofs = 6 * std::min(nbody, std::max(1, model.max_group_bodies));
  for (const ArticulatedTree& tree : model.trees) {
    dofs += tree.nv;
    force.push_back(Eigen::VectorXd::Zero(tree.nv));
    limit_engaged.emplace_back(tree.joints.size(), 0);
  }
  solver = std::make_unique<JointGroupSolver>(kMaxTreeGroupRows, dofs);
  bodies.assign(nbody, SolverBody{});
  body_com_W.assign(nbody, Vec3::Zero());
  trees.assign(ntree, GroupTree{});
  rows.assign(static_cast<std::size_t>(ntree) * kMaxTreeGroupRows, JointRow{});
  row_contact.assign(rows.size(), -1);
  row_start.assign(ntree + 1, 0);
}

void TreeGroupScratch::Reset() {
  for (std::vector<signed char>& v : limit_engaged) std::fill(v.begin(), v.end(), 0);
}

void SolveTreeGroups(const Model& model, Data& data, ContactScratch& cs,
                     dynamics::VelocityScratch& velocity) {
  Groups& G = cs.groups;
  TreeGroupScratch& s = cs.trees;
  const int ntree = static_cast<int>(model.trees.size());
  for (int t = 0; t < ntree; ++t) {
    if (!dynamics::PrepareTreeStep(model, t, data, s.force[t])) {
      // a mass matrix that does not factor: the tree starts again from its initial state
      data.Warn(Warning::kNonFiniteState);
      dynamics::ResetTree(model, t, data);
      if (!dynamics::PrepareTreeStep(model, t, data, s.force[t])) data.trees[t]->factored = false;
    }
  }
  for (int k = 0; k < G.ntree_group; ++k) {
    const int g = G.ngroup + k;
    s.row_start[k + 1] = s.row_start[k] + kMaxTreeGroupRows;
    const int nrows = ClassifyTreeGroup(model, data, cs, k);
    // free motion first: the joint-space solve adds the rows' forces to it
    for (int i = G.body_start[g]; i < G.body_start[g + 1]; ++i) {
      dynamics::MoveFreely(model, data, velocity, G.bodies[i]);
    }
    for (int i = G.tree_start[k]; i < G.tree_start[k + 1]; ++i) {
      const int t = G.trees[i];
      if (data.trees[t]->factored) dynamics::TreeFreeMotion(model, t, data, s.force[t]);
    }
    if (nrows < 0) {
      data.Warn(Warning::kGroupTooLarge);
      s.row_start[k + 1] = s.row_start[k];  // no rows: no impulse either
      continue;
    }
    s.row_start[k + 1] = s.row_start[k] + nrows;
    if (nrows == 0) continue;
    const JointGroup group = PackTreeGroup(model, data, G, s, k, nrows);
    ++s.solves;
    const JointPenaltyStats stats = s.solver->SolveJointPenalty(group, model.timestep_s);
    if (stats.error != JointGroupError::kNone) {
      data.Warn(Warning::kSolverFailed);
      continue;
    }
    UnpackBodies(data, G, k, group);
    for (int r = 0; r < nrows; ++r) {
      const int ci = s.row_contact[s.row_start[k] + r];
      if (ci < 0) continue;
      Contact& c = data.contacts[ci];
      c.normal_force_N = group.rows[r].normal_force_N;
      c.friction_force_N_W = group.rows[r].friction_force_N_W;
      if (cs.laws[ci].implicit) PlaceRowAnchors(model, data, cs, ci, group.rows[r]);
    }
  }
}

void TreeGroupImpulses(const Model& model, Data& data, const Groups& G, TreeGroupScratch& s) {
  const RenderParams& render = model.render;
  const double h = model.timestep_s;
  for (int k = 0; k < G.ntree_group; ++k) {
    const int g = G.ngroup + k;
    const int nrows = s.row_start[k + 1] - s.row_start[k];
    if (nrows == 0) continue;
    const WindowState w = data.tree_window[G.trees[G.tree_start[k]]];
    int index = 0, remaining = 0, total = 0;
    double contact_scale = 0.0, limit_scale = 0.0;
    if ((render.renderer == RendererKind::kImpulse || render.renderer == RendererKind::kTrain) &&
        ImpulseDue(model.schedule, w, data.step, &index, &remaining)) {
      const double e = render.renderer == RendererKind::kImpulse ? render.restitution : 0.0;
      contact_scale = (1.0 + e) * TrainShare(model.schedule, render, h, remaining);
      total = model.schedule.impulses;
    }
    int limit_index = 0;
    if (render.joint_limit_renderer == RendererKind::kImpulse &&
        ImpulseDue(Schedule{}, w, data.step, &limit_index, &remaining)) {
      limit_scale = 1.0 + render.restitution;  // Eq. 5
    } else if (render.joint_limit_renderer == RendererKind::kTrain &&
               ImpulseDue(model.joint_limit_schedule, w, data.step, &limit_index, &remaining)) {
      limit_scale = 1.0 / remaining;  // Eq. 8, plastic
    }
    if (contact_scale == 0.0 && limit_scale == 0.0) continue;
    if (contact_scale == 0.0) {
      index = limit_index;
      total = render.joint_limit_renderer == RendererKind::kTrain
                  ? model.joint_limit_schedule.impulses
                  : 1;
    }
    const JointGroup group = PackTreeGroup(model, data, G, s, k, nrows);
    bool tool = false;
    for (int r = 0; r < nrows; ++r) {
      const int ci = s.row_contact[s.row_start[k] + r];
      group.rows[r].impulse_scale = ci >= 0 ? contact_scale : limit_scale;
      if (ci >= 0) {
        const Contact& c = data.contacts[ci];
        tool = tool || c.body_a == model.tool || c.body_b == model.tool;
      }
    }
    const double ke_before = JointGroupKineticEnergy(group);
    const JointImpulseStats stats = s.solver->ApplyJointImpulses(group);
    if (stats.error != JointGroupError::kNone) {
      data.Warn(Warning::kSolverFailed);
      continue;
    }
    UnpackBodies(data, G, k, group);
    ImpulseEvent ev;
    ev.step = data.step;
    ev.time_s = data.time_s;
    ev.group = g;
    ev.contacts = nrows;
    ev.index = std::max(index, limit_index);
    ev.total = total;
    ev.tool = tool;
    ev.kinetic_energy_before_J = ke_before;
    ev.kinetic_energy_after_J = JointGroupKineticEnergy(group);
    double norm2 = 0.0;
    for (int r = 0; r < nrows; ++r) {
      const double p = group.rows[r].impulse_Ns;
      norm2 += p * p;
      const int ci = s.row_contact[s.row_start[k] + r];
      if (ci < 0) continue;
      Contact& c = data.contacts[ci];
      c.impulse_Ns = p;
      if (c.body_a == model.tool) ev.tool_impulse_Ns_W += p * c.n_W;
      if (c.body_b == model.tool) ev.tool_impulse_Ns_W -= p * c.n_W;
    }
    ev.impulse_norm_Ns = std::sqrt(norm2);
    if (data.nimpulse < static_cast<int>(data.impulses.size())) {
      data.impulses[data.nimpulse++] = ev;
    }
    data.tool_impulse_Ns_W += ev.tool_impulse_Ns_W;
    for (int i = G.body_start[g]; i < G.body_start[g + 1]; ++i) {
      data.window[G.bodies[i]].impulses_done = ev.index;
    }
    for (int i = G.tree_start[k]; i < G.tree_start[k + 1]; ++i) {
      data.tree_window[G.trees[i]].impulses_done = ev.index;
    }
  }
}

}  // namespace rigidtouch::contact
