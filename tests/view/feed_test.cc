// The viewer's feed: the reader of the triple buffer always gets a whole snapshot, never a mix of
// two ticks, and the newest one; the haptic thread, feeding a viewer that reads all the time while
// it records and taps with the mouse device, neither allocates nor takes a lock.
#include "view/feed.h"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "analysis/tap_experiment.h"
#include "device/mouse_device.h"
#include "dynamics/tree.h"
#include "limit_malloc.h"
#include "loop/haptic_loop.h"

// counts the mutex locks of threads that asked for it (std::mutex and every pthread mutex end
// here), passing them on to the C library's
namespace {
thread_local bool count_locks = false;
thread_local long locks = 0;
}  // namespace

extern "C" int pthread_mutex_lock(pthread_mutex_t* m) {
  using Lock = int (*)(pthread_mutex_t*);
  static const Lock real = reinterpret_cast<Lock>(dlsym(RTLD_NEXT, "pthread_mutex_lock"));
  if (count_locks) ++locks;
  return real(m);
}

namespace rigidtouch::view {
namespace {

struct Block {
  std::array<std::int64_t, 64> v{};
};

TEST(TripleBuffer, ReaderSeesWholeSnapshotsAndTheNewest) {
  TripleBuffer<Block> buffer;
  constexpr std::int64_t kWrites = 200000;
  std::atomic<bool> done{false};
  std::atomic<std::int64_t> reads{0};
  std::int64_t written = 0;
  std::thread writer([&] {
    // at least kWrites, and on until the reader has read 1000 times while writes went on
    for (std::int64_t k = 1; k <= kWrites || reads.load() < 1000; ++k) {
      buffer.back().v.fill(k);
      buffer.Publish();
      written = k;
    }
    done.store(true);
  });
  std::int64_t last = 0;
  while (!done.load()) {
    if (!buffer.Update()) continue;
    const Block& b = buffer.front();
    for (const std::int64_t x : b.v) ASSERT_EQ(x, b.v[0]);  // one tick's values, never two
    ASSERT_GE(b.v[0], last);                                // never older than before
    last = b.v[0];
    reads.fetch_add(1);
  }
  writer.join();
  buffer.Update();
  EXPECT_EQ(buffer.front().v[0], written);  // the newest once the writer stops
}

TEST(ViewFeed, HapticThreadNeitherAllocatesNorLocks) {
  if (!test::kMallocCounting) GTEST_SKIP() << "allocations are not counted under sanitizers";
  // the lock counter counts: a std::mutex on a counted thread shows up
  {
    std::mutex m;
    count_locks = true;
    m.lock();
    m.unlock();
    count_locks = false;
    ASSERT_EQ(locks, 1);
    locks = 0;
  }
  analysis::TapExperimentConfig c;
  c.scene_path = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml";
  c.load.device.coupling = Coupling::kDirect;
  c.rate_hz = 1000.0;
  analysis::TapSetup setup = analysis::PrepareTap(c);
  const Model& model = setup.model;
  device::MouseDevice mouse(setup.device, device::MouseDeviceParams{},
                            model.initial[model.tool].x_W);
  Data data = MakeData(model);
  ViewFeed feed(1000.0, 1024);
  loop::RecordQueue records(4096, [](std::span<const io::RecordSample>) {});
  std::atomic<bool> done{false};
  std::atomic<std::int64_t> snapshots{-1};  // the newest step the viewer has seen
  std::atomic<bool> reading{false};
  // the viewer's side: reads snapshots and drains the scope as fast as it can
  std::thread viewer([&] {
    std::vector<ScopeSample> scope(512);
    reading.store(true);
    while (!done.load()) {
      snapshots.store(feed.Latest().step);
      feed.PopScope(scope.data(), scope.size());
      mouse.SetTarget(model.initial[model.tool].x_W);
    }
  });
  while (!reading.load()) std::this_thread::yield();
  mouse.RequestTap();
  loop::HapticLoopResult r;
  long allocations = 0;
  {
    test::LimitMalloc guard;
    count_locks = true;
    r = loop::RunHapticTicks(model, data, mouse, 1000.0, 600, nullptr, nullptr, &records, &feed);
    count_locks = false;
    allocations = guard.allocations();
  }
  // the viewer keeps reading until the last tick's snapshot reaches it
  while (snapshots.load() != data.step) std::this_thread::yield();
  done.store(true);
  viewer.join();
  records.Close();
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(locks, 0);
  EXPECT_EQ(r.timing.ticks, 600);
  EXPECT_GT(r.impulses, 0);  // the tap hit the wall: the contact path ran too
}

// a tree's links and joints reach the viewer: every link's pose and every hinge's position as the
// tick left them, copied on the haptic thread without an allocation (scenes/arm.xml: one tree of
// six links and six hinges)
TEST(ViewFeed, TreeLinksAndJointsAreCopiedWithoutAllocating) {
  LoadOptions o;
  o.tool_name = "none";
  const Model model = LoadModel(std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/arm.xml", o);
  ASSERT_EQ(model.trees.size(), 1u);
  Data data = MakeData(model);
  for (int k = 0; k < 200; ++k) Tick(model, data, TickInput{});  // the arm sags under gravity
  ViewFeed feed(1000.0, 16);
  TraceSample sample;
  sample.step = data.step;
  long allocations = 0;
  {
    test::LimitMalloc guard;
    feed.OnTick(model, data, sample);
    allocations = guard.allocations();
  }
  if (test::kMallocCounting) {
    EXPECT_EQ(allocations, 0);
  }
  const ViewSnapshot& v = feed.Latest();
  const dynamics::TreeData& d = *data.trees[0];
  ASSERT_EQ(v.nlink, static_cast<int>(d.x_W.size()));
  for (int l = 0; l < v.nlink; ++l) {
    EXPECT_EQ(v.link_x_W[l], d.x_W[l]) << l;
    EXPECT_EQ(v.link_R_WB[l], d.R_WB[l]) << l;
  }
  ASSERT_EQ(v.njoint, 6);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(v.joint_q[j], d.qpos[model.trees[0].joints[j].qpos_adr]) << j;
  }
  EXPECT_GT(std::abs(v.joint_q[1]), 1e-4);  // the shoulder moved: not the initial zeros
  EXPECT_EQ(FirstViewLink(model, 0), 0);
}

}  // namespace
}  // namespace rigidtouch::view
