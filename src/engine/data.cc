// Data lifecycle and per-tick reports.
#include <algorithm>
#include <memory>

#include "dynamics/kinematics.h"
#include "dynamics/rigid_body.h"
#include "dynamics/tree.h"
#include "dynamics/tree_stage.h"
#include "engine/workspace.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
void WorkspaceDeleter::operator()(Workspace* w) const {
  delete w;
}

void TreeDataDeleter::operator()(dynamics::TreeData* d) const {
  delete d;
}

const char* JointKindName(JointKind kind) {
  switch (kind) {
    case JointKind::kFree:
      return "free";
    case JointKind::kBall:
      return "ball";
    case JointKind::kSlide:
      return "slide";
    case JointKind::kHinge:
      break;
  }
  return "hinge";
}

const char* WarningName(Warning w) {
  switch (w) {
    case Warning::kContactFull:
      return "contact_full";
    case Warning::kGroupTooLarge:
      return "group_too_large";
    case Warning::kSolverFailed:
      return "solver_failed";
    case Warning::kBadDeviceState:
      return "bad_device_state";
    case Warning::kNonFiniteState:
      return "non_finite_state";
    case Warning::kForceClipped:
      return "force_clipped";
    case Warning::kImpulseClipped:
      return "impulse_clipped";
    case Warning::kImplausibleDeviceState:
      return "implausible_device_state";
    case Warning::kCount:
      break;
  }
  return "unknown";
}

Data MakeData(const Model& model) {
  Data data;
  const int nbody = static_cast<int>(model.bodies.size());
  const int ncap = model.max_contacts;
  data.bodies.resize(nbody);
  data.R_WB.resize(nbody);
  data.contacts.resize(ncap);
  data.runs.resize(ncap);
  data.body_group.assign(nbody, -1);
  data.window.resize(nbody);
  data.impulses.resize(nbody + model.trees.size());
  data.workspace.reset(new Workspace);
  Workspace& ws = *data.workspace;
  ws.collision.Reserve(model);
  ws.contact.Reserve(nbody, ncap);
  ws.contact.groups.ReserveTrees(model);
  ws.contact.trees.Reserve(model);
  ws.velocity.Reserve(nbody, ncap, model.max_group_bodies, model.threads);
  ws.impulse.Reserve(model);
  ws.trees.Reserve(model);
  dynamics::MakeTreesData(model, data);
  ws.made_for = model.collision;
  if (model.threads == 2) {
    ws.collision.ReserveTwoThreads(model);
    ws.worker = std::make_unique<parallel::Worker>();
  }
  ResetData(model, data);
  return data;
}

bool DataFitsModel(const Model& model, const Data& data) {
  if (data.workspace == nullptr) return false;
  const std::weak_ptr<mjModel_>& made_for = data.workspace->made_for;
  // the same compiled scene: neither owner orders before the other (both empty for a model
  // built without one); another scene at the same address has another owner
  const bool same_scene =
      !made_for.owner_before(model.collision) && !model.collision.owner_before(made_for);
  const std::size_t nbody = model.bodies.size();
  const auto ncap = static_cast<std::size_t>(model.max_contacts);
  return same_scene && data.bodies.size() == nbody && data.window.size() == nbody &&
         data.contacts.size() == ncap && data.runs.size() == ncap &&
         data.workspace->collision.poses.size() == model.geoms.size() &&
         model.initial.size() == nbody && data.trees.size() == model.trees.size();
}

void ResetState(const Model& model, Data& data) {
  std::copy(model.initial.begin(), model.initial.end(), data.bodies.begin());
  dynamics::ComputeKinematics(data);
  data.ncontact = 0;
  data.nruns = 0;
  data.ngroup = 0;
  std::fill(data.body_group.begin(), data.body_group.end(), -1);
  std::fill(data.window.begin(), data.window.end(), WindowState{});
  data.tool_penalty_force_N_W.setZero();
  data.tool_coupling_force_N_W.setZero();
  data.tool_impulse_Ns_W.setZero();
  data.tool_penetration_m = 0.0;
  data.tool_normal_W = Vec3::UnitZ();
  data.tool_contacts = 0;
  data.nimpulse = 0;
  data.passivity = PassivityState{};
  data.event = EventState{};
  if (data.workspace) {
    data.workspace->collision.Reset(model);
    data.workspace->velocity.ForgetFactors();
    dynamics::ResetTrees(model, data, data.workspace->collision);
    data.workspace->contact.trees.Reset();
  }
}

void ResetData(const Model& model, Data& data) {
  ResetState(model, data);
  data.step = 0;
  data.time_s = 0.0;
  data.warnings.fill(WarningStat{});
}

double KineticEnergy(const Model& model, const Data& data) {
  double e = 0.0;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    e += dynamics::KineticEnergy(model.bodies[i], data.bodies[i]);
  }
  return e;
}

TraceSample MakeTraceSample(const Model& model, const Data& data, const DeviceCommand& command) {
  TraceSample s;
  s.step = data.step;
  s.time_s = data.time_s;
  const BodyState& tool = data.bodies[model.tool];
  s.tool_position_m = tool.x_W;
  s.tool_velocity_mps = tool.v_W;
  s.penalty_force_N = command.penalty_force_N;
  s.impulsive_force_N = command.impulsive_force_N;
  s.device_force_N = command.force_N;
  s.wall_normal = data.tool_normal_W;
  s.penetration_m = data.tool_penetration_m;
  s.tool_contacts = data.tool_contacts;
  s.clipped = command.clipped;
  s.passivity_dissipated_J = data.passivity.step_dissipated_J;
  for (int k = 0; k < data.nimpulse; ++k) {
    const ImpulseEvent& e = data.impulses[k];
    if (!e.tool) continue;
    ++s.impulses;
    s.kinetic_energy_before_J = e.kinetic_energy_before_J;
    s.kinetic_energy_after_J = e.kinetic_energy_after_J;
  }
  return s;
}

}  // namespace rigidtouch
