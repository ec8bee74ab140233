#include "dynamics/velocities.h"

#include <algorithm>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

// Eq. 1 without contact coupling: v += h F / m, w += h I^-1 tau
void FreeMotion(const Model& model, Data& data, const VelocityScratch& scratch, int i) {
  const double h = model.timestep_s;
  BodyState& s = data.bodies[i];
  s.v_W += h / model.bodies[i].mass_kg * scratch.force_W[i];
  s.w_W += h * WorldInverseInertiaTimes(model.bodies[i], data.R_WB[i], scratch.torque_W[i]);
}

}  // namespace

void VelocityScratch::Reserve(int nbody, int max_contacts, int max_group_bodies) {
  force_W.resize(nbody);
  torque_W.resize(nbody);
  implicit.resize(max_contacts);
  implicit_start.assign(nbody + 1, 0);
  group_solver.Reserve(max_group_bodies, max_contacts);
  // a group of two or more bodies each: at most nbody / 2 groups, and no more than 256 scratches
  // (about 0.2 MB each)
  const int nkept = max_group_bodies > 1 ? std::min(256, nbody / 2 + 1) : 0;
  kept.resize(nkept);
  for (GroupSolverScratch& k : kept) {
    k.Reserve(std::min(kKeptBodies, max_group_bodies), std::min(kKeptContacts, max_contacts));
  }
  kept_owner.assign(nkept, -1);
  kept_of_body.assign(nbody, -1);
  kept_next = 0;
}

void VelocityScratch::ForgetFactors() {
  group_solver.ForgetFactor();
  for (GroupSolverScratch& k : kept) k.ForgetFactor();
  std::fill(kept_owner.begin(), kept_owner.end(), -1);
  std::fill(kept_of_body.begin(), kept_of_body.end(), -1);
  kept_next = 0;
}

void VelocityScratch::SetReuseFactor(bool reuse) {
  group_solver.lagged.reuse_factor = reuse;
  for (GroupSolverScratch& k : kept) k.lagged.reuse_factor = reuse;
}

long VelocityScratch::LaggedSolves() const {
  long n = group_solver.lagged.lagged_solves;
  for (const GroupSolverScratch& k : kept) n += k.lagged.lagged_solves;
  return n;
}

long VelocityScratch::Factorisations() const {
  long n = group_solver.factorisations;
  for (const GroupSolverScratch& k : kept) n += k.factorisations;
  return n;
}

namespace {

// the scratch that solves a group of these bodies and `ncontact` implicit contacts: its own kept
// one if it fits, else the shared one
GroupSolverScratch& ScratchFor(VelocityScratch& s, std::span<const int> bodies, int ncontact) {
  if (s.kept.empty() || static_cast<int>(bodies.size()) > s.kept.front().max_bodies ||
      ncontact > s.kept.front().max_contacts) {
    return s.group_solver;
  }
  const int key = *std::min_element(bodies.begin(), bodies.end());
  int k = s.kept_of_body[key];
  if (k < 0) {
    k = s.kept_next;
    s.kept_next = (s.kept_next + 1) % static_cast<int>(s.kept.size());
    if (s.kept_owner[k] >= 0) s.kept_of_body[s.kept_owner[k]] = -1;
    s.kept_owner[k] = key;
    s.kept_of_body[key] = k;
    s.kept[k].ForgetFactor();
  }
  return s.kept[k];
}

}  // namespace

void AddFreeMotionForces(const Model& model, const Data& data, const Wrench& user,
                         VelocityScratch& scratch) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    const BodyModel& b = model.bodies[i];
    const bool compensated = i == model.tool && model.device.coupling != Coupling::kNone;
    scratch.force_W[i] = compensated ? Vec3::Zero() : Vec3(b.mass_kg * model.gravity_W);
    scratch.torque_W[i] =
        ImplicitGyroscopicTorque(b, data.R_WB[i], data.bodies[i].w_W, model.timestep_s);
  }
  scratch.force_W[model.tool] += user.force_N;
  scratch.torque_W[model.tool] += user.torque_Nm;
}

void UpdateVelocities(const Model& model, Data& data, const contact::Groups& groups,
                      VelocityScratch& scratch) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] < 0) FreeMotion(model, data, scratch, i);
  }
  for (int g = 0; g < groups.ngroup; ++g) {
    const int nb = groups.body_start[g + 1] - groups.body_start[g];
    const std::span<const int> bodies(groups.bodies.data() + groups.body_start[g], nb);
    const int begin = scratch.implicit_start[g], end = scratch.implicit_start[g + 1];
    bool solved = false;
    if (end > begin) {
      const std::span<ImplicitContact> implicit(scratch.implicit.data() + begin, end - begin);
      solved = SolveGroupVelocities(model, data, bodies, groups.slot, implicit, scratch.force_W,
                                    scratch.torque_W, ScratchFor(scratch, bodies, end - begin));
      if (solved) {
        // report the implicit forces at the new velocities
        for (const ImplicitContact& ic : implicit) {
          Contact& c = data.contacts[ic.contact];
          c.normal_force_N = std::max(0.0, ic.normal_force_N);
          c.friction_force_W += ic.friction_force_W;
        }
      } else {
        data.Warn(Warning::kSolverFailed);
      }
    }
    if (!solved) {
      for (int i : bodies) FreeMotion(model, data, scratch, i);
    }
  }
}

void IntegratePositions(const Model& model, Data& data) {
  for (BodyState& s : data.bodies) IntegratePosition(s, model.timestep_s);
}

}  // namespace rigidtouch::dynamics
