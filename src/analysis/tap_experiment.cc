#include "analysis/tap_experiment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "dynamics/tree.h"
#include "geometry/broadphase.h"
#include "io/materials.h"

namespace rigidtouch::analysis {
namespace {

// distance from the tool's centre of mass to its surface along -n: where the centre sits when
// the tool touches the wall
double ToolReach(const Model& model, const Vec3& n) {
  double reach = 0.0;
  for (const GeomModel& g : model.geoms) {
    if (g.body != model.tool) continue;
    const Vec3 c = g.pos_B;  // principal frame; the tool starts unrotated in every mode here
    double r = g.rbound_m;
    if (g.type == GeomType::kSphere) r = g.size.x();
    if (g.type == GeomType::kBox)
      r = (g.quat_B.toRotationMatrix().transpose() * n).cwiseAbs().dot(g.size);
    reach = std::max(reach, r - c.dot(n));
  }
  return reach;
}

std::string StaticSurfaces(const Model& model) {
  std::string names;
  for (const GeomModel& g : model.geoms) {
    if (g.body >= 0 || (g.type != GeomType::kPlane && g.type != GeomType::kBox)) continue;
    names += (names.empty() ? "'" : ", '") + g.name + "'";
  }
  return names.empty() ? "none" : names;
}

// the tool's distance to the wall plane when it first touched something in each tap: a tap that
// met another body first (or never touched) measured that body, not the wall
void CheckTheWallWasTapped(const TapRun& run, const std::string& scene_path) {
  const bool moving = run.wall.moving() && run.wall_trace.size() == run.trace.size();
  const Vec3& n = run.wall.normal;
  const double reach = ToolReach(run.model, n);
  const std::string wall = run.wall.geom.empty() ? "the wall" : "the wall '" + run.wall.geom + "'";
  int tap = -1;
  bool touched = true;
  for (const TraceSample& s : run.trace) {
    if (s.tap != tap) {
      if (!touched) break;
      tap = s.tap;
      touched = tap < 0;
    }
    if (touched || s.tool_contacts == 0) continue;
    touched = true;
    // a moving wall has no fixed plane: its first contact must be with the wall's geom
    if (moving) {
      if (!run.wall_trace[static_cast<std::size_t>(&s - run.trace.data())].touching_wall) {
        throw Error("scene file '" + scene_path + "': tap " + std::to_string(tap) +
                    " touched something other than " + wall +
                    " first (another body is in the way); choose the wall with --wall-geom NAME");
      }
      continue;
    }
    const double gap_m = (s.tool_position_m - run.wall.point_m).dot(n) - reach;
    if (gap_m > 1e-3) {
      std::ostringstream msg;
      msg << "scene file '" << scene_path << "': tap " << tap << " touched something "
          << gap_m * 1e3 << " mm before " << wall
          << " (another body is in the way); choose the wall with --wall-geom NAME or "
             "--wall-point X Y Z --wall-normal X Y Z";
      throw Error(msg.str());
    }
  }
  if (!touched) {
    throw Error("scene file '" + scene_path + "': tap " + std::to_string(tap) + " never touched " +
                wall + "; is it within reach of the tool's start?");
  }
}

// the point of link geom g (at the scene's initial pose) nearest the tool, with the outward
// normal there: a moving wall (a box's face nearest the tool; a sphere's or capsule's radial)
Wall MovingWall(const Model& model, const GeomModel& g, const std::string& where,
                const std::string& choose) {
  const Mat3 R = g.quat_B.toRotationMatrix();
  const Vec3 tool = model.initial[model.tool].x_W;
  const Vec3 q = R.transpose() * (tool - g.pos_B);  // the tool in the geom's frame
  Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
  if (g.type == GeomType::kPlane) {
    point = Vec3(q.x(), q.y(), 0.0);
  } else if (g.type == GeomType::kBox) {
    // the face the tool is farthest outside of (or, inside, nearest to)
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (std::abs(q[a]) - g.size[a] > std::abs(q[axis]) - g.size[axis]) axis = a;
    }
    const double side = q[axis] >= 0.0 ? 1.0 : -1.0;
    point = q.cwiseMax(-g.size).cwiseMin(g.size);
    point[axis] = side * g.size[axis];
    normal = side * Vec3::Unit(axis);
  } else if (g.type == GeomType::kSphere || g.type == GeomType::kCapsule) {
    const double half = g.type == GeomType::kCapsule ? g.size.y() : 0.0;
    const Vec3 centre(0.0, 0.0, std::clamp(q.z(), -half, half));
    if ((q - centre).norm() < 1e-9) {
      throw Error(where + ": the tool sits on the axis of geom '" + g.name +
                  "'; which side is its surface?" + choose);
    }
    normal = (q - centre).normalized();
    point = centre + g.size.x() * normal;
  } else {
    throw Error(where + ": geom '" + g.name + "' is not a plane, box, sphere or capsule" + choose);
  }
  Wall wall;
  wall.geom = g.name;
  wall.point_m = g.pos_B + R * point;
  wall.normal = R * normal;
  wall.tree = g.tree;
  wall.link = g.link;
  wall.geom_index = static_cast<int>(&g - model.geoms.data());
  // the hinge or slide nearest above the link: the one that moves it
  const ArticulatedTree& tree = model.trees[g.tree];
  for (int link = g.link; link >= 0 && wall.joint < 0; link = tree.link_parent[link]) {
    for (std::size_t j = 0; j < tree.joints.size(); ++j) {
      const JointModel& joint = tree.joints[j];
      if (joint.link == link &&
          (joint.type == JointKind::kHinge || joint.type == JointKind::kSlide)) {
        wall.joint = static_cast<int>(j);
        break;
      }
    }
  }
  return wall;
}

}  // namespace

