// What the haptic thread hands the viewer: the latest world snapshot through a lock-free triple
// buffer (the writer never waits, the reader always gets a whole snapshot), and every tick's forces
// for the scope through a lock-free single-producer queue. Nothing here allocates, locks or blocks
// on the haptic thread; sizes are fixed when the feed is built.
#pragma once

#include <array>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>

#include "loop/haptic_loop.h"

namespace rigidtouch::view {

/// A value shared by one writer and one reader without locks (triple buffering): the writer fills
/// its back slot and swaps it with the middle one; the reader swaps the middle slot in when it is
/// newer. Neither waits for the other.
template <typename T>
class TripleBuffer {
 public:
  /// Writer side: the slot to fill, then Publish().
  T& back() { return slots_[back_]; }
  void Publish() noexcept {
    back_ = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) & kIndex;
  }
  /// Reader side: takes the newest published value if there is one; returns whether it did.
  bool Update() noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  const T& front() const { return slots_[front_]; }

 private:
  static constexpr unsigned kIndex = 3, kFresh = 4;
  std::array<T, 3> slots_{};
  unsigned back_ = 0, front_ = 1;
  std::atomic<unsigned> middle_{2};
};

/// Largest numbers of bodies and contacts a snapshot carries (the rest are not drawn).
inline constexpr int kMaxViewBodies = 256;
inline constexpr int kMaxViewContacts = 64;
/// Largest numbers of tree links (over every tree, in tree order) and of hinge and slide joints a
/// snapshot carries.
inline constexpr int kMaxViewLinks = 64;
inline constexpr int kMaxViewJoints = 32;

/// One contact as drawn.
struct ContactView {
  Vec3 p_W = Vec3::Zero();
  Vec3 n_W = Vec3::UnitZ();
  double depth_m = 0.0;
  bool tool = false;  // one of the geoms is the tool's
};

/// The world after one tick, for drawing.
struct ViewSnapshot {
  std::int64_t step = -1;  // -1: nothing published yet
  double time_s = 0.0;
  int nbody = 0;
  std::array<Vec3, kMaxViewBodies> x_W{};
  std::array<Quat, kMaxViewBodies> q_WB{};
  // tree links' poses (every tree's links one after the other, Model::trees order)
  int nlink = 0;
  std::array<Vec3, kMaxViewLinks> link_x_W{};
  std::array<Mat3, kMaxViewLinks> link_R_WB{};
  // hinge and slide positions (rad, m), every tree's in joint order; other joints are skipped
  int njoint = 0;
  std::array<double, kMaxViewJoints> joint_q{};
  int ncontact = 0;
  std::array<ContactView, kMaxViewContacts> contacts{};
  TraceSample sample;  // the tick's forces, tool state and penetration
  // the haptic thread's own clock: rate and period error over the last second of ticks
  double measured_rate_hz = 0.0;
  double period_error_max_s = 0.0;   // largest |interval - period| in the last full second
  double period_error_mean_s = 0.0;  // mean over the same second
  std::uint64_t scope_dropped = 0;   // scope samples the full queue dropped
  std::uint32_t warnings = 0;        // Data::warnings kinds raised so far (bit per kind)
};

/// One tick on the scope.
struct ScopeSample {
  double time_s = 0.0;
  double penalty_N = 0.0;    // |penalty (or coupling) force|
  double impulsive_N = 0.0;  // |Eq. 9 force|
  double total_N = 0.0;      // |force sent to the device|
  double penetration_m = 0.0;
  int impulses = 0;
};

/// Index of tree t's first link in ViewSnapshot's link arrays.
int FirstViewLink(const Model& model, int t);

/// Copies the trees' link poses and hinge and slide positions into `v` (up to the snapshot's
/// sizes); no allocation.
void SnapshotTrees(const Model& model, const Data& data, ViewSnapshot& v) noexcept;

/// The haptic loop's observer that feeds a viewer.
class ViewFeed : public loop::TickObserver {
 public:
  /// `rate_hz` is the loop's rate (for the period error); the scope queue holds `scope_capacity`
  /// ticks between two frames.
  ViewFeed(double rate_hz, std::size_t scope_capacity);

  void OnTick(const Model& model, const Data& data, const TraceSample& sample) noexcept override;

  /// Reader side (one thread): the newest snapshot.
  const ViewSnapshot& Latest() {
    snapshots_.Update();
    return snapshots_.front();
  }
  /// Reader side: moves every pending scope sample into `out` (up to its size); returns how many.
  std::size_t PopScope(ScopeSample* out, std::size_t max) { return scope_.pop(out, max); }

 private:
  double period_s_;
  TripleBuffer<ViewSnapshot> snapshots_;
  boost::lockfree::spsc_queue<ScopeSample> scope_;
  std::uint64_t scope_dropped_ = 0;
  // period statistics of the current second
  std::chrono::steady_clock::time_point last_tick_{};
  bool have_last_ = false;
  double window_elapsed_s_ = 0.0;
  std::int64_t window_ticks_ = 0;
  double window_error_max_s_ = 0.0, window_error_sum_s_ = 0.0;
  double rate_hz_ = 0.0, error_max_s_ = 0.0, error_mean_s_ = 0.0;
};

}  // namespace rigidtouch::view
