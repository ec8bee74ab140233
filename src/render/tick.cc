// One haptic tick (DESIGN.md): coupling, geometry, phases, penalty, dynamics, impulses,
// integration, render. Nothing here allocates, locks, does I/O or throws.
#include <algorithm>
#include <cmath>

#include "contact/impulse_math.h"
#include "contact/impulse_reference.h"
#include "contact/schedule.h"
#include "dynamics/rigid_body.h"
#include "geometry/collision.h"
#include "render/workspace.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

void Warn(Data& data, Warning w) {
  WarningStat& s = data.warnings[static_cast<int>(w)];
  ++s.count;
  s.last_step = data.step;
}

bool Finite(const DeviceState& s) {
  return std::isfinite(s.time_s) && s.position_m.allFinite() && s.velocity_mps.allFinite() &&
         s.angular_velocity_radps.allFinite() && s.orientation.coeffs().allFinite();
}

// body frames are fixed until stage 7: each body's rotation matrix is computed once per tick,
// by DetectContacts (CollisionScratch::R_WB)
[[gnu::always_inline]] inline Vec3 WorldPoint(const Data& data, const Workspace& ws, int body,
                                              const Vec3& p_local) {
  if (body < 0) return p_local;
  return data.bodies[body].x_W + ws.collision.R_WB[body] * p_local;
}

Vec3 LocalPoint(const Data& data, const Workspace& ws, int body, const Vec3& p_W) {
  if (body < 0) return p_W;
  return ws.collision.R_WB[body].transpose() * (p_W - data.bodies[body].x_W);
}

// contact point offsets from the two centres of mass
void Offsets(const Data& data, const Contact& c, Vec3* r_a, Vec3* r_b) {
  *r_a = c.body_a >= 0 ? Vec3(c.p_W - data.bodies[c.body_a].x_W) : Vec3::Zero();
  *r_b = c.body_b >= 0 ? Vec3(c.p_W - data.bodies[c.body_b].x_W) : Vec3::Zero();
}

Vec3 RelativeVelocity(const Data& data, const Contact& c, const Vec3& r_a, const Vec3& r_b) {
  Vec3 u = Vec3::Zero();
  if (c.body_a >= 0) u += dynamics::PointVelocity(data.bodies[c.body_a], r_a);
  if (c.body_b >= 0) u -= dynamics::PointVelocity(data.bodies[c.body_b], r_b);
  return u;
}

// tangential displacement of the stick anchor (a's anchor relative to b's, tangent plane)
Vec3 AnchorDisplacement(const Data& data, const Workspace& ws, const Contact& c) {
  const Vec3 d =
      WorldPoint(data, ws, c.body_a, c.anchor_A) - WorldPoint(data, ws, c.body_b, c.anchor_B);
  return d - d.dot(c.n_W) * c.n_W;
}

// moves b's anchor so the anchor spring alone would exert `f_t` on a (the slip limit)
void SlideAnchor(const Data& data, const Workspace& ws, Contact& c, const Vec3& s, const Vec3& f_t,
                 double kt) {
  if (kt <= 0.0) return;
  const Vec3 s_target = -f_t / kt;
  const Vec3 pb = WorldPoint(data, ws, c.body_b, c.anchor_B) + (s - s_target);
  c.anchor_B = LocalPoint(data, ws, c.body_b, pb);
}

void Accumulate(Workspace& ws, const Contact& c, const Vec3& f_on_a, const Vec3& r_a,
                const Vec3& r_b) {
  if (c.body_a >= 0) {
    ws.force_W[c.body_a] += f_on_a;
    ws.torque_W[c.body_a] += r_a.cross(f_on_a);
  }
  if (c.body_b >= 0) {
    ws.force_W[c.body_b] -= f_on_a;
    ws.torque_W[c.body_b] -= r_b.cross(f_on_a);
  }
}

