// Collision detection (tick stage 2): broad phase, narrow phase, and contact identity across ticks.
//
// Plane, sphere and box pairs use rigidtouch's own narrow phase (narrow_phase.h); capsule and
// mesh pairs use MuJoCo's per-pair collision functions on the compiled model. MuJoCo's whole
// mj_collision is not used in the tick: it allocates every call and costs more than the step's
// budget on a 100-box pile (docs/decisions.md).
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <vector>

#include "geometry/broadphase.h"
#include "geometry/contact_matching.h"
#include "geometry/narrow_phase.h"
#include "parallel/worker.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::geometry {

/// What the narrow phase makes of one geom this tick.
enum class GeomCheck : unsigned char {
  kMuJoCo,    // a type MuJoCo's per-pair functions collide
  kAccepted,  // rigidtouch's narrow phase: SizeValid and (this tick) PoseFinite
  kRejected,  // rigidtouch's narrow phase, which gives it no contact (non-finite pose, bad size)
};

/// A geom on a dynamic body, whose pose DetectContacts computes every tick.
struct MovingGeom {
  int geom = -1;
  // a sphere whose rotation matrix nothing reads (no geom of the model takes MuJoCo's path, which
  // copies both geoms' rotations): its pose is its centre, R_WG is left as it was
  bool centre_only = false;
  // a centre-only sphere at its body's origin (pos_B is +0): its centre is the body's position
  bool at_body_origin = false;
  // any other geom whose frame is its body's (pos_B and quat_B (+0, +0, +0) and (+0, +0, +0, 1)):
  // its rotation matrix is the body's, which DetectContacts computes anyway (see UpdatePoses)
  bool body_frame = false;
};

/// Scratch of the collision stage, sized by Reserve.
struct CollisionScratch {
  // (ngeom) world poses: a static geom's are set by Reserve and Reset (the model is constant), the
  // moving geoms' every tick
  std::vector<GeomPose> poses;
  std::vector<GeomCheck> geom_kind;   // (ngeom) from the model's types and sizes (Reserve)
  std::vector<GeomCheck> geom_check;  // (ngeom) with the poses, as the poses are set
  std::vector<MovingGeom> moving;     // geoms on dynamic bodies, in geom order
  Broadphase broadphase;
  std::array<ContactPoint, kMaxPairContacts> points{};  // one pair's narrow-phase output
  std::vector<mjContact> mj_contacts;                   // one pair's MuJoCo output (mjMAXCONPAIR)
  mjData* mj = nullptr;                                 // MuJoCo data for the fallback functions
  // last tick's contacts and the next contact id, for the contacts' identity across ticks
  ContactMatching matching;

  // Model::threads 2: the tick's thread takes blocks of the pair list from the front and the
  // worker thread (owned by the Workspace) from the back, each colliding into its own point
  // buffer; the tick's thread then writes the points into the contact list in pair order, as one
  // thread would
  struct PairPoints {
    int offset = 0;  // into the point buffer of the thread that collided the pair
    int count = 0;   // points; -1: the tick's thread collides the pair itself, in order (MuJoCo's
                     // functions, which share `mj`, or a full buffer)
    int thread = 0;  // whose buffer: 0 the tick's thread, 1 the worker
  };
  std::vector<PairPoints> pair_points;                     // (pair capacity)
  std::array<std::vector<ContactPoint>, 2> thread_points;  // (max contacts + kMaxPairContacts)
  std::array<int, 2> thread_used{};                        // points in each buffer this tick
  parallel::TwoEndedRange pair_blocks;                     // blocks of kPairBlock pairs
  // when the two threads also write the contacts (every pair's count known, and all fit): each
  // pair's first contact and its run in the list (data.runs; a pair without points has none), and
  // whether it has a new one (numbered afterwards)
  std::vector<int> pair_first;          // (pair capacity)
  std::vector<int> pair_run;            // (pair capacity)
  std::vector<unsigned char> pair_new;  // (pair capacity)
  long written_on_two_threads = 0;      // ticks whose contacts both threads wrote, since made
  struct NarrowJob {
    const Model* model = nullptr;
    CollisionScratch* scratch = nullptr;
    Data* data = nullptr;  // written by the write job, each pair's contacts by one thread
    // the value of `progress` before this tick's collision stage began
    std::uint32_t progress_before = 0;
  };
  NarrowJob job;
  // raised by the tick's thread once this tick's sweep may be shared (by 1) and once the pairs
  // are found (by 2): the worker, which indexes last tick's contacts first, then takes blocks of
  // the sweep and then of the narrow phase
  parallel::WakeCounter progress;

  /// Sizes every buffer for `model`; allocates MuJoCo's data. Throws Error if that fails.
  void Reserve(const Model& model);
  /// Sizes the buffers of the narrow phase on two threads (MakeData, for Model::threads 2).
  void ReserveTwoThreads(const Model& model);
  /// Puts the persistent sort order back to its initial state; sets the static geoms' poses
  /// again.
  void Reset(const Model& model);
  CollisionScratch() = default;
  CollisionScratch(const CollisionScratch&) = delete;
  CollisionScratch& operator=(const CollisionScratch&) = delete;
  ~CollisionScratch();
};

/// Detects contacts at the poses in `data.bodies` into data.contacts (first data.ncontact valid,
/// the points of one geom pair contiguous, and indexed by data.runs), matching each to the contacts
/// data.contacts held before the call (they become scratch.matching.previous) to keep ids and
/// friction anchors
/// and to mark new contacts. Reads the bodies' rotations from data.R_WB (the kinematics stage).
/// Never allocates or throws; a full contact list counts Warning::kContactFull. With a worker
/// (Model::threads 2, buffers sized by ReserveTwoThreads) the two threads share the narrow phase;
/// the contacts are the same, bit for bit.
void DetectContacts(const Model& model, Data& data, CollisionScratch& scratch,
                    parallel::Worker* worker = nullptr);

}  // namespace rigidtouch::geometry
