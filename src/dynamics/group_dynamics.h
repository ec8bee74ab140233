// Velocity update of one contact group (tick stage 5): Eq. 1 over the step with penalty contact.
//
// Tool contacts are explicit (a device can only render forces from its current state). Scene
// contacts are linearly implicit (backward Euler): a row with force phi - c (J v+) gives
//   (M + h sum c J^T J) v+ = M v + h F + h sum phi J^T,
// so a stack of 0.1 kg boxes can use a stiffness of 2e5 N/m at h = 1 ms without going unstable.
//
// Each contact is a normal row and, while it sticks, two tangential rows; the contacts of one
// face-face manifold share their blocks' assembly (group_assembly.h). The system is solved by a
// sparse Cholesky factorisation over 6 x 6 body blocks (block_cholesky.h): only bodies that share
// a contact couple, the bodies are eliminated in minimum-degree order (a column of boxes is a
// chain and factors without fill-in; a leaning pile is a 3-D lattice where the order keeps the
// fill small), and the kernels are fixed-size 6 x 6 loops that never allocate. A factor may be
// reused over steps (lagged_factor.h).
#pragma once

#include <span>

#include "dynamics/block_cholesky.h"
#include "dynamics/group_assembly.h"
#include "dynamics/implicit_contact.h"
#include "dynamics/lagged_factor.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// Scratch for one group's solve, sized once for the largest allowed group; reused every tick:
/// the units' own scratch (block Cholesky, assembly, lagged factor) and the solve's counter. On its
/// own cache lines: the two threads' scratches sit side by side (VelocityScratch), and each
/// thread's counters would otherwise share a line with what the other reads.
struct alignas(64) GroupSolverScratch {
  int max_bodies = 0, max_contacts = 0;
  BlockCholesky factor;    // ordering, fill-in analysis and factor over the group's bodies
  GroupAssembly assembly;  // structure, patches, right-hand side and solution
  // the use of kept factors (lagged.reuse_factor false: every solve factors afresh) and its
  // counters (lagged_solves, refinement_steps, lagged_failures, unkept)
  LaggedFactor lagged;
  long factorisations = 0;  // solves that factored since Reserve (each pass counts)
  void Reserve(int max_group_bodies, int max_contacts);
};

/// Solves the new velocities of the group's bodies, in place in data.bodies. `force_W` and
/// `torque_W` hold each body's explicit force (gravity, user, gyroscopic, explicit contacts).
/// Contacts whose normal force would pull after the solve are dropped (friction included) and
/// the solve repeated (at most a few times), so the penalty never pulls. Each friction patch is
/// held to its Coulomb cone at the solved velocities (EnforceFrictionCones): a sticking patch
/// beyond it slips and the group is solved again (the pulls of that trial do not count); a
/// slipping patch's kinetic friction beyond mu_k N is lowered and the right-hand side solved
/// again with the same factor. Each contact's forces at
/// the new velocities are left in it. Returns false if the group exceeds the scratch's capacity
/// or the factorisation failed (then nothing is written). The ordering and fill-in analysis is
/// kept in the scratch and reused while the group's bodies touch the same neighbours.
///
/// With scratch.lagged.reuse_factor, a group whose system keeps its shape from its last solve
/// (same bodies, patches, stick states and coefficients; only the contacts' geometry and forces
/// moved) is solved with the factorisation that solve kept in `kept` (each group its own, stored
/// with its bodies; groups of other bodies in between do not disturb it) by iterative refinement
/// from the current velocities.
/// Its result x is accepted only if the residual r of the momentum balance bounds the error in
/// the kinetic-energy norm, sqrt((x - x*)^T M (x - x*)) <= |r|_M^-1 <= 1e-10 (|M v| + |h F| +
/// |r(v)|) (A >= M, so A^-1 <= M^-1), within two corrections and with no contact pulling;
/// otherwise the system is assembled and factored as without it, and the kept factor is not
/// tried again for the next 1, 3, 7, ... (at most 63) solves of the group. This pays off where
/// contact rests (a stack, a pile, an object held still), where the step changes the system little;
/// a group in fast motion factors every step.
bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitContact> contacts,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& scratch, KeptFactors& kept);

}  // namespace rigidtouch::dynamics
