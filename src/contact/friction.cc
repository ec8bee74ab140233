#include "contact/friction.h"

namespace rigidtouch::contact {

void SlideAnchor(const Data& data, Contact& c, const Vec3& s, const Vec3& f_t, double kt) {
  PlaceAnchors(data, c, kt > 0.0 ? Vec3(-f_t / kt) : s);
}

void DecidePatchFriction(Data& data, std::span<const PenaltyLaw> laws,
                         std::span<Vec3> anchor_displacement, int begin, int end) {
  if (!laws[begin].implicit) return;
  double fn = 0.0, ft = 0.0;
  for (int ci = begin; ci < end; ++ci) {
    const Contact& c = data.contacts[ci];
    fn += laws[ci].k_N_per_m * c.depth_m;
    anchor_displacement[ci] = AnchorDisplacement(data, c);
    ft += laws[ci].kt_N_per_m * anchor_displacement[ci].norm();
  }
  const bool stick = ft <= laws[begin].mu_static * fn;
  for (int ci = begin; ci < end; ++ci) data.contacts[ci].sticking = stick;
}

}  // namespace rigidtouch::contact
