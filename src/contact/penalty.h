// Penalty contact law (tick stage 4): spring-damper on penetration that never pulls, with Coulomb
// friction through a tangential stick anchor, as haptic renderers use.
#pragma once

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// Parameters of one contact point's law.
struct PenaltyLaw {
  double k_N_per_m = 0.0;    // normal stiffness of this point (the pair's, shared by its points)
  double b_Ns_per_m = 0.0;   // normal damping of this point
  double kt_N_per_m = 0.0;   // tangential anchor stiffness
  double bt_Ns_per_m = 0.0;  // tangential anchor damping
  double mu_static = 0.0;
  double mu_kinetic = 0.0;
  bool implicit = false;  // scene contact (backward Euler); tool contacts are explicit
};

/// The law of contact `c`: tool contacts use ContactParams' haptic stiffness and are explicit;
/// others use the scene stiffness and are integrated implicitly. Friction is the larger of the
/// two geoms' MJCF friction (MuJoCo's rule) unless ContactParams overrides it.
PenaltyLaw LawFor(const Model& model, const Contact& c);

/// Normal penalty force k d - b ddot(d), never negative (never pulls)  [N]. `normal_velocity` is
/// the relative normal velocity (positive separating), so the penetration rate is its negative.
inline double NormalForce(const PenaltyLaw& law, double depth_m, double normal_velocity_mps) {
  const double f = law.k_N_per_m * depth_m - law.b_Ns_per_m * normal_velocity_mps;
  return f > 0.0 ? f : 0.0;
}

}  // namespace rigidtouch::contact
