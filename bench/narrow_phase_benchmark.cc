// Times the hand-written narrow phase (src/geometry/narrow_phase.h) per call on fixed poses, and
// one narrow-phase pass over the 100-box pile next to MuJoCo's mj_kinematics + mj_collision on
// the same pile. A quick measurement for the design record, not a unit test.
//
// Run: narrow_phase_benchmark [--quick]   (--quick: 10x fewer timed calls, for a smoke test)
// Build: compile with src/ and include/ on the include path, link rigidtouch (or
// src/geometry/narrow_phase.cc) and mujoco.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "geometry/narrow_phase.h"

namespace {

using rigidtouch::GeomType;
using rigidtouch::Mat3;
using rigidtouch::Vec3;
using rigidtouch::geometry::Collide;
using rigidtouch::geometry::ContactPoint;
using rigidtouch::geometry::GeomPose;
using rigidtouch::geometry::kMaxPairContacts;
using SteadyClock = std::chrono::steady_clock;

Mat3 Rot(const Vec3& axis, double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

// one pair of geoms at fixed poses
struct Case {
  const char* name;
  GeomType t1;
  Vec3 size1;
  GeomPose pose1;
  GeomType t2;
  Vec3 size2;
  GeomPose pose2;
};

// median over batches of the time per call [ns]; also returns the points of one call
double TimeCase(const Case& c, int calls, int* points) {
  ContactPoint out[kMaxPairContacts];
  std::vector<double> batches;
  volatile int sink = 0;
  for (int batch = 0; batch < 11; ++batch) {
    const auto start = SteadyClock::now();
    int total = 0;
    for (int i = 0; i < calls; ++i) {
      total += Collide(c.t1, c.size1, c.pose1, c.t2, c.size2, c.pose2, out, kMaxPairContacts);
    }
    const auto stop = SteadyClock::now();
    sink = sink + total;
    batches.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / calls);
  }
  *points = Collide(c.t1, c.size1, c.pose1, c.t2, c.size2, c.pose2, out, kMaxPairContacts);
  std::nth_element(batches.begin(), batches.begin() + 5, batches.end());
  return batches[5];
}

// the 100-box pile: 5 x 5 x 4 boxes of half-size 25 mm on a plane, each layer 10 um into the one
// below (a resting stack's penetration), 1 mm apart sideways, slightly yawed and tilted at random
// (seeded): 25 box-plane and 75 box-box face contacts, about 400 points
struct Pile {
  static constexpr int kBoxes = 100;
  static constexpr double kHalf_m = 0.025;
  GeomPose boxes[kBoxes];
  std::vector<std::pair<int, int>> pairs;  // box pairs whose bounding spheres overlap
};

Pile MakeNarrowPile() {
  Pile pile;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  const double pitch_xy = 2 * Pile::kHalf_m + 1e-3, pitch_z = 2 * Pile::kHalf_m - 1e-5;
  int n = 0;
  for (int z = 0; z < 4; ++z) {
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 5; ++x) {
        pile.boxes[n].p_W =
            Vec3(-0.1 + pitch_xy * x, -0.1 + pitch_xy * y, Pile::kHalf_m - 1e-5 + pitch_z * z);
        // yaw up to 10 mrad; tilt up to 0.1 mrad keeps all 4 bottom corners below the face
        pile.boxes[n].R_WG = Rot(Vec3::UnitZ(), 1e-2 * jitter(rng)) *
                             Rot(Vec3(jitter(rng), jitter(rng), 0), 1e-4 * jitter(rng));
        ++n;
      }
    }
  }
  const double reach = 2 * std::sqrt(3.0) * Pile::kHalf_m;
  for (int i = 0; i < Pile::kBoxes; ++i) {
    for (int j = i + 1; j < Pile::kBoxes; ++j) {
      if ((pile.boxes[i].p_W - pile.boxes[j].p_W).norm() < reach) pile.pairs.emplace_back(i, j);
    }
  }
  return pile;
}

// one narrow-phase pass: every box against the plane, every candidate box pair [ns per pass]
double TimePile(const Pile& pile, int passes, int* contacts) {
  static ContactPoint out[kMaxPairContacts];
  const Vec3 half = Vec3::Constant(Pile::kHalf_m);
  const GeomPose plane{Vec3::Zero(), Mat3::Identity()};
  std::vector<double> batches;
  for (int batch = 0; batch < 11; ++batch) {
    int total = 0;
    const auto start = SteadyClock::now();
    for (int pass = 0; pass < passes; ++pass) {
      total = 0;
      for (int i = 0; i < Pile::kBoxes; ++i) {
        total += Collide(GeomType::kBox, half, pile.boxes[i], GeomType::kPlane, half, plane, out,
                         kMaxPairContacts);
      }
      for (const auto& [i, j] : pile.pairs) {
        total += Collide(GeomType::kBox, half, pile.boxes[i], GeomType::kBox, half, pile.boxes[j],
                         out, kMaxPairContacts);
      }
    }
    const auto stop = SteadyClock::now();
    *contacts = total;
    batches.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / passes);
  }
  std::nth_element(batches.begin(), batches.begin() + 5, batches.end());
  return batches[5];
}

