// The lagged factorisation of the implicit group solve (group_dynamics.h): while a group keeps
// its bodies, patches, stick states and coefficients, the factor of an earlier step's system
// solves this step's by iterative refinement; every group keeps its own (KeptFactors). The
// result is accepted only when the residual of the momentum balance bounds the velocity error in
// the kinetic-energy norm (see SolveGroupVelocities); otherwise the caller factors afresh.
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

/// The factors kept for later steps, one per contact group, stored with the group's bodies and
/// sized once for the scene's bodies (Reserve): each body holds its diagonal block of the factor
/// L and the below-diagonal blocks of its column; the group's first body (its anchor) holds what
/// the factor was made for and the back-off. Every group of a step keeps its own factor, and
/// groups share no body, so two threads solving different groups write different entries.
struct KeptFactors {
  // the below-diagonal blocks one body's column can keep: a factor with a longer column (fill-in
  // of a large lattice) is not kept, and its group factors every step
  static constexpr int kMaxColumn = 8;
  struct Column {
    int anchor = -1;   // the group's first body when this column was kept (-1: none)
    long version = 0;  // that anchor's Record::version then
    int pos = -1;      // the body's elimination position
    int count = 0;     // below-diagonal blocks
    Mat6 diag = Mat6::Zero();
    Vec6 diag_inv = Vec6::Zero();
    std::array<int, kMaxColumn> row{};
    std::array<Mat6, kMaxColumn> off{};
  };
  struct Record {
    bool valid = false;
    long version = 0;  // raised by each factor kept for this anchor
    int nb = 0, npatch = 0;
    std::uint64_t keys = 0;             // a hash of the sorted patch keys (LaggedFactor::PatchKey)
    int lag_backoff = 0, lag_skip = 0;  // after failed refinements: solves left without a try
  };
  std::vector<Column> columns;  // (nbody) by body
  std::vector<Record> records;  // (nbody) by anchor body

  void Reserve(int nbody);
  /// Drops every kept factor and back-off: no record or column is used again until written anew,
  /// as after Reserve.
  void Forget();
};

/// What one solver scratch needs to use kept factors: the switch, the key and order scratch and
/// the counters.
struct LaggedFactor {
  // false: every solve factors afresh (and KeptFactors is neither read nor written)
  bool reuse_factor = true;
  // a patch's key: its two bodies (unordered), point count, stick state and coefficients; a
  // system's keys sorted, so that neither the patches' order nor which body is a matters
  using PatchKey = std::array<std::uint64_t, 2>;
  std::vector<PatchKey> patch_keys;  // (max_contacts) this solve's
  std::vector<int> order;            // (max_bodies) the kept factor's body at each position
  // counters since Reserve: solves by a kept factor, the refinement's corrections over those,
  // refinements given up (then factored), and factors not kept (a column beyond kMaxColumn)
  long lagged_solves = 0, refinement_steps = 0, lagged_failures = 0, unkept = 0;

  void Reserve(int max_bodies, int max_contacts);
};

/// Keeps the factor now in the BlockCholesky for later steps of this group (the bodies and the
/// patches in g, assembled with every contact active), in the entries of its bodies, unless a
/// column is longer than KeptFactors::kMaxColumn (then the group keeps none).
void KeepFactor(KeptFactors& kept, LaggedFactor& lag, const GroupAssembly& g,
                std::span<const int> bodies, std::span<const ImplicitContact> contacts,
                const BlockCholesky& factor);

/// Drops the factor kept for the group whose first body is `anchor` (its back-off stays).
inline void DropKeptFactor(KeptFactors& kept, int anchor) {
  kept.records[anchor].valid = false;
}

/// Solves the group into g.x with its kept factor if that was made for a system of this shape
/// (the same bodies at the same elimination positions as `factor`'s analysis, the same patch keys)
/// and the back-off allows a try: by iterative refinement against this step's system from the
/// current velocities, until the residual bounds the velocity error in the kinetic-energy norm
/// by 1e-10 of the step's momentum scale, within two corrections and with no contact pulling.
/// False (nothing final written, the caller factors afresh) otherwise; a failed try backs off for
/// the next 1, 3, 7, ... (at most 63) solves of the group. Partitions the contacts into patches
/// (g.patch_range) when the bodies match.
bool SolveWithKeptFactor(const Model& model, const Data& data, std::span<const int> bodies,
                         std::span<const int> slot, std::span<ImplicitContact> contacts,
                         std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                         LaggedFactor& lag, KeptFactors& kept, GroupAssembly& g,
                         const BlockCholesky& factor);

}  // namespace rigidtouch::dynamics