Wall FindWall(const Model& model, const std::string& scene_path, const std::string& geom) {
  const std::string where = "scene file '" + scene_path + "'";
  const std::string choose =
      "; choose one with --wall-geom NAME (a static plane or box: " + StaticSurfaces(model) +
      ") or give --wall-point X Y Z and --wall-normal X Y Z";
  const GeomModel* found = nullptr;
  if (!geom.empty() || std::any_of(model.geoms.begin(), model.geoms.end(),
                                   [](const GeomModel& g) { return g.name == "wall"; })) {
    const std::string name = geom.empty() ? "wall" : geom;
    for (const GeomModel& g : model.geoms) {
      if (g.name == name) found = &g;
    }
    if (found == nullptr) throw Error(where + ": no geom named '" + name + "'" + choose);
  } else {
    int planes = 0;
    for (const GeomModel& g : model.geoms) {
      if (g.body < 0 && g.type == GeomType::kPlane) {
        found = &g;
        ++planes;
      }
    }
    if (planes != 1) {
      throw Error(where + ": which surface is the wall? there is no geom named 'wall' and " +
                  std::to_string(planes) + " static planes" + choose);
    }
  }
  if (found->body >= 0) {
    throw Error(where + ": geom '" + found->name + "' belongs to a moving body; the wall must be " +
                "static (a worldbody geom) or a link of a jointed body" + choose);
  }
  if (found->tree >= 0) return MovingWall(model, *found, where, choose);
  const Mat3 R = found->quat_B.toRotationMatrix();
  Wall wall;
  wall.geom = found->name;
  wall.normal = R.col(2);
  if (found->type == GeomType::kPlane) {
    wall.point_m = found->pos_B;
  } else if (found->type == GeomType::kBox) {
    wall.point_m = found->pos_B + found->size.z() * wall.normal;
  } else {
    throw Error(where + ": geom '" + found->name + "' is not a plane or a box" + choose);
  }
  return wall;
}

