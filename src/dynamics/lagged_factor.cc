#include "dynamics/lagged_factor.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

// the refinement: at most this many corrections, until the velocity error in the kinetic-energy
// norm is below this fraction of the step's momentum scale
constexpr int kMaxRefinements = 2;
constexpr double kRefineTolerance = 1e-10;
// after a failed refinement the kept factor is not tried for 1, 3, 7, ... solves, at most this
// many: on the stack a failed try costs about 60% of a factorised solve
constexpr int kMaxBackoff = 63;

// the patches' keys (LaggedFactor::PatchKey), sorted: the bodies, count and stick state
// exactly, the coefficients by their bits
void PatchKeys(LaggedFactor& lag, const GroupAssembly& g,
               std::span<const ImplicitContact> contacts) {
  for (int q = 0; q < g.npatch; ++q) {
    const int begin = g.patch_range[2 * q], end = g.patch_range[2 * q + 1];
    const ImplicitContact& c = contacts[begin];
    // body indices + 1 (static: 0) in 24 bits each, the count in 15, the stick state in 1
    const auto lo = static_cast<std::uint64_t>(std::min(c.body_a, c.body_b) + 1);
    const auto hi = static_cast<std::uint64_t>(std::max(c.body_a, c.body_b) + 1);
    const auto count = static_cast<std::uint64_t>(end - begin);
    const std::uint64_t shape = lo << 40 | hi << 16 | count << 1 | (c.stick ? 1 : 0);
    const auto c_n = std::bit_cast<std::uint64_t>(c.c_n_Ns_per_m);
    const auto c_t = std::bit_cast<std::uint64_t>(c.stick ? c.c_t_Ns_per_m : 0.0);
    lag.patch_keys[q] = {shape, c_n ^ (c_t << 1 | c_t >> 63)};
  }
  std::sort(lag.patch_keys.begin(), lag.patch_keys.begin() + g.npatch);
}

// one 64-bit hash of the sorted patch keys (FNV-1a over their words)
std::uint64_t HashKeys(const LaggedFactor& lag, int npatch) {
  std::uint64_t h = 1469598103934665603ull;
  for (int q = 0; q < npatch; ++q) {
    for (const std::uint64_t word : lag.patch_keys[q]) {
      h ^= word;
      h *= 1099511628211ull;
    }
  }
  return h;
}

// true if the group's kept factor was made for a system of this shape: the same bodies at the
// same elimination positions as this step's analysis (every body's column written by the one
// KeepFactor the anchor's record names, for as many bodies) and the same patch keys. Its values
// differ (the contacts moved), which the refinement accounts for; keys that are equal by chance
// for different systems only cost a refinement that fails. Partitions the contacts into patches
// and fills lag.order when the bodies match.
bool FactorFits(const KeptFactors& kept, LaggedFactor& lag, GroupAssembly& g,
                std::span<const int> bodies, std::span<const ImplicitContact> contacts,
                const BlockCholesky& factor) {
  const int nb = static_cast<int>(bodies.size());
  const int anchor = bodies[0];
  const KeptFactors::Record& r = kept.records[anchor];
  if (!r.valid || r.nb != nb) return false;
  for (int k = 0; k < nb; ++k) {
    const KeptFactors::Column& c = kept.columns[bodies[k]];
    if (c.anchor != anchor || c.version != r.version || c.pos != factor.pos[k]) return false;
    lag.order[c.pos] = bodies[k];
  }
  PartitionPatches(g, contacts);
  if (g.npatch != r.npatch) return false;
  PatchKeys(lag, g, contacts);
  return HashKeys(lag, g.npatch) == r.keys;
}

// f^T m^-1 f + t^T I^-1 t for a body of rotation R (the M^-1 norm of an impulse, squared)
double InverseMassNorm2(const BodyModel& b, const Mat3& R, const Vec3& f, const Vec3& t) {
  const Vec3 t_B = R.transpose() * t;
  return f.squaredNorm() / b.mass_kg + t_B.dot(t_B.cwiseQuotient(b.inertia_kgm2));
}

