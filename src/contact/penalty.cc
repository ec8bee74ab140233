#include "contact/penalty.h"

#include <algorithm>

namespace rigidtouch::contact {

PenaltyLaw LawFor(const Model& model, const Contact& c) {
  const ContactParams& p = model.contact;
  PenaltyLaw law;
  const bool tool = c.body_a == model.tool || c.body_b == model.tool;
  const double share = 1.0 / std::max(1, c.pair_points);
  law.implicit = !tool;
  law.k_N_per_m = (tool ? p.stiffness_N_per_m : p.scene_stiffness_N_per_m) * share;
  law.b_Ns_per_m = (tool ? p.damping_Ns_per_m : p.scene_damping_Ns_per_m) * share;
  law.kt_N_per_m = p.tangential_ratio * law.k_N_per_m;
  law.bt_Ns_per_m = p.tangential_ratio * law.b_Ns_per_m;
  const double mu = std::max(model.geoms[c.geom_a].friction, model.geoms[c.geom_b].friction);
  law.mu_kinetic = p.friction_kinetic >= 0.0 ? p.friction_kinetic : mu;
  law.mu_static = p.friction_static >= 0.0 ? p.friction_static : law.mu_kinetic;
  if (law.mu_static < law.mu_kinetic) law.mu_static = law.mu_kinetic;
  return law;
}

}  // namespace rigidtouch::contact