// explicit penalty and friction of one contact (tool contacts, or scene contacts of a group too
// large for the implicit solve); updates the friction anchor
void ExplicitContact(Data& data, Workspace& ws, int ci) {
  Contact& c = data.contacts[ci];
  const contact::PenaltyLaw& law = ws.laws[ci];
  Vec3 r_a, r_b;
  Offsets(data, c, &r_a, &r_b);
  const Vec3 u = RelativeVelocity(data, c, r_a, r_b);
  const double un = u.dot(c.n_W);
  const double fn = contact::NormalForce(law, c.depth_m, un);
  Vec3 ft = Vec3::Zero();
  if (fn > 0.0) {
    const Vec3 s = AnchorDisplacement(data, ws, c);
    const Vec3 ut = u - un * c.n_W;
    ft = -law.kt_N_per_m * s - law.bt_Ns_per_m * ut;
    c.sticking = ft.norm() <= law.mu_static * fn;
    if (!c.sticking) {
      ft *= law.mu_kinetic * fn / ft.norm();
      SlideAnchor(data, ws, c, s, ft, law.kt_N_per_m);
    }
  } else {
    c.anchor_A = c.p_A;  // no load: the anchor follows the contact point
    c.anchor_B = c.p_B;
    c.sticking = false;
  }
  c.normal_force_N = fn;
  c.friction_force_W = ft;
  Accumulate(ws, c, fn * c.n_W + ft, r_a, r_b);
}

// one scene contact for the implicit solve (false: not penetrating, nothing to solve); slipping
// friction stays explicit
bool ImplicitContactFor(const Model& model, Data& data, Workspace& ws, int ci,
                        dynamics::ImplicitContact& ic) {
  Contact& c = data.contacts[ci];
  const contact::PenaltyLaw& law = ws.laws[ci];
  const double h = model.timestep_s;
  c.normal_force_N = 0.0;
  c.friction_force_W.setZero();
  if (!(c.depth_m > 0.0)) {
    c.anchor_A = c.p_A;
    c.anchor_B = c.p_B;
    c.sticking = false;
    return false;
  }
  // backward Euler: depth after the step is d - h u_n+, so the force is k d - (h k + b) u_n+;
  // every penetrating point enters the solve, and SolveGroupVelocities drops the contacts that
  // would pull at the new velocities (a trial on the old velocities would react to velocity noise)
  ic = dynamics::ImplicitContact{};
  ic.body_a = c.body_a;
  ic.body_b = c.body_b;
  ic.n_W = c.n_W;
  ic.p_W = c.p_W;
  ic.phi_n_N = law.k_N_per_m * c.depth_m;
  ic.c_n_Ns_per_m = h * law.k_N_per_m + law.b_Ns_per_m;
  ic.contact = ci;
  // stick or slip was decided for the whole geom pair (DecidePatchFriction)
  const Vec3 s = ws.anchor_displacement[ci];  // computed by DecidePatchFriction this tick
  if (c.sticking) {
    // the anchor spring (s lies in the tangent plane) with implicit tangential damping
    ic.stick = true;
    ic.phi_t_W = -law.kt_N_per_m * s;
    ic.c_t_Ns_per_m = h * law.kt_N_per_m + law.bt_Ns_per_m;
  } else {
    // kinetic friction opposes the stretch of the anchor, which trails the sliding contact
    const double stretch = s.norm();
    const Vec3 ft =
        stretch > 0.0 ? Vec3(-s * (law.mu_kinetic * ic.phi_n_N / stretch)) : Vec3::Zero();
    SlideAnchor(data, ws, c, s, ft, law.kt_N_per_m);
    c.friction_force_W = ft;
    Vec3 r_a, r_b;
    Offsets(data, c, &r_a, &r_b);
    Accumulate(ws, c, ft, r_a, r_b);
  }
  return true;
}

