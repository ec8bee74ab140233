// The lagged factorisation of the implicit group solve (group_dynamics.h): while a group keeps
// its bodies, patches, stick states and coefficients, the factor of an earlier step's system
// solves this step's by iterative refinement. The result is accepted only when the residual of
// the momentum balance bounds the velocity error in the kinetic-energy norm (see
// SolveGroupVelocities); otherwise the caller factors afresh.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "dynamics/block_cholesky.h"
#include "dynamics/group_assembly.h"
#include "dynamics/implicit_contact.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// What the factor kept in a BlockCholesky was made for, the refinement's scratch, the back-off
/// after failed refinements and the counters.
struct LaggedFactor {
  // false: every solve factors afresh
  bool reuse_factor = true;
  bool factor_valid = false;
  // a patch's key: its two bodies (unordered), point count, stick state and coefficients; a
  // system's keys sorted, so that neither the patches' order nor which body is a matters
  using PatchKey = std::array<std::uint64_t, 2>;
  std::vector<PatchKey> patch_keys, factor_keys;  // (max_contacts) this solve's, the factor's
  int factor_nb = 0, factor_npatch = 0;
  std::vector<int> factor_bodies;     // (max_bodies)
  int lag_backoff = 0, lag_skip = 0;  // after failed refinements: solves left without a try
  // counters since Reserve: solves by a kept factor, the refinement's corrections over those,
  // and refinements given up (then factored)
  long lagged_solves = 0, refinement_steps = 0, lagged_failures = 0;

  void Reserve(int max_bodies, int max_contacts);
  /// Drops the kept factor and the back-off.
  void Forget() {
    factor_valid = false;
    lag_backoff = lag_skip = 0;
  }
};

/// Records that the factor now in the BlockCholesky was made for this system (the bodies and
/// the patches in g, assembled with every contact active).
void KeepFactor(LaggedFactor& lag, const GroupAssembly& g, std::span<const int> bodies,
                std::span<const ImplicitContact> contacts);

/// Solves the group into g.x with the kept factor if it was made for a system of this shape
/// (same bodies in the same positions, same patch keys) and the back-off allows a try: by
/// iterative refinement against this step's system from the current velocities, until the
/// residual bounds the velocity error in the kinetic-energy norm by 1e-10 of the step's momentum
/// scale, within two corrections and with no contact pulling. False (nothing final written, the
/// caller factors afresh) otherwise; a failed try backs off for the next 1, 3, 7, ... (at most
/// 63) solves. Partitions the contacts into patches (g.patch_range) when the bodies match.
bool SolveWithKeptFactor(const Model& model, const Data& data, std::span<const int> bodies,
                         std::span<const int> slot, std::span<ImplicitContact> contacts,
                         std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                         LaggedFactor& lag, GroupAssembly& g, const BlockCholesky& factor);

}  // namespace rigidtouch::dynamics