namespace {

// how far along the unit direction d from o the ray enters geom g at `pose`; negative if it misses
// the geom or starts inside it
double RayEntry(const GeomModel& g, const geometry::GeomPose& pose, const Vec3& o, const Vec3& d) {
  constexpr double kMiss = -1.0;
  if (g.type == GeomType::kPlane) {
    const Vec3 m = pose.R_WG.col(2);
    const double height = (o - pose.p_W).dot(m), along = d.dot(m);
    return height > 0.0 && along < 0.0 ? height / -along : kMiss;
  }
  if (g.type == GeomType::kBox) {
    // the slabs of the box's three axes, in its frame
    const Vec3 ob = pose.R_WG.transpose() * (o - pose.p_W), db = pose.R_WG.transpose() * d;
    double enter = -std::numeric_limits<double>::infinity();
    double leave = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (db[a] == 0.0) {
        if (std::abs(ob[a]) > g.size[a]) return kMiss;
        continue;
      }
      const double t1 = (-g.size[a] - ob[a]) / db[a], t2 = (g.size[a] - ob[a]) / db[a];
      enter = std::max(enter, std::min(t1, t2));
      leave = std::min(leave, std::max(t1, t2));
    }
    return enter <= leave && enter > 0.0 ? enter : kMiss;
  }
  // a sphere, and the bounding sphere of the other shapes
  const double r = g.type == GeomType::kSphere ? g.size.x() : g.rbound_m;
  const Vec3 c = o - pose.p_W;
  const double b = c.dot(d), outside = c.squaredNorm() - r * r;
  const double disc = b * b - outside;
  return outside > 0.0 && b < 0.0 && disc >= 0.0 ? -b - std::sqrt(disc) : kMiss;
}

}  // namespace

std::optional<Wall> SurfaceBelowTool(const Model& model, const Vec3& normal) {
  const Vec3 n = normal.normalized(), d = -n;
  const Vec3 o = model.initial[model.tool].x_W;
  std::vector<geometry::GeomPose> poses(model.geoms.size());
  geometry::GeomPoses(model, model.initial, poses);
  double nearest = std::numeric_limits<double>::infinity();
  int hit = -1;
  for (std::size_t i = 0; i < model.geoms.size(); ++i) {
    const GeomModel& g = model.geoms[i];
    if (g.body == model.tool) continue;
    const bool touchable = std::any_of(model.geoms.begin(), model.geoms.end(), [&](const auto& t) {
      return t.body == model.tool && geometry::CanCollide(t, g);
    });
    if (!touchable) continue;
    const double t = RayEntry(g, poses[i], o, d);
    if (t > 0.0 && t < nearest) {
      nearest = t;
      hit = static_cast<int>(i);
    }
  }
  if (hit < 0) return std::nullopt;
  Wall wall;
  wall.point_m = o + nearest * d;
  wall.normal = n;
  wall.geom = model.geoms[hit].name;
  return wall;
}

RenderParams WallRenderParams(int wall) {
  RenderParams r;
  r.restitution = 0.0;
  r.t_collision_s = 0.1;
  switch (wall) {
    case 0:
      r.renderer = RendererKind::kImpulse;
      break;
    case 1:
      r.renderer = RendererKind::kTrain;
      r.frequency_hz = 250.0;
      break;
    case 2:
      r.renderer = RendererKind::kTrain;
      r.frequency_hz = 50.0;
      break;
    default: {
      std::ostringstream msg;
      msg << "unknown wall " << wall << "; valid walls: 0 (single impulse), 1 (train 250 Hz), "
          << "2 (train 50 Hz)";
      throw Error(msg.str());
    }
  }
  return r;
}

void UseDeviceAndHandMass(Model& model, const device::DeviceModelParams& device,
                          const device::HandParams& hand) {
  BodyModel& tool = model.bodies[model.tool];
  const double mass = device::EffectiveMassKg(device, hand);
  tool.inertia_kgm2 *= mass / tool.mass_kg;
  tool.mass_kg = mass;
}