// stick or slip per geom pair, from the anchor springs alone: the points of one face are one
// contact patch with one friction cone (sum |kt s| <= mu_s sum k d), and a decision on state, not
// on velocities, cannot chatter with velocity noise. Only implicit (scene) contacts; a tool
// contact decides alone in ExplicitContact.
void DecidePatchFriction(Data& data, Workspace& ws) {
  for (int begin = 0; begin < data.ncontact;) {
    const Contact& first = data.contacts[begin];
    int end = begin + 1;
    while (end < data.ncontact && data.contacts[end].geom_a == first.geom_a &&
           data.contacts[end].geom_b == first.geom_b) {
      ++end;
    }
    if (ws.laws[begin].implicit) {
      double fn = 0.0, ft = 0.0;
      for (int ci = begin; ci < end; ++ci) {
        const Contact& c = data.contacts[ci];
        fn += ws.laws[ci].k_N_per_m * c.depth_m;
        ws.anchor_displacement[ci] = AnchorDisplacement(data, ws, c);
        ft += ws.laws[ci].kt_N_per_m * ws.anchor_displacement[ci].norm();
      }
      const bool stick = ft <= ws.laws[begin].mu_static * fn;
      for (int ci = begin; ci < end; ++ci) data.contacts[ci].sticking = stick;
    }
    begin = end;
  }
}

void FreeMotion(const Model& model, Data& data, const Workspace& ws, int i) {
  const double h = model.timestep_s;
  BodyState& s = data.bodies[i];
  s.v_W += h / model.bodies[i].mass_kg * ws.force_W[i];
  s.w_W +=
      h * dynamics::WorldInverseInertiaTimes(model.bodies[i], ws.collision.R_WB[i], ws.torque_W[i]);
}

// the collision window of a group: restarted by an approaching new contact (METHOD.md
// decisions), otherwise the most recent window among its bodies
WindowState GroupWindow(const Model& model, Data& data, const Workspace& ws, int g) {
  const contact::Groups& G = ws.groups;
  WindowState w;
  for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) {
    const WindowState& b = data.window[G.bodies[k]];
    if (b.onset_step > w.onset_step) w = b;
  }
  if (model.render.renderer == RendererKind::kPenalty) return w;
  for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
    const int ci = G.contacts[k];
    if (data.contacts[ci].is_new && ws.normal_velocity[ci] < -model.contact.onset_speed_mps) {
      w.onset_step = data.step;
      w.impulses_done = 0;
      break;
    }
  }
  return w;
}

bool InWindow(const Model& model, const WindowState& w, std::int64_t step) {
  if (w.onset_step < 0) return false;
  const std::int64_t k = step - w.onset_step;
  return model.render.renderer == RendererKind::kTrain ? k < model.schedule.window_steps : k == 0;
}