// MuJoCo on the same pile: mj_kinematics + mj_collision per pass [ns]
double TimeMujocoPile(const Pile& pile, int passes, int* contacts) {
  std::string xml =
      "<mujoco><size nconmax=\"2000\"/><worldbody><geom type=\"plane\" size=\"1 1 0.1\"/>";
  for (int i = 0; i < Pile::kBoxes; ++i) {
    xml += "<body><freejoint/><geom type=\"box\" size=\"0.025 0.025 0.025\"/></body>";
  }
  xml += "</worldbody></mujoco>";
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  mj_makeEmptyFileVFS(vfs.get(), "pile.xml", static_cast<int>(xml.size()));
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "pile.xml")], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML("pile.xml", vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (m == nullptr) {
    std::fprintf(stderr, "MuJoCo: %s\n", error);
    return -1.0;
  }
  mjData* d = mj_makeData(m);
  for (int i = 0; i < Pile::kBoxes; ++i) {
    mjtNum* q = d->qpos + 7 * i;
    const rigidtouch::Quat quat(pile.boxes[i].R_WG);
    for (int k = 0; k < 3; ++k) q[k] = pile.boxes[i].p_W[k];
    q[3] = quat.w();
    q[4] = quat.x();
    q[5] = quat.y();
    q[6] = quat.z();
  }
  std::vector<double> batches;
  for (int batch = 0; batch < 11; ++batch) {
    const auto start = SteadyClock::now();
    for (int pass = 0; pass < passes; ++pass) {
      mj_kinematics(m, d);
      mj_collision(m, d);
    }
    const auto stop = SteadyClock::now();
    batches.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / passes);
  }
  *contacts = d->ncon;
  mj_deleteData(d);
  mj_deleteModel(m);
  std::nth_element(batches.begin(), batches.begin() + 5, batches.end());
  return batches[5];
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int calls = quick ? 20000 : 200000;
  const Vec3 cube = Vec3::Constant(0.025);
  const Mat3 I = Mat3::Identity();
  const double deg = std::numbers::pi / 180.0;
  const Mat3 tilt = Rot(Vec3(1, 0.3, 0), 0.3);
  const Case cases[] = {
      {"box-box face, resting (4 points)",
       GeomType::kBox,
       cube,
       {tilt * Vec3(0.003, -0.002, 0.05 - 1e-5), tilt},
       GeomType::kBox,
       cube,
       {Vec3::Zero(), tilt}},
      {"box-box face, 45 deg yaw (octagon -> 4)",
       GeomType::kBox,
       cube,
       {Vec3(0, 0, 0.05 - 1e-4), Rot(Vec3::UnitZ(), 45 * deg)},
       GeomType::kBox,
       cube,
       {Vec3::Zero(), I}},
      {"box-box edge-edge (1 point)",
       GeomType::kBox,
       cube,
       {Vec3(0, 0, 0.05 * std::sqrt(2.0) - 1e-4), Rot(Vec3::UnitY(), 45 * deg)},
       GeomType::kBox,
       cube,
       {Vec3::Zero(), Rot(Vec3::UnitX(), 45 * deg)}},
      {"box-box separated, last axis",
       GeomType::kBox,
       cube,
       {Vec3(0, 0, 0.05 * std::sqrt(2.0) + 1e-4), Rot(Vec3::UnitY(), 45 * deg)},
       GeomType::kBox,
       cube,
       {Vec3::Zero(), Rot(Vec3::UnitX(), 45 * deg)}},
      {"box-plane, resting (4 points)",
       GeomType::kBox,
       cube,
       {Vec3(0, 0, 0.025 - 1e-5), I},
       GeomType::kPlane,
       cube,
       {Vec3::Zero(), I}},
      {"box-plane, tilted (1 point)",
       GeomType::kBox,
       cube,
       {Vec3(0, 0, 0.04), Rot(Vec3(1, 1, 0), 40 * deg)},
       GeomType::kPlane,
       cube,
       {Vec3::Zero(), I}},
      {"sphere-box (1 point)",
       GeomType::kSphere,
       cube,
       {Vec3(0.01, 0.0, 0.045), I},
       GeomType::kBox,
       cube,
       {Vec3::Zero(), tilt}},
      {"sphere-plane (1 point)",
       GeomType::kSphere,
       cube,
       {Vec3(0, 0, 0.02), I},
       GeomType::kPlane,
       cube,
       {Vec3::Zero(), I}},
  };
  std::printf("%-42s %8s %10s\n", "pair", "points", "ns/call");
  for (const Case& c : cases) {
    int points = 0;
    const double ns = TimeCase(c, calls, &points);
    std::printf("%-42s %8d %10.1f\n", c.name, points, ns);
  }
  const Pile pile = MakeNarrowPile();
  const int passes = quick ? 200 : 2000;
  int ours = 0, theirs = 0;
  const double ours_ns = TimePile(pile, passes, &ours);
  const double mujoco_ns = TimeMujocoPile(pile, passes / 4, &theirs);
  std::printf(
      "100-box pile: narrow phase over 100 box-plane + %zu box-box candidate pairs: %.1f us per "
      "pass, %d contacts\n",
      pile.pairs.size(), ours_ns / 1000.0, ours);
  std::printf("100-box pile: MuJoCo mj_kinematics + mj_collision: %.1f us per pass, %d contacts\n",
              mujoco_ns / 1000.0, theirs);
  return 0;
}