TapSetup PrepareTap(const TapExperimentConfig& config) {
  if (!(std::isfinite(config.rate_hz) && config.rate_hz >= 100.0 && config.rate_hz <= 20000.0)) {
    std::ostringstream msg;
    msg << "rate = " << config.rate_hz << " Hz is out of range: valid 100 to 20000 Hz";
    throw Error(msg.str());
  }
  if (!config.wall_normal.allFinite() || config.wall_normal.norm() < 1e-9) {
    throw Error("wall normal must be a finite non-zero vector");
  }
  TapSetup setup;
  const device::DeviceSpec spec = device::ParseDeviceSpec(config.device_preset);
  setup.device = spec.limits;
  if (config.max_force_N) setup.device.max_force_N = *config.max_force_N;
  const DeviceLimits& limits = setup.device;
  const double h = 1.0 / config.rate_hz;

  LoadOptions load = config.load;
  load.timestep_s = h;
  // a device with no stiffness limit (ideal, or a spec's 0) keeps the coupling's own
  const auto capped = [](double limit, double otherwise) {
    return limit > 0.0 ? limit : otherwise;
  };
  load.contact.stiffness_N_per_m = config.stiffness_N_per_m.value_or(
      device::DefaultWall(limits, h, load.contact.stiffness_N_per_m).stiffness_N_per_m);
  load.contact.damping_Ns_per_m = config.damping_Ns_per_m.value_or(
      device::DefaultDamping(limits, h, load.contact.stiffness_N_per_m));
  load.device.limits.max_force_N = limits.max_force_N;
  load.device.position_resolution_m = config.device_model.value_or(spec.model).encoder_resolution_m;
  if (load.device.coupling == Coupling::kNone) load.device.coupling = Coupling::kDirect;
  if (load.device.coupling == Coupling::kVirtual) {
    // the coupling is what the device renders: its limits bound the coupling, not the wall
    load.device.coupling_stiffness_N_per_m = config.coupling_stiffness_N_per_m.value_or(
        capped(limits.max_stiffness_N_per_m, load.device.coupling_stiffness_N_per_m));
    const double kc_h = load.device.coupling_stiffness_N_per_m * h;
    load.device.coupling_damping_Ns_per_m = config.coupling_damping_Ns_per_m.value_or(
        limits.max_damping_Ns_per_m > 0.0 ? std::min(kc_h, limits.max_damping_Ns_per_m) : kc_h);
  }
  device::DeviceModelParams dm = config.device_model.value_or(spec.model);
  dm.tick_rate_hz = config.rate_hz;
  // an acceleration material's force is this device's effective mass times its acceleration
  setup.material_note = io::RenderMaterialOnDevice(
      load.render, device::EffectiveMassKg(dm, config.hand), setup.device.name);
  Model model = LoadModel(config.scene_path, load);

  device::TapScript script = config.script;
  if (config.wall_point_m) {
    setup.wall.point_m = *config.wall_point_m;
    setup.wall.normal = config.wall_normal.normalized();
  } else {
    setup.wall = FindWall(model, config.scene_path, config.wall_geom);
    if (config.aim_below_tool) {
      if (const std::optional<Wall> below = SurfaceBelowTool(model, setup.wall.normal)) {
        setup.wall = *below;
      }
    }
  }
  const Vec3 n = setup.wall.normal;
  script.surface_normal = n;
  script.surface_point_m = setup.wall.point_m + ToolReach(model, n) * n;
  setup.simulated = std::make_unique<device::SimulatedDevice>(limits, config.hand, dm, script);
  device::SimulatedDevice& dev = *setup.simulated;

  if (model.device.coupling == Coupling::kDirect) UseDeviceAndHandMass(model, dm, config.hand);
  const DeviceState start = dev.Read();
  const double scene_tool_m = model.initial[model.tool].x_W.norm();
  model.initial[model.tool].x_W = start.position_m;
  model.initial[model.tool].v_W.setZero();
  model.initial[model.tool].w_W.setZero();
  model.initial[model.tool].q_WB = Quat::Identity();
  if (config.widen_plausible_radius) {
    model.device.plausible_radius_m = std::max(
        model.device.plausible_radius_m, std::max(setup.wall.point_m.norm(), scene_tool_m) + 0.5);
  }
  Configure(model);

  setup.model = std::move(model);
  return setup;
}

