// The worker thread of Model::threads 2: jobs hand over their data both ways, and the narrow phase
// shared with it gives the contacts of one thread, bit for bit. Run under ThreadSanitizer by
// scripts/test.sh.
#include "geometry/worker.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <thread>

#include "render/workspace.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::geometry {
namespace {

struct Counter {
  int input = 0;  // written by the test before each Post
  long sum = 0;   // the job's running sum of the inputs
  int other = 0;  // jobs that ran on a thread other than the test's
  std::thread::id caller;
};

void AddInput(void* context) {
  auto* c = static_cast<Counter*>(context);
  c->sum += c->input;
  if (std::this_thread::get_id() != c->caller) ++c->other;
}

// each posted job runs once, on the worker, sees what was written before Post, and its writes
// are seen after Wait: the sum of 1..2000 (a lost or repeated job, or a stale input, changes it)
TEST(WorkerTest, RunsEachPostedJobOnceOnItsThread) {
  Worker worker;
  Counter c;
  c.caller = std::this_thread::get_id();
  for (int i = 1; i <= 2000; ++i) {
    c.input = i;
    worker.Post(&AddInput, &c);
    worker.Wait();
  }
  EXPECT_EQ(c.sum, 2000L * 2001L / 2);
  EXPECT_EQ(c.other, 2000);
}

bool SameBits(const Vec3& a, const Vec3& b) {
  return std::memcmp(a.data(), b.data(), 24) == 0;
}

// a 64-box pile (more than the 32 pairs from which the worker takes half) settling under the
// tool pushed down: every tick's contact list with two threads is the one-thread list, bit for
// bit (points, normals, depths, ids, forces), and so are the body states
TEST(WorkerTest, TwoThreadsGiveTheContactsOfOne) {
  const std::string path =
      test::WriteTempFile("pile_threads.xml", test::PileXml(4, 4, 4, 0.051, 0.22));
  LoadOptions o1, o2;
  o2.threads = 2;
  const Model m1 = LoadModel(path, o1);
  const Model m2 = LoadModel(path, o2);
  Data d1 = MakeData(m1);
  Data d2 = MakeData(m2);
  ASSERT_EQ(d1.workspace->collision.worker, nullptr);
  ASSERT_NE(d2.workspace->collision.worker, nullptr);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  int most = 0;
  for (int s = 0; s < 300; ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    ASSERT_EQ(d1.ncontact, d2.ncontact) << "step " << s;
    most = std::max(most, d1.workspace->collision.broadphase.npair);
    for (int k = 0; k < d1.ncontact; ++k) {
      const Contact& a = d1.contacts[k];
      const Contact& b = d2.contacts[k];
      ASSERT_TRUE(a.id == b.id && a.geom_a == b.geom_a && a.geom_b == b.geom_b &&
                  SameBits(a.p_W, b.p_W) && SameBits(a.n_W, b.n_W) &&
                  std::memcmp(&a.depth_m, &b.depth_m, 8) == 0 &&
                  std::memcmp(&a.normal_force_N, &b.normal_force_N, 8) == 0)
          << "step " << s << " contact " << k;
    }
  }
  for (std::size_t i = 0; i < d1.bodies.size(); ++i) {
    EXPECT_TRUE(SameBits(d1.bodies[i].x_W, d2.bodies[i].x_W)) << "body " << i;
  }
  EXPECT_GT(most, 40);  // above the 32 pairs from which the worker takes half
}

}  // namespace
}  // namespace rigidtouch::geometry