// the residual of the momentum balance at the velocities g.x, into g.b:
//   r = M (v - x) + h F + h sum J^T f(x),
// zero exactly at the solution of the implicit system; the contacts' forces at x are left in
// them. Returns r^T M^-1 r. Since A = M + h sum J^T C J >= M, the error of x in the kinetic-energy
// norm is bounded by the residual: (x - x*)^T M (x - x*) <= r^T A^-1 r <= r^T M^-1 r.
double Residual(const Model& model, const Data& data, std::span<const int> bodies,
                std::span<const int> slot, std::span<ImplicitContact> contacts,
                std::span<const Vec3> force_W, std::span<const Vec3> torque_W, GroupAssembly& g,
                const BlockCholesky& factor, bool* pulls) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k], p = factor.pos[k];
    const BodyState& st = data.bodies[i];
    g.b[p].head<3>() = model.bodies[i].mass_kg * (st.v_W - g.x[p].head<3>()) + h * force_W[i];
    g.b[p].tail<3>() = WorldInertiaTimes(model.bodies[i], data.R_WB[i], st.w_W - g.x[p].tail<3>()) +
                       h * torque_W[i];
  }
  bool pulled = false;
  for (int q = 0; q < g.npatch; ++q) {
    pulled |= PatchForces<true>(g, factor, data, slot, contacts, g.patch_range[2 * q],
                                g.patch_range[2 * q + 1], false, h);
  }
  *pulls = pulled;
  double r2 = 0.0;
  for (int k = 0; k < nb; ++k) {
    const int p = factor.pos[k];
    const Vec3 rl = g.b[p].head<3>(), ra = g.b[p].tail<3>();
    r2 += InverseMassNorm2(model.bodies[bodies[k]], data.R_WB[bodies[k]], rl, ra);
  }
  return r2;
}

// solves the group with the factor of an earlier step's system of the same shape, by iterative
// refinement against this step's system: x <- x + F^-1 r(x) from the current velocities, until
// the residual bounds the velocity error in the kinetic-energy norm by kRefineTolerance of the
// step's momentum scale. False (nothing final written, the caller factors afresh) if that takes
// more than kMaxRefinements corrections or the accepted velocities would make a contact pull.
bool SolveLagged(const Model& model, const Data& data, std::span<const int> bodies,
                 std::span<const int> slot, std::span<ImplicitContact> contacts,
                 std::span<const Vec3> force_W, std::span<const Vec3> torque_W, LaggedFactor& lag,
                 const KeptFactors& kept, GroupAssembly& g, const BlockCholesky& factor) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  // the momentum scale: |M v| + |h F| + |r(v)|, each in the M^-1 norm
  double mv2 = 0.0, hf2 = 0.0;
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k], p = factor.pos[k];
    const BodyModel& bm = model.bodies[i];
    const BodyState& st = data.bodies[i];
    const Mat3& R = data.R_WB[i];  // the kinematics stage's
    g.x[p] << st.v_W, st.w_W;
    const Vec3 w_B = R.transpose() * st.w_W;
    mv2 += bm.mass_kg * st.v_W.squaredNorm() + w_B.dot(w_B.cwiseProduct(bm.inertia_kgm2));
    hf2 += h * h * InverseMassNorm2(bm, R, force_W[i], torque_W[i]);
  }
  bool pulls = false;
  double r2 = Residual(model, data, bodies, slot, contacts, force_W, torque_W, g, factor, &pulls);
  const double scale = std::sqrt(mv2) + std::sqrt(hf2) + std::sqrt(r2);
  const double tol2 = kRefineTolerance * kRefineTolerance * scale * scale;
  int steps = 0;
  double last2 = r2;
  while (!(r2 <= tol2)) {
    if (steps == kMaxRefinements) return false;
    if (steps > 0) {
      // each correction shrinks the residual by about the last one's ratio: stop early if the
      // corrections left cannot bring it under the tolerance
      double predicted2 = r2;
      for (int k = steps; k < kMaxRefinements; ++k) predicted2 *= r2 / last2;
      if (!(predicted2 <= tol2)) return false;
    }
    const bool finite = SolveByColumns(nb, g.b, [&kept, &lag](int p) {
      const KeptFactors::Column& c = kept.columns[lag.order[p]];
      return FactorColumn{c.diag, c.diag_inv, c.row.data(), c.off.data(), c.count};
    });
    if (!finite) return false;
    for (int p = 0; p < nb; ++p) g.x[p] += g.b[p];
    last2 = r2;
    r2 = Residual(model, data, bodies, slot, contacts, force_W, torque_W, g, factor, &pulls);
    ++steps;
  }
  if (pulls) return false;
  lag.refinement_steps += steps;
  return true;
}

}  // namespace

