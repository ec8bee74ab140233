// rigidtouch public API: load a scene, make its data, advance it one haptic tick at a time.
//
//   rigidtouch::LoadOptions options;
//   rigidtouch::Model model = rigidtouch::LoadModel("scene.xml", options);
//   rigidtouch::Data data = rigidtouch::MakeData(model);
//   for (...) { DeviceCommand out = rigidtouch::Tick(model, data, input); }
#pragma once

#include <optional>
#include <string>

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"
#include "rigidtouch/trace.h"
#include "rigidtouch/types.h"

namespace rigidtouch {

/// rigidtouch's own parameters, kept apart from the scene file: flag > config > default.
struct LoadOptions {
  std::string tool_name = "tool";    // body that is the virtual tool
  std::optional<double> timestep_s;  // default: the MJCF option timestep
  ContactParams contact;
  RenderParams render;
  DeviceParams device;
  int max_contacts = 0;      // 0: what the scene can produce; less than that is refused
  int max_group_bodies = 0;  // 0: every body
  int threads = 1;  // 1, or 2: a worker thread shares collision, the contacts' classification
                    // and forces, and the group solves (the results are the same bit for bit)
};

/// Loads an MJCF scene compiled by MuJoCo. Throws Error naming the file (and MuJoCo's line) on
/// malformed XML, the geom on an unsupported type, the tool name if no body has it, and any
/// parameter outside its valid range.
Model LoadModel(const std::string& mjcf_path, const LoadOptions& options);

/// Validates the parameters of `model` and derives its impulse schedule (Eq. 6, Eq. 7). Call after
/// changing model.render, model.contact or model.device. Throws Error naming the parameter.
void Configure(Model& model);

/// Allocates all state of `model`, at its initial state.
Data MakeData(const Model& model);

/// Puts `data` back to the initial state; keeps its buffers.
void ResetData(const Model& model, Data& data);

/// Whether `data` was made by MakeData for this model: one loaded from the same file by the same
/// LoadModel call (or a copy of it, however configured since), with the sizes MakeData used.
/// Tick, ResetData and KineticEnergy assume it and do not check (a Data of another scene would
/// be read and written past its buffers); the Python module checks it and raises.
bool DataFitsModel(const Model& model, const Data& data);

/// Input of one tick.
struct TickInput {
  DeviceState device;  // ignored when model.device.coupling is kNone
  Wrench tool_wrench;  // user wrench on the tool's centre of mass (kNone only)
};

/// Advances the world by one step h and returns the device command (docs/architecture.md).
/// Never allocates, throws or blocks; problems are counted in data.warnings.
DeviceCommand Tick(const Model& model, Data& data, const TickInput& input);

/// Total kinetic energy of the dynamic bodies [J].
double KineticEnergy(const Model& model, const Data& data);

/// A trace sample of the last tick (tool state, forces, impulses).
TraceSample MakeTraceSample(const Model& model, const Data& data, const DeviceCommand& command);

}  // namespace rigidtouch