// stage 6 for one group: Eq. 5 (single impulse) or Eq. 8 (train) when the schedule says so
void GroupImpulse(const Model& model, Data& data, Workspace& ws, int g, WindowState& window) {
  int index = 0, remaining = 0;
  if (!contact::ImpulseDue(model.schedule, window, data.step, &index, &remaining)) return;
  const contact::Groups& G = ws.groups;
  const int nb = G.body_start[g + 1] - G.body_start[g];
  const int nc = G.contact_start[g + 1] - G.contact_start[g];
  if (nc == 0) return;
  for (int k = 0; k < nb; ++k) {
    const int i = G.bodies[G.body_start[g] + k];
    const BodyState& s = data.bodies[i];
    contact::SolverBody& sb = ws.solver_bodies[k];
    sb.inv_mass = 1.0 / model.bodies[i].mass_kg;
    sb.inv_inertia_W = dynamics::WorldInverseInertia(model.bodies[i], s);
    sb.v_W = s.v_W;
    sb.w_W = s.w_W;
  }
  bool tool = false;
  for (int k = 0; k < nc; ++k) {
    const int ci = G.contacts[G.contact_start[g] + k];
    const Contact& c = data.contacts[ci];
    contact::SolverRow& row = ws.solver_rows[k];
    row.body_a = c.body_a >= 0 ? G.slot[c.body_a] : -1;
    row.body_b = c.body_b >= 0 ? G.slot[c.body_b] : -1;
    row.n_W = c.n_W;
    Offsets(data, c, &row.r_a_W, &row.r_b_W);
    tool = tool || c.body_a == model.tool || c.body_b == model.tool;
  }
  const std::span<contact::SolverBody> bodies(ws.solver_bodies.data(), nb);
  const std::span<contact::SolverRow> rows(ws.solver_rows.data(), nc);
  const std::span<double> p(ws.impulses.data(), nc);
  const contact::ImpulseProblem problem{bodies, rows};
  const double e = model.render.renderer == RendererKind::kImpulse ? model.render.restitution : 0.0;
  if (model.render.reference_solver) {
    // exact Eq. 5 / Eq. 8 with the pseudo-inverse; allocates, for comparison runs only
    const Eigen::VectorXd ref = contact::ReferenceImpulse(problem, e, remaining);
    for (int k = 0; k < nc; ++k) p[k] = ref[k];
  } else {
    const double scale = (1.0 + e) / remaining;  // Eq. 5 (N = 1) and Eq. 8 (e = 0)
    const contact::ImpulseSolverStats stats = ws.impulse_solver->Solve(problem, scale, p);
    if (stats.error != contact::ImpulseSolverError::kNone) {
      Warn(data, Warning::kSolverFailed);
      return;
    }
  }
  const double ke_before = contact::KineticEnergy(bodies);
  contact::ApplyImpulses(bodies, rows, p);
  const double ke_after = contact::KineticEnergy(bodies);
  ImpulseEvent& ev = data.impulses[data.nimpulse++];
  ev = ImpulseEvent{};
  ev.step = data.step;
  ev.time_s = data.time_s;
  ev.group = g;
  ev.contacts = nc;
  ev.index = index;
  ev.total = model.schedule.impulses;
  ev.tool = tool;
  ev.kinetic_energy_before_J = ke_before;
  ev.kinetic_energy_after_J = ke_after;
  double norm2 = 0.0;
  for (int k = 0; k < nc; ++k) {
    Contact& c = data.contacts[G.contacts[G.contact_start[g] + k]];
    c.impulse_Ns = p[k];
    norm2 += p[k] * p[k];
    if (c.body_a == model.tool) ev.tool_impulse_W += p[k] * c.n_W;
    if (c.body_b == model.tool) ev.tool_impulse_W -= p[k] * c.n_W;
  }
  ev.impulse_norm_Ns = std::sqrt(norm2);
  data.tool_impulse_W += ev.tool_impulse_W;
  for (int k = 0; k < nb; ++k) {
    BodyState& s = data.bodies[G.bodies[G.body_start[g] + k]];
    s.v_W = bodies[k].v_W;
    s.w_W = bodies[k].w_W;
  }
  window.impulses_done = index;
}

bool StateFinite(const Data& data) {
  for (const BodyState& s : data.bodies) {
    if (!s.x_W.allFinite() || !s.v_W.allFinite() || !s.w_W.allFinite() ||
        !s.q_WB.coeffs().allFinite()) {
      return false;
    }
  }
  return true;
}

}  // namespace