namespace {

// one tick of a moving wall: its joint, the velocity of its point under the tool, and the
// impulse the tool's contacts with it gave the joint (J^T P at each contact point)
WallSample SampleMovingWall(const Model& model, const Data& data, const Wall& wall, double reach,
                            Eigen::MatrixXd& jac_trans, Eigen::MatrixXd& jac_rot) {
  WallSample w;
  const dynamics::TreeModel& tm = *model.trees[wall.tree].dynamics;
  const dynamics::TreeData& d = *data.trees[wall.tree];
  const int dof = wall.joint >= 0 ? model.trees[wall.tree].joints[wall.joint].dof_adr : -1;
  if (dof >= 0) {
    w.joint_position = d.qpos[model.trees[wall.tree].joints[wall.joint].qpos_adr];
    w.joint_velocity = d.qvel[dof];
  }
  const Vec3 under_tool = data.bodies[model.tool].x_W - reach * wall.normal;
  dynamics::TreePointJacobian(tm, d, wall.link, under_tool, jac_trans, jac_rot);
  w.surface_velocity_mps = jac_trans * d.qvel;
  const double h = model.timestep_s;
  for (int i = 0; i < data.ncontact; ++i) {
    const Contact& c = data.contacts[i];
    const bool a_is_wall = c.geom_a == wall.geom_index, b_is_wall = c.geom_b == wall.geom_index;
    const int other = a_is_wall ? c.body_b : c.body_a;
    if (!(a_is_wall || b_is_wall) || other != model.tool) continue;
    w.touching_wall = true;
    // the impulse on side a this tick (normal penalty and impulse along n, friction); the wall
    // takes its opposite when it is side b
    const Vec3 on_a = (c.normal_force_N * h + c.impulse_Ns) * c.n_W + h * c.friction_force_N_W;
    const Vec3 on_wall = a_is_wall ? on_a : Vec3(-on_a);
    if (dof >= 0) {
      dynamics::TreePointJacobian(tm, d, wall.link, c.p_W, jac_trans, jac_rot);
      w.joint_impulse += jac_trans.col(dof).dot(on_wall);
    }
  }
  return w;
}

// the moving wall's joint as compiled: its name, kind, damping, spring, and the tree's inertia
// about it at the initial state (the mass matrix's diagonal, armature included)
void DescribeJoint(const Model& model, const Wall& wall, TapRun& run) {
  if (!wall.moving() || wall.joint < 0) return;
  const ArticulatedTree& tree = model.trees[wall.tree];
  const JointModel& joint = tree.joints[wall.joint];
  const dynamics::TreeModel& tm = *tree.dynamics;
  run.joint_name = joint.name;
  run.joint_kind = joint.type;
  run.joint_damping = tm.joint(wall.joint).damping;
  run.joint_stiffness = tm.joint(wall.joint).stiffness;
  dynamics::TreeData d = dynamics::MakeTreeData(tm);
  for (int i = 0; i < tree.nq; ++i) d.qpos[i] = tree.initial_qpos[i];
  dynamics::TreeKinematics(tm, d);
  dynamics::TreeMassMatrix(tm, d);
  run.joint_inertia = d.M(joint.dof_adr, joint.dof_adr);
}

// per tap, the moving wall's joint (TapRun::joint_taps)
JointMotion MotionOverTap(const TapRun& run, std::size_t begin, std::size_t end) {
  JointMotion m;
  const std::vector<WallSample>& w = run.wall_trace;
  m.position_at_start = w[begin].joint_position;
  m.position_at_end = w[end - 1].joint_position;
  m.velocity_at_end = w[end - 1].joint_velocity;
  m.min_position = m.max_position = m.position_at_start;
  for (std::size_t k = begin; k < end; ++k) {
    m.min_position = std::min(m.min_position, w[k].joint_position);
    m.max_position = std::max(m.max_position, w[k].joint_position);
    m.peak_speed = std::max(m.peak_speed, std::abs(w[k].joint_velocity));
    m.impulse += w[k].joint_impulse;
  }
  return m;
}

}  // namespace