void KeptFactors::Reserve(int nbody) {
  columns.assign(nbody, Column{});
  records.assign(nbody, Record{});
}

void KeptFactors::Forget() {
  for (Column& c : columns) {
    c.anchor = -1;
    c.version = 0;
  }
  std::fill(records.begin(), records.end(), Record{});
}

void LaggedFactor::Reserve(int max_bodies, int max_contacts) {
  patch_keys.assign(max_contacts, PatchKey{});
  order.assign(max_bodies, -1);
  lagged_solves = refinement_steps = lagged_failures = unkept = 0;
}

void KeepFactor(KeptFactors& kept, LaggedFactor& lag, const GroupAssembly& g,
                std::span<const int> bodies, std::span<const ImplicitContact> contacts,
                const BlockCholesky& factor) {
  const int nb = static_cast<int>(bodies.size());
  KeptFactors::Record& r = kept.records[bodies[0]];
  for (int p = 0; p < nb; ++p) {
    if (factor.col_start[p + 1] - factor.col_start[p] > KeptFactors::kMaxColumn) {
      r.valid = false;
      ++lag.unkept;
      return;
    }
  }
  PatchKeys(lag, g, contacts);
  r.valid = true;
  ++r.version;
  r.nb = nb;
  r.npatch = g.npatch;
  r.keys = HashKeys(lag, g.npatch);
  for (int k = 0; k < nb; ++k) {
    const int p = factor.pos[k];
    KeptFactors::Column& c = kept.columns[bodies[k]];
    c.anchor = bodies[0];
    c.version = r.version;
    c.pos = p;
    c.count = factor.col_start[p + 1] - factor.col_start[p];
    c.diag = factor.diag[p];
    c.diag_inv = factor.diag_inv[p];
    for (int e = 0; e < c.count; ++e) {
      c.row[e] = factor.col_row[factor.col_start[p] + e];
      c.off[e] = factor.off[factor.col_start[p] + e];
    }
  }
}

bool SolveWithKeptFactor(const Model& model, const Data& data, std::span<const int> bodies,
                         std::span<const int> slot, std::span<ImplicitContact> contacts,
                         std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                         LaggedFactor& lag, KeptFactors& kept, GroupAssembly& g,
                         const BlockCholesky& factor) {
  if (!FactorFits(kept, lag, g, bodies, contacts, factor)) return false;
  KeptFactors::Record& r = kept.records[bodies[0]];
  if (r.lag_skip > 0) {
    --r.lag_skip;
    return false;
  }
  if (SolveLagged(model, data, bodies, slot, contacts, force_W, torque_W, lag, kept, g, factor)) {
    ++lag.lagged_solves;
    r.lag_backoff = 0;
    return true;
  }
  // while the group moves too much for the kept factor, try it ever more rarely
  ++lag.lagged_failures;
  r.lag_backoff = std::min(2 * r.lag_backoff + 1, kMaxBackoff);
  r.lag_skip = r.lag_backoff;
  return false;
}

}  // namespace rigidtouch::dynamics
