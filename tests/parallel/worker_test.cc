// The worker thread of Model::threads 2: jobs hand over their data both ways, the two-ended range
// hands out each index once, and the narrow phase and group solves shared with it give the
// contacts, states and kept factor of one thread, bit for bit, without allocating. Run under
// ThreadSanitizer by scripts/test.sh.
#include "parallel/worker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "draw.h"
#include "dynamics/tree.h"
#include "engine/workspace.h"
#include "limit_malloc.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::parallel {
namespace {

struct Counter {
  int input = 0;  // written by the test before each Post
  long sum = 0;   // the job's running sum of the inputs
  int other = 0;  // jobs that ran on a thread other than the test's
  std::thread::id caller;
  long busy_ns = 0;  // how long the job runs
};

void AddInput(void* context) {
  auto* c = static_cast<Counter*>(context);
  if (c->busy_ns > 0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::nanoseconds(c->busy_ns);
    while (std::chrono::steady_clock::now() < until) {
    }
  }
  c->sum += c->input;
  if (std::this_thread::get_id() != c->caller) ++c->other;
}

// each posted job runs once, on the worker or taken back by Finish, sees what was written before
// Post, and its writes are seen after Finish: the sum of 1..2000 (a lost or repeated job, or a
// stale input, changes it)
TEST(WorkerTest, RunsEachPostedJobOnceOnItsThread) {
  Worker worker;
  Counter c;
  c.caller = std::this_thread::get_id();
  for (int i = 1; i <= 2000; ++i) {
    c.input = i;
    worker.Post(&AddInput, &c);
    worker.Finish();
  }
  EXPECT_EQ(c.sum, 2000L * 2001L / 2);
  EXPECT_EQ(c.other + worker.jobs_taken_back(), 2000);
}

// the hand-off's wake-ups, without the spin that usually hides them: a thread that has gone to
// sleep on a counter is woken by the other's change to it. Thirty thousand hand-offs in which the
// threads sleep, with sleep limits of a second: without the wake-ups the test would take hours,
// with them it takes a second or two (tens under the sanitizers). The hand-offs run on a thread
// of their own, so that the test can fail after two minutes (and exit: a thread asleep for good
// cannot be joined) rather than hang
TEST(WorkerTest, NoWakeUpIsLostWhenTheThreadsSleep) {
  static constexpr int kHandOffs = 30000;
  std::atomic<int> done{0};
  std::thread stress([&done] {
    Worker worker(/*spins=*/0, /*tick_sleep_limit_ns=*/1'000'000'000,
                  /*worker_sleep_limit_ns=*/1'000'000'000);
    Counter c;
    c.caller = std::this_thread::get_id();
    for (int i = 1; i <= kHandOffs; ++i) {
      c.input = 1;
      // jobs of 0 to 3 us: about as long as the library's own short spin in wait, so that the
      // waiting thread often goes to sleep just as the job ends
      c.busy_ns = (i * 7919L) % 3000;
      worker.Post(&AddInput, &c);
      // every other job must run on the worker: the posting thread sleeps until it has
      if (i % 2 == 0) {
        worker.Wait();
      } else {
        worker.Finish();
      }
      done.store(i, std::memory_order_relaxed);
    }
    EXPECT_EQ(c.sum, kHandOffs);
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (done.load() < kHandOffs && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (done.load() < kHandOffs) {
    ADD_FAILURE() << "the hand-off stopped after " << done.load() << " of " << kHandOffs
                  << ": a wake-up was lost";
    std::fflush(nullptr);
    std::_Exit(1);
  }
  stress.join();
}

// a waiter asleep on a counter returns once the counter has changed even when no wake-up came (a
// lost one), after at most its sleep limit: the tick never waits for good on a wake-up the system
// lost
TEST(WorkerTest, ALostWakeUpCostsAtMostTheSleepLimit) {
  WakeCounter counter;
  std::atomic<bool> returned{false};
  std::uint32_t seen = 0;
  std::thread waiter([&] {
    seen = counter.AwaitChange(0, /*spins=*/0, /*sleep_limit_ns=*/1'000'000);
    returned.store(true);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(returned.load());  // nothing changed: still waiting
  counter.StoreWithoutWaking(7);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!returned.load() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!returned.load()) {
    ADD_FAILURE() << "the waiter still sleeps 10 s after the change";
    std::fflush(nullptr);
    std::_Exit(1);
  }
  waiter.join();
  EXPECT_EQ(seen, 7u);
}

// two threads taking from both ends of a range take every index once: the front's in rising
// order, the back's in falling order, every front index below every back index
TEST(WorkerTest, TwoEndedRangeHandsOutEachIndexOnce) {
  constexpr int kN = 200000;
  TwoEndedRange range;
  std::vector<int> front, back;
  front.reserve(kN);
  back.reserve(kN);
  range.Reset(0, kN);
  std::thread other([&] {
    for (int i = range.TakeBack(); i >= 0; i = range.TakeBack()) back.push_back(i);
  });
  for (int i = range.TakeFront(); i >= 0; i = range.TakeFront()) front.push_back(i);
  other.join();
  ASSERT_EQ(front.size() + back.size(), static_cast<std::size_t>(kN));
  EXPECT_TRUE(std::is_sorted(front.begin(), front.end()));
  EXPECT_TRUE(std::is_sorted(back.rbegin(), back.rend()));
  for (std::size_t k = 0; k < front.size(); ++k) ASSERT_EQ(front[k], static_cast<int>(k));
  for (std::size_t k = 0; k < back.size(); ++k) ASSERT_EQ(back[k], kN - 1 - static_cast<int>(k));
  EXPECT_EQ(range.TakeFront(), -1);
  EXPECT_EQ(range.TakeBack(), -1);
}

bool SameVec3Bits(const Vec3& a, const Vec3& b) {
  return std::memcmp(a.data(), b.data(), 24) == 0;
}

// the state a step leaves for the next one's kept-factor reuse: every group's record (what its
// factor was made for, the back-off) and every body's column of it, bit for bit
bool SameKeptFactors(const Data& d1, const Data& d2) {
  const dynamics::KeptFactors& a = d1.workspace->velocity.kept;
  const dynamics::KeptFactors& b = d2.workspace->velocity.kept;
  for (std::size_t i = 0; i < a.records.size(); ++i) {
    const dynamics::KeptFactors::Record &ra = a.records[i], &rb = b.records[i];
    if (ra.valid != rb.valid || ra.version != rb.version || ra.nb != rb.nb ||
        ra.npatch != rb.npatch || ra.keys != rb.keys || ra.lag_backoff != rb.lag_backoff ||
        ra.lag_skip != rb.lag_skip) {
      return false;
    }
    const dynamics::KeptFactors::Column &ca = a.columns[i], &cb = b.columns[i];
    if (ca.anchor != cb.anchor || ca.version != cb.version || ca.pos != cb.pos ||
        ca.count != cb.count || std::memcmp(ca.diag.data(), cb.diag.data(), 36 * 8) != 0 ||
        std::memcmp(ca.diag_inv.data(), cb.diag_inv.data(), 6 * 8) != 0) {
      return false;
    }
    for (int e = 0; e < ca.count; ++e) {
      if (ca.row[e] != cb.row[e] || std::memcmp(ca.off[e].data(), cb.off[e].data(), 36 * 8) != 0) {
        return false;
      }
    }
  }
  return true;
}

// data.runs indexes the contact list: consecutive runs that cover it, each the points of one geom
// pair (one run per pair) with that pair's geoms and bodies
void ExpectRunsIndexTheList(const Data& d, int step) {
  int next = 0;
  for (int r = 0; r < d.nruns; ++r) {
    const PairRun& run = d.runs[r];
    ASSERT_EQ(run.begin, next) << "step " << step << " run " << r;
    ASSERT_GE(run.count, 1) << "step " << step << " run " << r;
    for (int c = run.begin; c < run.begin + run.count; ++c) {
      const Contact& con = d.contacts[c];
      ASSERT_TRUE(con.geom_a == run.geom_a && con.geom_b == run.geom_b &&
                  con.body_a == run.body_a && con.body_b == run.body_b)
          << "step " << step << " run " << r << " contact " << c;
    }
    if (r > 0) {
      ASSERT_FALSE(d.runs[r - 1].geom_a == run.geom_a && d.runs[r - 1].geom_b == run.geom_b)
          << "step " << step << " run " << r;
    }
    next += run.count;
  }
  ASSERT_EQ(next, d.ncontact) << "step " << step;
}

// one scene file loaded and made with one and with two threads
struct OneAndTwoThreads {
  static Model Load(const std::string& path, int threads) {
    LoadOptions o;
    o.threads = threads;
    return LoadModel(path, o);
  }
  explicit OneAndTwoThreads(const std::string& path)
      : m1(Load(path, 1)), m2(Load(path, 2)), d1(MakeData(m1)), d2(MakeData(m2)) {}
  const Model m1, m2;
  Data d1, d2;
};

// a 288-box pile (more than the 256 boxes from which the worker shares the broad phase, and the
// 32 pairs from which it shares the narrow phase) settling under the tool pushed down: every
// tick's contact list with two threads is the one-thread list, bit for bit (points, normals,
// depths, ids, matching, forces, and its index of runs), and so are the body states
TEST(WorkerTest, TwoThreadsGiveTheContactsOfOne) {
  OneAndTwoThreads t(test::WriteTempFile("pile_threads.xml", test::PileXml(6, 6, 8, 0.051, 0.45)));
  const Model &m1 = t.m1, &m2 = t.m2;
  Data &d1 = t.d1, &d2 = t.d2;
  ASSERT_EQ(d1.workspace->worker, nullptr);
  ASSERT_NE(d2.workspace->worker, nullptr);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  int most = 0;
  for (int s = 0; s < 300; ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    ASSERT_EQ(d1.ncontact, d2.ncontact) << "step " << s;
    ASSERT_TRUE(SameKeptFactors(d1, d2)) << "step " << s;
    most = std::max(most, d1.workspace->collision.broadphase.npair);
    for (int k = 0; k < d1.ncontact; ++k) {
      const Contact& a = d1.contacts[k];
      const Contact& b = d2.contacts[k];
      ASSERT_TRUE(a.id == b.id && a.geom_a == b.geom_a && a.geom_b == b.geom_b &&
                  a.is_new == b.is_new && a.sticking == b.sticking && a.phase == b.phase &&
                  a.group == b.group && a.pair_points == b.pair_points &&
                  SameVec3Bits(a.p_W, b.p_W) && SameVec3Bits(a.n_W, b.n_W) &&
                  SameVec3Bits(a.anchor_A, b.anchor_A) && SameVec3Bits(a.anchor_B, b.anchor_B) &&
                  std::memcmp(&a.depth_m, &b.depth_m, 8) == 0 &&
                  std::memcmp(&a.normal_force_N, &b.normal_force_N, 8) == 0)
          << "step " << s << " contact " << k;
      // each contact's group is its dynamic body's (stage 3 writes it with the windows)
      ASSERT_EQ(a.group, d1.body_group[a.body_a >= 0 ? a.body_a : a.body_b])
          << "step " << s << " contact " << k;
    }
    ASSERT_EQ(d1.workspace->collision.matching.next_contact_id,
              d2.workspace->collision.matching.next_contact_id)
        << "step " << s;
    // the list's index of runs, which the groups are built from, on either path
    ExpectRunsIndexTheList(d1, s);
    ExpectRunsIndexTheList(d2, s);
  }
  // the contacts were written and matched on the two threads in the steps with enough pairs
  EXPECT_GT(d2.workspace->collision.written_on_two_threads, 100);
  for (std::size_t i = 0; i < d1.bodies.size(); ++i) {
    EXPECT_TRUE(SameVec3Bits(d1.bodies[i].x_W, d2.bodies[i].x_W)) << "body " << i;
  }
  EXPECT_GT(most, 40);  // above the 32 pairs from which the worker takes half
  // and in a step of the pile (36 columns, over 200 contacts) the worker was offered four jobs:
  // indexing last tick's contacts and then the sweep and the narrow phase (one job), writing the
  // contacts, the free-motion forces (while the groups are built), and the groups' laws, friction
  // decisions, windows, contact forces and solves (stages 3 to 5, each group whole on one thread)
  const long posted = d2.workspace->worker->jobs_posted();
  Tick(m2, d2, in);
  EXPECT_GT(d2.ncontact, 200);
  EXPECT_EQ(d2.workspace->worker->jobs_posted() - posted, 4);
}

// two columns of 10 boxes settling for 3000 steps, two groups, which the two threads share
// (either may solve either column in a step). Each column keeps its own factor with its bodies,
// whichever thread made it, and the states and kept factors are those of one thread after every
// step, bit for bit; almost every solve is a lagged one on both. On a loaded machine the system
// may not run the worker in time for any of the first 3000 steps' groups (the tick's thread then
// solves both); the columns are then stepped on, up to 30000 steps, until the worker has solved
// some.
TEST(WorkerTest, GroupsSolvedOnTwoThreadsKeepTheirFactors) {
  OneAndTwoThreads t(
      test::WriteTempFile("columns_threads.xml", test::PileXml(2, 1, 10, 0.051, 0.21)));
  const Model &m1 = t.m1, &m2 = t.m2;
  Data &d1 = t.d1, &d2 = t.d2;
  TickInput in;
  const dynamics::VelocityScratch& worker_side = d2.workspace->velocity;
  for (int s = 0; s < 3000 || (worker_side.worker_solver.lagged.lagged_solves == 0 && s < 30000);
       ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    for (std::size_t i = 0; i < d1.bodies.size(); ++i) {
      ASSERT_TRUE(SameVec3Bits(d1.bodies[i].x_W, d2.bodies[i].x_W) &&
                  SameVec3Bits(d1.bodies[i].v_W, d2.bodies[i].v_W) &&
                  SameVec3Bits(d1.bodies[i].w_W, d2.bodies[i].w_W))
          << "step " << s << " body " << i;
    }
    ASSERT_TRUE(SameKeptFactors(d1, d2)) << "step " << s;
  }
  const dynamics::VelocityScratch& v1 = d1.workspace->velocity;
  const dynamics::VelocityScratch& v2 = d2.workspace->velocity;
  EXPECT_GT(v2.shared_steps, 2500);  // the columns were offered to the two threads
  const long lagged1 = v1.group_solver.lagged.lagged_solves;
  EXPECT_GT(lagged1, 2 * 2500);  // both columns, most steps
  EXPECT_EQ(v2.group_solver.lagged.lagged_solves + v2.worker_solver.lagged.lagged_solves, lagged1);
  // and the worker solved some of them (measured 1059-2215 of 5954 on a loaded machine)
  EXPECT_GT(v2.worker_solver.lagged.lagged_solves, 0);
}

// stage 6's record of one tick, compared bit for bit: the events in order, the tool's impulse,
// every contact's impulse and every body's state; false with the first difference in *why
bool SameImpulses(const Data& d1, const Data& d2, std::string* why) {
  if (d1.nimpulse != d2.nimpulse) {
    *why = "impulse count " + std::to_string(d1.nimpulse) + " != " + std::to_string(d2.nimpulse);
    return false;
  }
  for (int k = 0; k < d1.nimpulse; ++k) {
    const ImpulseEvent &a = d1.impulses[k], &b = d2.impulses[k];
    if (a.group != b.group || a.contacts != b.contacts || a.index != b.index ||
        a.total != b.total || a.tool != b.tool ||
        std::memcmp(&a.kinetic_energy_before_J, &b.kinetic_energy_before_J, 8) != 0 ||
        std::memcmp(&a.kinetic_energy_after_J, &b.kinetic_energy_after_J, 8) != 0 ||
        std::memcmp(&a.impulse_norm_Ns, &b.impulse_norm_Ns, 8) != 0 ||
        !SameVec3Bits(a.tool_impulse_Ns_W, b.tool_impulse_Ns_W)) {
      *why = "event " + std::to_string(k);
      return false;
    }
  }
  if (!SameVec3Bits(d1.tool_impulse_Ns_W, d2.tool_impulse_Ns_W)) {
    *why = "tool impulse";
    return false;
  }
  for (int c = 0; c < d1.ncontact; ++c) {
    if (std::memcmp(&d1.contacts[c].impulse_Ns, &d2.contacts[c].impulse_Ns, 8) != 0) {
      *why = "contact " + std::to_string(c);
      return false;
    }
  }
  for (std::size_t i = 0; i < d1.bodies.size(); ++i) {
    const BodyState &a = d1.bodies[i], &b = d2.bodies[i];
    if (!SameVec3Bits(a.x_W, b.x_W) || !SameVec3Bits(a.v_W, b.v_W) || !SameVec3Bits(a.w_W, b.w_W) ||
        d1.window[i].onset_step != d2.window[i].onset_step ||
        d1.window[i].impulses_done != d2.window[i].impulses_done ||
        d1.window[i].interior != d2.window[i].interior) {
      *why = "body " + std::to_string(i);
      return false;
    }
  }
  return true;
}

// a 6 x 6 x 8 pile landing (boxes 1 mm apart): its 36 columns' collision windows open within a
// few ticks of each other, so in many ticks several groups have an impulse of their trains due,
// and with two threads the worker solves some of them with its own solver. Every tick's impulses
// (the events in group order, the tool's impulse, each contact's impulse) and the body states
// and windows are those of one thread, bit for bit. On a loaded machine the system may not run
// the worker in time for any shared group of the first 400 steps; the pile is then stepped on
// (its windows keep opening as the columns settle and touch) until the worker has solved some.
TEST(WorkerTest, ImpulsesSharedByTwoThreadsAreThoseOfOne) {
  OneAndTwoThreads t(test::WriteTempFile("pile_impulses.xml", test::PileXml(6, 6, 8, 0.051, 0.45)));
  const Model &m1 = t.m1, &m2 = t.m2;
  Data &d1 = t.d1, &d2 = t.d2;
  ASSERT_EQ(m1.render.renderer, RendererKind::kTrain);  // the default: trains of impulses
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  const contact::ImpulseScratch& shared = d2.workspace->impulse;
  long impulses = 0;
  int most_in_a_tick = 0;
  for (int s = 0; s < 400 || (shared.solved_on_worker == 0 && s < 4000); ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    std::string why;
    ASSERT_TRUE(SameImpulses(d1, d2, &why)) << "step " << s << ": " << why;
    impulses += d1.nimpulse;
    most_in_a_tick = std::max(most_in_a_tick, d1.nimpulse);
  }
  EXPECT_GT(impulses, 500);       // the trains ran (measured: 1771 over 400 steps)
  EXPECT_GE(most_in_a_tick, 10);  // many groups at once (measured: 37, the 36 columns and the tool)
  EXPECT_GT(shared.shared_steps, 10);  // and they were offered to both threads
  EXPECT_GT(shared.solved_on_worker, 0);
  EXPECT_EQ(d1.workspace->impulse.shared_steps, 0);  // never with one thread
}

// the same landing with the worker's lane cut to 24 rows, smaller than a landed column's 32 (the
// shipped lane has 4096): the groups it takes that are larger are left to the tick's thread, and
// the results are still those of one thread, bit for bit (measured: 289 groups solved on the
// worker, 1019 left)
TEST(WorkerTest, ImpulseGroupsTooLargeForTheWorkersLaneAreSolvedByTheTicksThread) {
  OneAndTwoThreads t(
      test::WriteTempFile("pile_impulses_lane.xml", test::PileXml(6, 6, 8, 0.051, 0.45)));
  const Model &m1 = t.m1, &m2 = t.m2;
  Data &d1 = t.d1, &d2 = t.d2;
  contact::ImpulseScratch& shared = d2.workspace->impulse;
  constexpr int kRows = 24;
  shared.Reserve(m2, kRows);
  ASSERT_EQ(static_cast<int>(shared.worker_lane.rows.size()), kRows);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  for (int s = 0;
       s < 400 || ((shared.solved_on_worker == 0 || shared.left_by_worker == 0) && s < 4000); ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    std::string why;
    ASSERT_TRUE(SameImpulses(d1, d2, &why)) << "step " << s << ": " << why;
  }
  EXPECT_GT(shared.left_by_worker, 0);    // the worker met groups too large for it
  EXPECT_GT(shared.solved_on_worker, 0);  // and solved the others
}

// the 100-box pile kicked (every body given a seeded random velocity, as in KickedPileTest): its
// groups of 300-600 rows go to the interior-point method, and their next impulses go there at
// once (the window's hint, read by whichever thread solves the group). The results are those of
// one thread, bit for bit. Returns the ticks with an impulse while the hint was set.
int KickedPileOnOneAndTwoThreads(int settle, int steps) {
  OneAndTwoThreads t(std::string(RIGIDTOUCH_SCENES) + "/pile.xml");
  const Model &m1 = t.m1, &m2 = t.m2;
  Data &d1 = t.d1, &d2 = t.d2;
  TickInput in;
  for (int s = 0; s < settle; ++s) {
    Tick(m1, d1, in);
    Tick(m2, d2, in);
  }
  std::mt19937_64 rng(5);
  std::normal_distribution<double> v(0.0, 0.3 / std::sqrt(3.0)), w(0.0, 10.0 / std::sqrt(3.0));
  for (std::size_t i = 0; i < d1.bodies.size(); ++i) {
    const Vec3 dv = test::Draw3(v, rng), dw = test::Draw3(w, rng);
    d1.bodies[i].v_W += dv;
    d2.bodies[i].v_W += dv;
    d1.bodies[i].w_W += dw;
    d2.bodies[i].w_W += dw;
  }
  const contact::ImpulseScratch& shared = d2.workspace->impulse;
  int hinted_ticks = 0;
  for (int s = 0; s < steps || (shared.solved_on_worker == 0 && s < 1500); ++s) {
    bool hint = false;
    for (const WindowState& window : d1.window) hint = hint || window.interior;
    Tick(m1, d1, in);
    Tick(m2, d2, in);
    std::string why;
    EXPECT_TRUE(SameImpulses(d1, d2, &why)) << "step " << s << ": " << why;
    if (!why.empty()) break;
    if (hint && d1.nimpulse > 0) ++hinted_ticks;
  }
  EXPECT_GT(shared.solved_on_worker, 0);
  return hinted_ticks;
}

// 0.3 s after the kick: a release-build test (label slow-parallel)
TEST(WorkerTest, SlowKickedPileWithTheInteriorPointHintIsTheSameOnTwoThreads) {
  EXPECT_GT(KickedPileOnOneAndTwoThreads(500, 300), 10);  // the hint was in use (measured: 224)
}

// its fast counterpart, run under the sanitizers too: the first 0.08 s after the kick
// (measured: 67 ticks with the hint in use)
TEST(WorkerTest, KickedPileWithTheInteriorPointHintIsTheSameOnTwoThreadsAtFirst) {
  EXPECT_GT(KickedPileOnOneAndTwoThreads(300, 80), 20);
}

// an allocation guard that lives on the worker thread between two of its jobs
alignas(test::LimitMalloc) unsigned char worker_guard[sizeof(test::LimitMalloc)];
void StartWorkerGuard(void*) {
  new (worker_guard) test::LimitMalloc;
}
void StopWorkerGuard(void* allocations) {
  auto* guard = std::launder(reinterpret_cast<test::LimitMalloc*>(worker_guard));
  *static_cast<long*>(allocations) = guard->allocations();
  guard->~LimitMalloc();
}
void Allocate(void*) {
  test::ProbeAllocation();
}

// runs job(context) on the worker thread itself
void OnWorker(Worker& worker, Worker::Job job, void* context) {
  worker.Post(job, context);
  worker.Wait();
}

// with two threads neither the tick's thread nor the worker allocates while a 100-box pile
// (its narrow phase, group solves and impulses shared with the worker) runs 2000 ticks; the
// worker's guard sees an allocation made by a job, so that it would see one in the tick
TEST(WorkerTest, NeitherThreadAllocatesInTheTick) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  const std::string path =
      test::WriteTempFile("pile_alloc.xml", test::PileXml(5, 5, 4, 0.051, 0.21));
  LoadOptions o;
  o.threads = 2;
  const Model m = LoadModel(path, o);
  Data d = MakeData(m);
  Worker& worker = *d.workspace->worker;
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  long probe = -1;
  OnWorker(worker, &StartWorkerGuard, nullptr);
  OnWorker(worker, &Allocate, nullptr);
  OnWorker(worker, &StopWorkerGuard, &probe);
  ASSERT_EQ(probe, 1);
  for (int s = 0; s < 10; ++s) Tick(m, d, in);  // warm-up
  long on_worker = -1;
  const long shared_before = d.workspace->velocity.shared_steps;
  const long impulses_shared_before = d.workspace->impulse.shared_steps;
  OnWorker(worker, &StartWorkerGuard, nullptr);
  {
    test::LimitMalloc guard;
    for (int s = 0; s < 2000; ++s) Tick(m, d, in);
    EXPECT_EQ(guard.allocations(), 0);
  }
  OnWorker(worker, &StopWorkerGuard, &on_worker);
  EXPECT_EQ(on_worker, 0);
  EXPECT_GT(d.ncontact, 300);                                    // the pile was in contact
  EXPECT_GT(d.workspace->velocity.shared_steps, shared_before);  // and its groups were split
  // as were its impulses while it landed
  EXPECT_GT(d.workspace->impulse.shared_steps, impulses_shared_before);
}

// ThreadSanitizer's case for trees (scripts/test.sh runs this file under it): a 4 x 4 x 3 pile
// beside a hinged lid with a stop that the tool and two boxes fall onto. The free-body groups are
// shared between the threads while the lid's group is solved on the tick's thread after them;
// every tick's bodies and tree state with two threads are the one-thread state, bit for bit
TEST(WorkerTest, TwoThreadsWithATreeGiveTheStateOfOne) {
  std::string xml = test::PileXml(4, 4, 3, 0.051, 0.5);
  const std::string lid =
      "<body name=\"lid\" pos=\"0.4 0 0.2\"><joint name=\"hinge\" type=\"hinge\" axis=\"1 0 0\""
      " limited=\"true\" range=\"-20 20\"/>"
      "<geom type=\"box\" size=\"0.1 0.1 0.01\" pos=\"0 0.05 0\" mass=\"1\"/></body>"
      "<body name=\"drop_0\" pos=\"0.38 0.05 0.3\"><freejoint/>"
      "<geom type=\"box\" size=\"0.02 0.02 0.02\" mass=\"0.1\"/></body>"
      "<body name=\"drop_1\" pos=\"0.43 0.1 0.35\"><freejoint/>"
      "<geom type=\"box\" size=\"0.02 0.02 0.02\" mass=\"0.1\"/></body>";
  xml.insert(xml.find("</worldbody>"), lid);
  OneAndTwoThreads t(test::WriteTempFile("pile_lid_threads.xml", xml));
  ASSERT_EQ(t.m1.trees.size(), 1u);
  const TickInput in;
  int lid_groups = 0;
  for (int step = 0; step < 600; ++step) {
    Tick(t.m1, t.d1, in);
    Tick(t.m2, t.d2, in);
    const contact::Groups& g = t.d2.workspace->contact.groups;
    lid_groups += g.body_start[t.d2.ngroup + 1] > g.body_start[t.d2.ngroup];
    for (std::size_t i = 0; i < t.d1.bodies.size(); ++i) {
      ASSERT_EQ(std::memcmp(&t.d1.bodies[i], &t.d2.bodies[i], sizeof(BodyState)), 0)
          << "step " << step << " body " << i;
    }
    ASSERT_EQ(t.d1.trees[0]->qpos, t.d2.trees[0]->qpos) << "step " << step;
    ASSERT_EQ(t.d1.trees[0]->qvel, t.d2.trees[0]->qvel) << "step " << step;
  }
  EXPECT_GT(lid_groups, 100);  // the lid shared a group with falling bodies
  EXPECT_GT(t.d2.workspace->velocity.shared_steps, 0);  // the worker took free-body groups
}

// the pile beside a tree (a free root capsule, two hinged capsule legs) landing on the floor:
// link-static rows on the tick's thread while the worker takes free-body groups; bit for bit
TEST(WorkerTest, TwoThreadsWithATreeOnTheFloorGiveTheStateOfOne) {
  std::string xml = test::PileXml(4, 4, 3, 0.051, 0.5);
  std::string tree =
      "<body name=\"torso\" pos=\"0.5 0 0.52\"><freejoint/>"
      "<geom type=\"capsule\" fromto=\"0 0 -0.1 0 0 0.1\" size=\"0.05\" mass=\"4\"/>";
  for (const char* y : {"-0.06", "0.06"}) {
    tree += std::string("<body pos=\"0 ") + y +
            " -0.15\"><joint type=\"hinge\" axis=\"0 1 0\" damping=\"0.5\"/>"
            "<geom type=\"capsule\" fromto=\"0 0 0 0 0 -0.3\" size=\"0.03\" mass=\"1\"/>"
            "</body>";
  }
  xml.insert(xml.find("</worldbody>"), tree + "</body>");
  OneAndTwoThreads t(test::WriteTempFile("pile_tree_floor_threads.xml", xml));
  ASSERT_EQ(t.m1.trees.size(), 1u);
  const TickInput in;
  int floor_rows = 0;
  for (int step = 0; step < 600; ++step) {
    Tick(t.m1, t.d1, in);
    Tick(t.m2, t.d2, in);
    for (int i = 0; i < t.d2.ncontact; ++i) {
      const Contact& c = t.d2.contacts[i];
      floor_rows += t.m2.geoms[c.geom_a].tree >= 0 && t.m2.geoms[c.geom_b].body < 0 &&
                    t.m2.geoms[c.geom_b].tree < 0;
    }
    for (std::size_t i = 0; i < t.d1.bodies.size(); ++i) {
      ASSERT_EQ(std::memcmp(&t.d1.bodies[i], &t.d2.bodies[i], sizeof(BodyState)), 0)
          << "step " << step << " body " << i;
    }
    ASSERT_EQ(t.d1.trees[0]->qpos, t.d2.trees[0]->qpos) << "step " << step;
    ASSERT_EQ(t.d1.trees[0]->qvel, t.d2.trees[0]->qvel) << "step " << step;
  }
  EXPECT_GT(floor_rows, 100);                           // the tree stood or lay on the floor
  EXPECT_GT(t.d2.workspace->velocity.shared_steps, 0);  // the worker took free-body groups
  EXPECT_GT(t.d2.trees[0]->qpos[2], 0.0);               // above the floor
}

}  // namespace
}  // namespace rigidtouch::parallel