// ticks between two looks at the progress (a clock read costs about as much as a tick)
constexpr std::int64_t kProgressTicks = 256;

TapRun RunTapExperiment(const TapExperimentConfig& config) {
  TapSetup setup = PrepareTap(config);
  TapRun run;
  run.device = setup.device;
  Model& model = setup.model;
  device::SimulatedDevice& dev = *setup.simulated;
  Data data = MakeData(model);
  const Wall& wall = setup.wall;
  const double reach = ToolReach(model, wall.normal);
  Eigen::MatrixXd jac_trans, jac_rot;
  if (wall.moving()) {
    const int nv = model.trees[wall.tree].nv;
    jac_trans.resize(3, nv);
    jac_rot.resize(3, nv);
  }
  const std::int64_t max_ticks = std::llround((dev.duration_s() + 1.0) * config.rate_hz);
  run.trace.reserve(static_cast<std::size_t>(max_ticks));
  TickInput input;
  for (std::int64_t tick = 0; tick < max_ticks && !dev.finished(); ++tick) {
    if (config.progress != nullptr && tick % kProgressTicks == 0) {
      config.progress->ThrowIfStopped(config.progress_where, config.progress_kept);
      if (config.progress->Due()) {
        const double done = static_cast<double>(tick) / static_cast<double>(max_ticks);
        config.progress->Report(
            config.progress_from + (config.progress_to - config.progress_from) * done,
            config.progress_where);
      }
    }
    input.device = dev.Read();
    const DeviceCommand command = Tick(model, data, input);
    dev.Write(command);
    TraceSample s = MakeTraceSample(model, data, command);
    // the trace describes the tick as the device lived it: the true handle position at the start
    // of the tick, and the force held from here to the next sample (zero-order hold); tap and
    // hand force through the same hook as loop::RunHapticLoop
    s.step = tick;
    s.time_s = dev.time_s();
    dev.AnnotateTrace(s);
    s.tool_position_m = dev.true_position_m();
    s.tool_velocity_mps = dev.true_velocity_mps();
    s.device_force_N = dev.displayed_force_N();
    // the engine clips to the preset's limit before the device sees the command
    s.clipped = command.clipped || dev.last_command_clipped();
    if (s.clipped) {
      ++run.clipped_ticks;
      if (command.impulsive_force_N.squaredNorm() > 0.0) ++run.clipped_impulse_ticks;
    }
    run.trace.push_back(s);
    if (wall.moving()) {
      run.wall_trace.push_back(SampleMovingWall(model, data, wall, reach, jac_trans, jac_rot));
    }
    // the same per-period hook as loop::RunHapticLoop, so both paths advance the plant alike
    dev.EndPeriod(1.0 / config.rate_hz);
  }
  run.energy_to_user_J = dev.energy_to_user_J();
  run.warnings = data.warnings;

  // every renderer's taps over the same window (TapMetricsOptions: 100 ms, the longest collision
  // window), so that their spectral figures compare at one resolution
  // a moving wall's taps: the approach speed relative to its point under the tool
  std::vector<Vec3> surface_velocity_mps;
  for (const WallSample& w : run.wall_trace) surface_velocity_mps.push_back(w.surface_velocity_mps);
  DescribeJoint(model, wall, run);
  for (const auto& samples : SplitTaps(run.trace)) {
    TapMetricsOptions options;
    const auto begin = static_cast<std::size_t>(samples.data() - run.trace.data());
    if (wall.moving()) {
      options.surface_velocity_mps =
          std::span<const Vec3>(surface_velocity_mps).subspan(begin, samples.size());
      if (wall.joint >= 0)
        run.joint_taps.push_back(MotionOverTap(run, begin, begin + samples.size()));
    }
    run.taps.push_back(ComputeTapMetrics(samples, options));
  }
  run.model = std::move(model);
  run.wall = setup.wall;
  run.material_note = setup.material_note;
  CheckTheWallWasTapped(run, config.scene_path);
  return run;
}

}  // namespace rigidtouch::analysis