DeviceCommand Tick(const Model& model, Data& data, const TickInput& input) {
  Workspace& ws = *data.workspace;
  const double h = model.timestep_s;
  const int nbody = static_cast<int>(model.bodies.size());
  const int tool = model.tool;
  DeviceCommand out;
  out.sequence = input.device.sequence;
  data.nimpulse = 0;
  data.tool_impulse_W.setZero();
  data.tool_coupling_force_W.setZero();

  // 1. coupling
  Wrench user;
  bool device_ok = true;
  const DeviceState& dev = input.device;
  switch (model.device.coupling) {
    case Coupling::kNone:
      if (input.tool_wrench.force_N.allFinite() && input.tool_wrench.torque_Nm.allFinite()) {
        user = input.tool_wrench;
      } else {
        device_ok = false;
      }
      break;
    case Coupling::kDirect:
    case Coupling::kVirtual: {
      if (!dev.valid || !Finite(dev)) {
        device_ok = false;
        break;
      }
      BodyState& t = data.bodies[tool];
      // the tool turns with the handle under both couplings, so contact torques cannot spin a tool
      // the user holds (a free sphere dragged over a rough floor would roll and stick-slip, and
      // the user would feel that chatter as friction)
      t.q_WB = (dev.orientation * model.bodies[tool].iquat_B).normalized();
      t.w_W = dev.angular_velocity_radps;
      const Vec3 x_dev = dev.position_m + model.device.workspace_offset_m;
      if (model.device.coupling == Coupling::kDirect) {
        t.x_W = x_dev;
        t.v_W = dev.velocity_mps;
      } else {
        // the spring-damper couples the position
        user.force_N = model.device.coupling_stiffness_N_per_m * (x_dev - t.x_W) +
                       model.device.coupling_damping_Ns_per_m * (dev.velocity_mps - t.v_W);
        data.tool_coupling_force_W = user.force_N;
      }
      break;
    }
  }
  if (!device_ok) Warn(data, Warning::kBadDeviceState);

  // 2. geometry
  geometry::DetectContacts(model, data, ws.collision);

  // 3. phases and groups
  contact::BuildGroups(data, ws.groups);
  for (int ci = 0; ci < data.ncontact; ++ci) {
    Contact& c = data.contacts[ci];
    // the approach speed only matters for a new contact (a collision onset, GroupWindow)
    ws.normal_velocity[ci] = 0.0;
    if (c.is_new) {
      Vec3 r_a, r_b;
      Offsets(data, c, &r_a, &r_b);
      ws.normal_velocity[ci] = RelativeVelocity(data, c, r_a, r_b).dot(c.n_W);
    }
    // one law per geom pair: its points are consecutive
    const bool same_pair = ci > 0 && data.contacts[ci - 1].geom_a == c.geom_a &&
                           data.contacts[ci - 1].geom_b == c.geom_b &&
                           data.contacts[ci - 1].pair_points == c.pair_points;
    ws.laws[ci] = same_pair ? ws.laws[ci - 1] : contact::LawFor(model, c);
  }
  DecidePatchFriction(data, ws);
  const contact::Groups& G = ws.groups;
  for (int g = 0; g < G.ngroup; ++g) {
    const WindowState w = GroupWindow(model, data, ws, g);
    for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
    const ContactPhase phase =
        InWindow(model, w, data.step) ? ContactPhase::kColliding : ContactPhase::kResting;
    for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
      data.contacts[G.contacts[k]].phase = phase;
    }
  }

  // 4. penalty (explicit parts) and 5. free-motion forces
  for (int i = 0; i < nbody; ++i) {
    const BodyModel& b = model.bodies[i];
    // a tool held through a device is gravity-compensated like the device itself
    const bool compensated = i == tool && model.device.coupling != Coupling::kNone;
    ws.force_W[i] = compensated ? Vec3::Zero() : Vec3(b.mass_kg * model.gravity_W);
    ws.torque_W[i] = dynamics::GyroscopicTorque(b, ws.collision.R_WB[i], data.bodies[i].w_W);
  }
  ws.force_W[tool] += user.force_N;
  ws.torque_W[tool] += user.torque_Nm;
  for (int ci = 0; ci < data.ncontact; ++ci) {
    const Contact& c = data.contacts[ci];
    const bool too_large =
        G.body_start[c.group + 1] - G.body_start[c.group] > model.max_group_bodies;
    if (!ws.laws[ci].implicit || too_large) ExplicitContact(data, ws, ci);
  }

  // 5. dynamics: implicit scene contacts per group, free motion elsewhere
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] < 0) FreeMotion(model, data, ws, i);
  }
  for (int g = 0; g < G.ngroup; ++g) {
    const int nb = G.body_start[g + 1] - G.body_start[g];
    const std::span<const int> bodies(G.bodies.data() + G.body_start[g], nb);
    int nimplicit = 0;
    if (nb <= model.max_group_bodies) {
      for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
        const int ci = G.contacts[k];
        if (ws.laws[ci].implicit &&
            ImplicitContactFor(model, data, ws, ci, ws.implicit[nimplicit])) {
          ++nimplicit;
        }
      }
    } else {
      Warn(data, Warning::kGroupTooLarge);
    }
    bool solved = false;
    if (nimplicit > 0) {
      const std::span<dynamics::ImplicitContact> implicit(ws.implicit.data(), nimplicit);
      solved = dynamics::SolveGroupVelocities(model, data, bodies, G.slot, implicit, ws.force_W,
                                              ws.torque_W, ws.group_solver);
      if (solved) {
        // report the implicit forces at the new velocities
        for (const dynamics::ImplicitContact& ic : implicit) {
          Contact& c = data.contacts[ic.contact];
          c.normal_force_N = std::max(0.0, ic.normal_force_N);
          c.friction_force_W += ic.friction_force_W;
        }
      } else {
        Warn(data, Warning::kSolverFailed);
      }
    }
    if (!solved) {
      for (int i : bodies) FreeMotion(model, data, ws, i);
    }
  }

  // 6. impulses
  for (int g = 0; g < G.ngroup; ++g) {
    if (model.render.renderer == RendererKind::kPenalty) break;
    WindowState w = data.window[G.bodies[G.body_start[g]]];
    GroupImpulse(model, data, ws, g, w);
    for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
  }

  // 7. integrate positions
  for (int i = 0; i < nbody; ++i) dynamics::IntegratePosition(data.bodies[i], h);

  // 8. render: penalty (or coupling) + Eq. 9, device limits, safety
  data.tool_penalty_force_W.setZero();
  data.tool_penetration_m = 0.0;
  data.tool_contacts = 0;
  Vec3 tool_torque = Vec3::Zero();
  for (int ci = 0; ci < data.ncontact; ++ci) {
    const Contact& c = data.contacts[ci];
    if (c.body_a != tool && c.body_b != tool) continue;
    const double sign = c.body_a == tool ? 1.0 : -1.0;
    const Vec3 f = sign * (c.normal_force_N * c.n_W + c.friction_force_W);
    data.tool_penalty_force_W += f;
    tool_torque += (c.p_W - data.bodies[tool].x_W).cross(f);
    ++data.tool_contacts;
    if (c.depth_m > data.tool_penetration_m) {
      data.tool_penetration_m = c.depth_m;
      data.tool_normal_W = sign * c.n_W;
    }
  }
  if (model.device.coupling == Coupling::kVirtual) {
    out.penalty_force_N = -data.tool_coupling_force_W;  // the coupling spring pulls the device
  } else {
    out.penalty_force_N = data.tool_penalty_force_W;
    out.torque_Nm = tool_torque;
  }
  out.impulsive_force_N = data.tool_impulse_W / h;  // Eq. 9
  out.force_N = out.penalty_force_N + out.impulsive_force_N;
  if (model.device.max_force_N > 0.0 && out.force_N.norm() > model.device.max_force_N) {
    out.force_N *= model.device.max_force_N / out.force_N.norm();
    out.clipped = true;
    Warn(data, Warning::kForceClipped);
    if (out.impulsive_force_N.squaredNorm() > 0.0) Warn(data, Warning::kImpulseClipped);
  }
  if (!StateFinite(data)) {
    Warn(data, Warning::kNonFiniteState);
    std::copy(model.initial.begin(), model.initial.end(), data.bodies.begin());
    data.ncontact = 0;
    device_ok = false;
  }
  if (!device_ok || !out.force_N.allFinite() || !out.torque_Nm.allFinite()) {
    out.force_N.setZero();
    out.torque_Nm.setZero();
    out.safe_fallback = true;
  }
  ++data.step;
  data.time_s = static_cast<double>(data.step) * h;
  return out;
}

}  // namespace rigidtouch
