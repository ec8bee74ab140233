// Contact and pair capacity bounded from the scene (issue 16).
#include "geometry/capacity.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <string>

#include "engine/workspace.h"
#include "limit_malloc.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::geometry {
namespace {

std::string Pile() {
  return std::string(RIGIDTOUCH_SCENES) + "/pile.xml";
}

// nx x ny x nz boxes of half-size 25 mm touching face to face on a floor, the tool sphere beside
std::string WriteGrid(int nx, int ny, int nz) {
  std::ostringstream xml;
  xml << "<mujoco><option timestep=\"0.001\"/><worldbody>"
         "<geom type=\"plane\" size=\"0 0 1\"/>";
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nz; ++k) {
        xml << "<body pos=\"" << 0.05 * i << " " << 0.05 * j << " " << 0.025 + 0.05 * k
            << "\"><freejoint/><geom type=\"box\" size=\"0.025 0.025 0.025\" mass=\"0.1\"/></body>";
      }
    }
  }
  xml << "<body name=\"tool\" pos=\"-1 0 0.005\"><freejoint/>"
         "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>";
  const std::string name =
      "grid" + std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) + ".xml";
  return test::WriteTempFile(name, xml.str());
}

// prints the bytes MakeData allocates for `m`, and of those the collision backend's mjData
// (MuJoCo sizes it from the scene's nconmax and njmax, not from rigidtouch's capacity); returns
// MakeData's bytes
double PrintMemory(const char* name, const Model& m, const SceneCapacity& cap) {
  const struct mallinfo2 before = mallinfo2();
  Data d = MakeData(m);
  const struct mallinfo2 after = mallinfo2();
  mjData* mj = mj_makeData(m.collision.get());
  const struct mallinfo2 with_mj = mallinfo2();
  mj_deleteData(mj);
  auto used = [](const struct mallinfo2& i) { return static_cast<double>(i.uordblks + i.hblkhd); };
  std::cout << name << ": " << cap.collidable_pairs << " collidable pairs, capacity " << cap.pairs
            << " pairs and " << cap.contacts << " contacts (exact bound " << cap.exact_contacts
            << "); MakeData allocated " << (used(after) - used(before)) / 1e6
            << " MB, of which MuJoCo's mjData " << (used(with_mj) - used(after)) / 1e6 << " MB\n";
  return used(after) - used(before);
}

TEST(CapacityTest, MaxPairPointsIsSymmetricAndMatchesTheNarrowPhases) {
  using T = GeomType;
  EXPECT_EQ(MaxPairPoints(T::kPlane, T::kPlane), 0);
  EXPECT_EQ(MaxPairPoints(T::kSphere, T::kPlane), 1);
  EXPECT_EQ(MaxPairPoints(T::kSphere, T::kBox), 1);
  EXPECT_EQ(MaxPairPoints(T::kBox, T::kBox), 4);
  EXPECT_EQ(MaxPairPoints(T::kPlane, T::kBox), 4);
  EXPECT_EQ(MaxPairPoints(T::kCapsule, T::kPlane), 2);
  EXPECT_EQ(MaxPairPoints(T::kCapsule, T::kBox), 2);
  EXPECT_EQ(MaxPairPoints(T::kSphere, T::kCapsule), 1);
  EXPECT_EQ(MaxPairPoints(T::kMesh, T::kPlane), 3);
  EXPECT_EQ(MaxPairPoints(T::kMesh, T::kMesh), 5);
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      EXPECT_EQ(MaxPairPoints(static_cast<T>(a), static_cast<T>(b)),
                MaxPairPoints(static_cast<T>(b), static_cast<T>(a)));
    }
  }
}

// the pile's 100 boxes and the tool: every pair of them and each with the floor
TEST(CapacityTest, PileIsBoundedByEveryCollidablePair) {
  const Model m = LoadModel(Pile(), {});
  const SceneCapacity cap = BoundCapacity(m);
  EXPECT_EQ(cap.collidable_pairs, 101 * 100 / 2 + 101);
  EXPECT_EQ(cap.exact_contacts, 99 * 100 / 2 * 4 + 100 * 1 + 100 * 4 + 1);
  EXPECT_LE(cap.pairs, cap.collidable_pairs);
  EXPECT_LE(cap.contacts, cap.exact_contacts);
  EXPECT_EQ(m.max_contacts, cap.contacts);
  Data d = MakeData(m);
  EXPECT_EQ(static_cast<long>(d.workspace->collision.broadphase.pairs.size()), cap.pairs);
}

// a large grid of boxes: the packing bound keeps the capacity linear in the number of boxes
TEST(CapacityTest, PackingBoundsALargeGridLinearly) {
  const Model m = LoadModel(WriteGrid(10, 10, 10), {});
  const SceneCapacity cap = BoundCapacity(m);
  EXPECT_TRUE(cap.packing);
  EXPECT_EQ(cap.collidable_pairs, 1001L * 1000 / 2 + 1001);
  EXPECT_LT(cap.pairs, 200L * 1001);
  EXPECT_LT(cap.contacts, 200L * 1001);
  // a box touching face to face has 26 neighbours whose boxes overlap its own
  EXPECT_GE(cap.pairs, 13L * 1000);
  PrintMemory("1000-box grid", m, cap);
}

// what MakeData allocates for the pile stays bounded: 20.0 MB when this bound was set (about
// 1.6 kB per contact of capacity, the collision backend's mjData 0.7 MB of it); a buffer sized by
// pairs times contacts, or the capacity growing back towards every collidable pair's points,
// would go past it
TEST(CapacityTest, PileMemory) {
  // mallinfo2 counts glibc's heap, which a sanitizer replaces (it then reports 0 bytes)
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  const Model m = LoadModel(Pile(), {});
  const SceneCapacity cap = BoundCapacity(m);
  const double bytes = PrintMemory("pile", m, cap);
  EXPECT_GT(bytes, 0.0);
  EXPECT_LT(bytes, 24e6);
  EXPECT_LT(bytes / static_cast<double>(cap.contacts), 2000.0);
}

// a user-set max_contacts below what the scene can produce is refused at load, naming the number
TEST(CapacityTest, TooSmallMaxContactsIsRefusedAtLoadNamingTheNumberNeeded) {
  LoadOptions options;
  options.max_contacts = 100;
  const long needed = BoundCapacity(LoadModel(Pile(), {})).contacts;
  try {
    LoadModel(Pile(), options);
    FAIL() << "loaded";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("max_contacts is 100"), std::string::npos) << what;
    EXPECT_NE(what.find("at least " + std::to_string(needed)), std::string::npos) << what;
  }
  options.max_contacts = static_cast<int>(needed);
  EXPECT_EQ(LoadModel(Pile(), options).max_contacts, needed);
}

}  // namespace
}  // namespace rigidtouch::geometry
