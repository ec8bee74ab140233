// Assembly of one contact group's linearly implicit system (group_dynamics.h) over 6 x 6 body
// blocks, and the contacts' forces at solved velocities.
//
// The system is (M + h sum c J^T J) v+ = M v + h F + h sum phi J^T (backward Euler on the
// penalty rows). The contacts of one face-face manifold form a patch: consecutive contacts with
// the same bodies, normal and coefficients, whose blocks are assembled at once from the points'
// moments (AssemblePatch in the .cc) instead of a rank-1 update per row.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "dynamics/block_cholesky.h"
#include "dynamics/implicit_contact.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// The assembly's scratch: the group's structure, its patches and the system's right-hand side
/// and solution, by elimination position (BlockCholesky::pos of the body's group slot).
struct GroupAssembly {
  // the group's structure (StructureOf): pairs of group slots that share a contact, PackEdge
  std::vector<std::uint64_t> pairs;  // (max_contacts)
  int npairs = 0;
  std::vector<int> patch_range;  // (2 max_contacts) the active patches' [begin, end)
  int npatch = 0;
  std::vector<Vec6> b, x;  // (max_bodies) right-hand side (then residual), solution
  void Reserve(int max_bodies, int max_contacts);
  std::span<const std::uint64_t> structure() const { return {pairs.data(), std::size_t(npairs)}; }
};

/// The pairs of group slots that share a contact (PackEdge, smaller slot first), sorted and
/// unique, into a.pairs. Equal lists give equal analyses, so a group whose bodies keep touching
/// the same neighbours is analysed once, whatever order its contacts come in and whichever body
/// of a manifold is its reference.
void StructureOf(GroupAssembly& a, std::span<const int> slot,
                 std::span<const ImplicitContact> contacts);

/// The active contacts' patches (consecutive contacts with the same bodies, normal and
/// coefficients) into a.patch_range, [begin, end) each; dropped contacts may lie between two.
void PartitionPatches(GroupAssembly& a, std::span<const ImplicitContact> contacts);

/// Writes M + h sum c J^T J into the factor's blocks and M v + h F + h sum phi J^T into a.b over
/// the active contacts, a patch at a time (partitions them first). The factor's analysis must
/// be that of StructureOf(contacts).
void Assemble(const Model& model, const Data& data, std::span<const int> bodies,
              std::span<const int> slot, std::span<const ImplicitContact> contacts,
              std::span<const Vec3> force_W, std::span<const Vec3> torque_W, GroupAssembly& a,
              BlockCholesky& factor);

/// Writes only M v + h F + h sum phi J^T into a.b, over the patches of the last Assemble (whose
/// contacts may since have changed their phi, not their activity, stick state or coefficients):
/// the factor of that Assemble solves the system again.
void AssembleRightHandSide(const Model& model, const Data& data, std::span<const int> bodies,
                           std::span<const int> slot, std::span<const ImplicitContact> contacts,
                           std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                           GroupAssembly& a, const BlockCholesky& factor);

/// The forces of patch [begin, end) at the velocities a.x, left in its contacts. Returns true if
/// a normal force would pull. `may_drop`: such a contact is taken out (active = false, no
/// force), so the system is solved again without it. kAccumulate: the patch's impulse over the
/// step, h sum J^T f, is added to a.b (the residual of the momentum balance).
template <bool kAccumulate>
bool PatchForces(GroupAssembly& a, const BlockCholesky& factor, const Data& data,
                 std::span<const int> slot, std::span<ImplicitContact> contacts, int begin, int end,
                 bool may_drop, double h);

/// What EnforceFrictionCones changed (bit flags).
enum FrictionChange : int {
  kFrictionKept = 0,
  kFrictionSlipped = 1,  // a sticking patch started to slip
  kFrictionScaled = 2,   // a slipping patch's kinetic friction was lowered
};

/// Coulomb's cone per friction patch (consecutive contacts with the same ImplicitContact::patch;
/// dropped ones count for nothing, and so does a pulling normal force) at the forces PatchForces
/// left in the contacts. A sticking patch whose tangential forces sum to more than mu_static
/// times its normal force, by more than mu_static 1e-10 times its penalty force (a trial force at
/// rounding level, as on a face whose normal force is zero, has no direction to give), slips:
/// each active contact's tangential force becomes kinetic friction
/// mu_kinetic phi_n along the force it had (its trial stick force, which opposes the slip). A
/// slipping patch whose kinetic friction sums to more than mu_kinetic times its normal force at
/// these velocities is scaled down to below it by as much as it was over (at most 1e-3), or, with
/// `last_chance` (no solve after the next), taken out for this step, so that no patch ends a step
/// beyond its cone. Returns the FrictionChange flags; any but kFrictionKept means the group must be
/// solved again.
int EnforceFrictionCones(std::span<ImplicitContact> contacts, bool last_chance);

/// A slipping patch whose kinetic friction (constant over the step) reversed its slip by more
/// than the anchor can take up (the sum of its active contacts' slip_power_W above the sum of
/// |phi_t| reversal_limit_mps) sticks: its contacts take back their anchor springs' tangential
/// rows (c_t_stick_Ns_per_m; phi_t stays the kinetic friction, the anchors' stretch at the slip
/// limit). Backward Euler's Coulomb friction has no slip that reverses within a step: where
/// friction would stop the slip, the contact sticks, and EnforceFrictionCones lets it slip again
/// if sticking needs more than the cone. Without this, a sliding contact whose friction changes
/// its slip velocity by more than that velocity in one step (a rolling ball: its tangential
/// effective mass is 2/7 of its mass) reverses its slip and its friction every step. Returns
/// whether a patch was made to stick (the group must be solved again).
bool StickReversedSlips(std::span<ImplicitContact> contacts);

}  // namespace rigidtouch::dynamics
