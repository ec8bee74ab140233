// The native part of the Python module `rigidtouch`: the engine's API in snake_case (load_model,
// configure, make_data, tick, reset_data, kinetic_energy), the simulated hand and device, the tap
// experiment through the `tap` subcommand's own flags, and the study toolkit. The pure-Python
// package (python/rigidtouch/) wraps it. Units are SI and in the names, as in the C++ API.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"
#include "analysis/tap_metrics.h"
#include "arrays.h"
#include "dynamics/tree.h"
#include "io/config.h"
#include "io/output_file.h"
#include "rigidtouch/command.h"
#include "rigidtouch/tap_run.h"
#include "study/analysis.h"
#include "study/log.h"
#include "study/protocol.h"
#include "study/simulate.h"
#include "study/stimulus.h"

namespace rigidtouch::cli {
// the CLI's subcommand registry (main.cc defines it for the executable); the subcommands linked
// into the module register here and are not used, except `tap` through RunTapFlags
std::vector<Command>& Commands() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace rigidtouch::cli

namespace rigidtouch::python {
namespace {

namespace st = rigidtouch::study;
using py::literals::operator""_a;

// a JSON value as Python objects, through the json module (exact: dump() round-trips doubles)
py::object ToPython(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

// a DeviceState from keyword-style fields; unknown keys are refused by name
DeviceState MakeDeviceState(const py::dict& fields) {
  DeviceState s;
  for (const auto& [key, value] : fields) {
    const std::string k = py::cast<std::string>(key);
    if (k == "position_m") {
      s.position_m = py::cast<Vec3>(value);
    } else if (k == "velocity_mps") {
      s.velocity_mps = py::cast<Vec3>(value);
    } else if (k == "angular_velocity_radps") {
      s.angular_velocity_radps = py::cast<Vec3>(value);
    } else if (k == "orientation_wxyz") {
      const Eigen::Vector4d q = py::cast<Eigen::Vector4d>(value);
      s.orientation = Quat(q[0], q[1], q[2], q[3]);
    } else if (k == "time_s") {
      s.time_s = py::cast<double>(value);
    } else if (k == "sequence") {
      s.sequence = py::cast<std::uint64_t>(value);
    } else if (k == "buttons") {
      s.buttons = py::cast<std::uint32_t>(value);
    } else if (k == "valid") {
      s.valid = py::cast<bool>(value);
    } else if (k == "fresh") {
      s.fresh = py::cast<bool>(value);
    } else {
      throw py::value_error("device state: unknown field '" + k +
                            "'; valid: position_m, velocity_mps, angular_velocity_radps, "
                            "orientation_wxyz, time_s, sequence, buttons, valid, fresh");
    }
  }
  return s;
}

bool IsCommandField(const std::string& k) {
  return k == "force_N" || k == "torque_Nm" || k == "penalty_force_N" || k == "impulsive_force_N" ||
         k == "sequence" || k == "clipped" || k == "safe_fallback";
}

py::dict CommandDict(const DeviceCommand& c) {
  return py::dict("sequence"_a = c.sequence, "force_N"_a = Vec3(c.force_N),
                  "torque_Nm"_a = Vec3(c.torque_Nm), "penalty_force_N"_a = Vec3(c.penalty_force_N),
                  "impulsive_force_N"_a = Vec3(c.impulsive_force_N), "clipped"_a = c.clipped,
                  "safe_fallback"_a = c.safe_fallback);
}

py::dict WarningsDict(const std::array<WarningStat, static_cast<int>(Warning::kCount)>& w) {
  py::dict d;
  for (int k = 0; k < static_cast<int>(Warning::kCount); ++k) {
    if (w[k].count > 0) d[WarningName(static_cast<Warning>(k))] = w[k].count;
  }
  return d;
}

// Configure after changing a section; on a refused value the model is left as it was
void ConfigureSections(Model& model, const std::optional<ContactParams>& contact,
                       const std::optional<RenderParams>& render,
                       const std::optional<DeviceParams>& device) {
  const Model before = model;
  if (contact) model.contact = *contact;
  if (render) model.render = *render;
  if (device) model.device = *device;
  try {
    Configure(model);
  } catch (...) {
    model = before;
    throw;
  }
}

// --- the tap experiment through the CLI's flags ---------------------------------------------

struct TapResultNative {
  py::object result;  // the JSON object `rigidtouch tap --json` prints, as Python objects
  py::array trace;    // one sample per tick (TraceDtype)
};

TapResultNative Tap(const std::vector<std::string>& args) {
  cli::TapOutcome out;
  {
    py::gil_scoped_release release;
    out = cli::RunTapFlags(args);
    // passive = energy to the user never positive: the running sum's largest value
    const std::vector<double> cumulative = analysis::CumulativeEnergyToUserJ(out.run.trace);
    double most = 0.0;
    for (double e : cumulative) most = std::max(most, e);
    out.result["max_cumulative_energy_to_user_J"] = most;
  }
  TapResultNative r;
  r.result = ToPython(out.result);
  r.trace = TraceArray(std::move(out.run.trace));
  return r;
}

// --- the study toolkit ------------------------------------------------------------------------

py::object SimulateCohort(const std::string& protocol_path, int participants, std::uint64_t seed,
                          const std::string& observer_path, const std::string& scene,
                          const std::string& device, const std::string& log_dir, bool resume) {
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    const st::Protocol protocol = st::LoadProtocol(protocol_path);
    st::CohortConfig config;
    if (participants < 1) {
      throw Error("participants = " + std::to_string(participants) + ": valid 1 or more");
    }
    config.participants = participants;
    config.seed = seed;
    config.resume = resume;
    config.log_dir = log_dir;
    config.observer =
        observer_path.empty() ? st::ObserverParams{} : st::LoadObserverParams(observer_path);
    config.software_version = RIGIDTOUCH_VERSION;
    st::TapSourceOptions source_options;
    source_options.scene = scene;
    source_options.device = device;
    const auto source = st::MakeTapStimulusSource(source_options);
    const std::vector<st::ParticipantRun> runs = st::SimulateCohort(protocol, *source, config);
    std::vector<st::LogInput> logs;
    for (const auto& run : runs) {
      logs.push_back({run.log_path.empty() ? run.id : run.log_path, run.records});
    }
    report = st::ReportToJson(st::AnalyzeLogs(logs));
    report["simulation"] = {{"participants", participants},
                            {"seed", seed},
                            {"observer", config.observer.ToJson()},
                            {"stimulus_source", source->Describe()}};
  }
  return ToPython(report);
}

py::object AnalyzeLogs(const std::vector<std::string>& paths) {
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    std::vector<st::LogInput> logs;
    for (const std::string& path : paths) {
      st::LogContents contents = st::ReadLog(path);
      if (contents.records.empty()) throw Error(path + ": no such log or empty log");
      logs.push_back({path, std::move(contents.records)});
    }
    report = st::ReportToJson(st::AnalyzeLogs(logs));
  }
  return ToPython(report);
}

// the module's docstring, and Python exceptions for the library's errors: ValueError for bad
// input, OutputError (an OSError) for a file that cannot be written
void DefineDocAndErrors(py::module_& m) {
  m.doc() =
      "rigidtouch's engine from Python: haptic rendering of rigid contact (penalty feedback plus "
      "passive collision impulses). SI units throughout, the unit in every name.";
  static py::exception<io::OutputError> output_error(m, "OutputError", PyExc_OSError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const io::OutputError& e) {
      output_error(e.what());
    } catch (const Error& e) {
      // bad user input: the message names the file, field or value
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
}

// the parameter sections of a scene: contact law, rendering, device, load options
void DefineParams(py::module_& m) {
  py::class_<ContactParams>(m, "ContactParams",
                            "Penalty contact law (tick stage 4); every field in SI units.")
      .def(py::init<>())
      .def_readwrite("stiffness_N_per_m", &ContactParams::stiffness_N_per_m,
                     "tool contact stiffness k [N/m]")
      .def_readwrite("damping_Ns_per_m", &ContactParams::damping_Ns_per_m,
                     "tool contact damping b [N s/m]")
      .def_readwrite("scene_stiffness_N_per_m", &ContactParams::scene_stiffness_N_per_m,
                     "stiffness of contacts between other bodies [N/m]")
      .def_readwrite("scene_damping_Ns_per_m", &ContactParams::scene_damping_Ns_per_m,
                     "damping of contacts between other bodies [N s/m]")
      .def_readwrite("friction_static", &ContactParams::friction_static,
                     "static Coulomb coefficient, >= 0; -1: the MJCF geom friction")
      .def_readwrite("friction_kinetic", &ContactParams::friction_kinetic,
                     "kinetic Coulomb coefficient, >= 0; -1: the MJCF geom friction")
      .def_readwrite("tangential_ratio", &ContactParams::tangential_ratio,
                     "tangential anchor spring relative to the normal law")
      .def_readwrite("onset_speed_mps", &ContactParams::onset_speed_mps,
                     "approach speed above which a new contact starts a window [m/s]")
      .def_readwrite("scene_stiffness_given", &ContactParams::scene_stiffness_given,
                     "keep scene_stiffness_N_per_m even when it equals the default")
      .def_readwrite("scene_damping_given", &ContactParams::scene_damping_given,
                     "keep scene_damping_Ns_per_m even when it equals the default");

  py::class_<RenderParams>(m, "RenderParams", "Collision rendering (Eq. 6-7).")
      .def(py::init<>())
      .def_property(
          "renderer",
          [](const RenderParams& r) { return std::string(text::RendererName(r.renderer)); },
          [](RenderParams& r, const std::string& name) { r.renderer = io::ParseRenderer(name); },
          "renderer name, as the CLI's --renderer takes it")
      .def_readwrite("restitution", &RenderParams::restitution, "restitution e in [0, 1]")
      .def_readwrite("t_collision_s", &RenderParams::t_collision_s,
                     "collision window t_c [s], at most 0.1")
      .def_readwrite("frequency_given", &RenderParams::frequency_given,
                     "keep frequency_hz even when it is the default and above 1/h")
      .def_readwrite("frequency_hz", &RenderParams::frequency_hz,
                     "impulse-train frequency f [Hz], in [1/t_c, 1/h]")
      .def_readwrite("reference_solver", &RenderParams::reference_solver,
                     "use the exact pseudo-inverse of Eq. 5/8 (may pull; allocates)");

  py::class_<DeviceParams>(m, "DeviceParams", "Device-side settings of the tick.")
      .def(py::init<>())
      .def_property(
          "coupling",
          [](const DeviceParams& d) { return std::string(text::CouplingName(d.coupling)); },
          [](DeviceParams& d, const std::string& name) { d.coupling = io::ParseCoupling(name); },
          "none | direct | virtual")
      .def_property(
          "max_force_N", [](const DeviceParams& d) { return d.limits.max_force_N; },
          [](DeviceParams& d, double v) { d.limits.max_force_N = v; }, "force limit [N]; 0: none")
      .def_readwrite("coupling_stiffness_N_per_m", &DeviceParams::coupling_stiffness_N_per_m,
                     "virtual coupling stiffness [N/m]")
      .def_readwrite("coupling_damping_Ns_per_m", &DeviceParams::coupling_damping_Ns_per_m,
                     "virtual coupling damping [N s/m]")
      .def_readwrite("workspace_offset_m", &DeviceParams::workspace_offset_m,
                     "tool position = device position + this [m]")
      .def_property(
          "max_stiffness_N_per_m",
          [](const DeviceParams& d) { return d.limits.max_stiffness_N_per_m; },
          [](DeviceParams& d, double v) { d.limits.max_stiffness_N_per_m = v; },
          "largest stiffness the device displays [N/m]; 0: unknown")
      .def_property(
          "max_damping_Ns_per_m",
          [](const DeviceParams& d) { return d.limits.max_damping_Ns_per_m; },
          [](DeviceParams& d, double v) { d.limits.max_damping_Ns_per_m = v; },
          "largest damping the device displays [N s/m]; 0: unknown")
      .def_readwrite("plausible_radius_m", &DeviceParams::plausible_radius_m,
                     "device states farther from the origin are implausible [m]")
      .def_readwrite("plausible_speed_mps", &DeviceParams::plausible_speed_mps,
                     "device states faster than this are implausible [m/s]")
      .def_readwrite("plausible_angular_speed_radps", &DeviceParams::plausible_angular_speed_radps,
                     "device states spinning faster are implausible [rad/s]");

  py::class_<LoadOptions>(m, "LoadOptions",
                          "rigidtouch's own parameters of a scene, apart from the MJCF file.")
      .def(py::init<>())
      .def_readwrite("tool_name", &LoadOptions::tool_name, "body that is the virtual tool")
      .def_readwrite("timestep_s", &LoadOptions::timestep_s,
                     "time step h [s]; None: the MJCF option timestep")
      .def_readwrite("contact", &LoadOptions::contact, "ContactParams")
      .def_readwrite("render", &LoadOptions::render, "RenderParams")
      .def_readwrite("device", &LoadOptions::device, "DeviceParams")
      .def_readwrite("max_contacts", &LoadOptions::max_contacts,
                     "contact capacity; 0: what the scene can produce")
      .def_readwrite("max_group_bodies", &LoadOptions::max_group_bodies,
                     "bodies per contact group; 0: every body")
      .def_readwrite("threads", &LoadOptions::threads,
                     "1, or 2: a worker thread shares collision detection, the contacts' "
                     "classification and forces, and the group solves (the results are the "
                     "same bit for bit)");
}

// f(joint, qpos address, dof address) for every joint of every tree, the addresses into the
// trees' coordinates laid end to end (Data.qpos, Data.qvel)
template <typename F>
void ForEachJoint(const Model& model, F&& f) {
  int q0 = 0, v0 = 0;
  for (const ArticulatedTree& tree : model.trees) {
    for (const JointModel& j : tree.joints) f(j, q0 + j.qpos_adr, v0 + j.dof_adr);
    q0 += tree.nq;
    v0 += tree.nv;
  }
}

std::vector<std::string> JointStrings(const Model& model, bool types) {
  std::vector<std::string> out;
  ForEachJoint(model, [&](const JointModel& j, int, int) {
    if (!types) {
      out.push_back(j.name);
      return;
    }
    out.push_back(JointKindName(j.type));
  });
  return out;
}

py::array_t<double> JointRanges(const Model& model) {
  std::vector<double> r;
  ForEachJoint(model, [&](const JointModel& j, int, int) {
    const double inf = std::numeric_limits<double>::infinity();
    r.push_back(j.limited ? j.range_lo_rad_or_m : -inf);
    r.push_back(j.limited ? j.range_hi_rad_or_m : inf);
  });
  py::array_t<double> out({static_cast<py::ssize_t>(r.size() / 2), py::ssize_t{2}});
  std::copy(r.begin(), r.end(), out.mutable_data());
  return out;
}

py::array_t<int> JointAddresses(const Model& model, bool dof) {
  std::vector<int> out;
  ForEachJoint(model, [&](const JointModel&, int q, int v) { out.push_back(dof ? v : q); });
  return py::array_t<int>(py::cast(out));
}

// every tree's qpos (or qvel) laid end to end
py::array_t<double> TreeVector(const Data& d, bool velocity) {
  std::vector<double> out;
  for (const auto& tree : d.trees) {
    const Eigen::VectorXd& x = velocity ? tree->qvel : tree->qpos;
    out.insert(out.end(), x.data(), x.data() + x.size());
  }
  return py::array_t<double>(py::cast(out));
}

// the loaded scene
void DefineModel(py::module_& m) {
  py::class_<Model>(m, "Model",
                    "A loaded scene: everything constant while it runs. Change its contact, "
                    "render and device sections with configure().")
      .def_readonly("source", &Model::source, "scene file it was loaded from")
      .def_readonly("timestep_s", &Model::timestep_s, "time step h [s]")
      .def_readonly("gravity_W", &Model::gravity_W, "gravity, world frame [m/s^2]")
      .def_readonly("tool", &Model::tool, "index of the tool among the bodies")
      .def_property_readonly(
          "body_names",
          [](const Model& model) {
            std::vector<std::string> names;
            for (const BodyModel& b : model.bodies) names.push_back(b.name);
            return names;
          },
          "names of the dynamic bodies, in state order")
      .def_property_readonly(
          "body_masses_kg",
          [](const Model& model) {
            std::vector<double> masses;
            for (const BodyModel& b : model.bodies) masses.push_back(b.mass_kg);
            return masses;
          },
          "mass of each dynamic body [kg]")
      .def_property_readonly(
          "nbody", [](const Model& model) { return static_cast<int>(model.bodies.size()); },
          "number of dynamic bodies")
      .def_property_readonly(
          "contact", [](const Model& model) { return model.contact; },
          "the contact law (a copy; change it with configure)")
      .def_property_readonly(
          "render", [](const Model& model) { return model.render; },
          "the rendering (a copy; change it with configure)")
      .def_property_readonly(
          "device", [](const Model& model) { return model.device; },
          "the device settings (a copy; change it with configure)")
      .def_property_readonly(
          "schedule",
          [](const Model& model) {
            return py::dict("window_steps"_a = model.schedule.window_steps,
                            "interval_steps"_a = model.schedule.interval_steps,
                            "impulses"_a = model.schedule.impulses);
          },
          "impulse schedule derived by configure (Eq. 6, Eq. 7), in steps")
      .def_readonly("has_tool", &Model::has_tool,
                    "whether the scene has a tool (False when loaded with tool=None)")
      .def_property_readonly(
          "joint_names", [](const Model& model) { return JointStrings(model, false); },
          "every tree's joints, tree after tree in joint order (MuJoCo's)")
      .def_property_readonly(
          "joint_types", [](const Model& model) { return JointStrings(model, true); },
          "each joint's type: 'hinge', 'slide', 'ball' or 'free'")
      .def_property_readonly("joint_ranges", &JointRanges,
                             "each joint's range, (njoint, 2): [rad] for a hinge, [m] for a "
                             "slide, [0, max angle] for a ball; (-inf, inf) when not limited")
      .def_property_readonly(
          "joint_limited",
          [](const Model& model) {
            std::vector<bool> out;
            ForEachJoint(model, [&](const JointModel& j, int, int) { out.push_back(j.limited); });
            return py::array_t<bool>(py::cast(out));
          },
          "whether each joint's range is enforced (hinge, slide) or reported (ball)")
      .def_property_readonly(
          "joint_qpos_adr", [](const Model& model) { return JointAddresses(model, false); },
          "each joint's first coordinate in Data.qpos (1 for a hinge or slide, 4 for a ball, 7 "
          "for a free joint)")
      .def_property_readonly(
          "joint_dof_adr", [](const Model& model) { return JointAddresses(model, true); },
          "each joint's first velocity in Data.qvel (1, 3 or 6 of them)")
      .def_readonly("max_contacts", &Model::max_contacts, "contact capacity")
      .def_readonly("load_warnings", &Model::load_warnings,
                    "problems found at load that do not stop the scene, one sentence each");
}

// the running state, with array views into it
void DefineData(py::module_& m) {
  py::class_<Data>(m, "Data",
                   "All mutable state of a running scene. Arrays are views into it (no copy): "
                   "they change with every tick.")
      .def_readonly("step", &Data::step, "ticks done")
      .def_readonly("time_s", &Data::time_s, "simulated time [s]")
      .def_property_readonly(
          "x_W", [](py::object self) { return BodyStateView(self.cast<Data&>().bodies, 0, self); },
          "centre-of-mass positions, world frame, (nbody, 3) [m]; a writable view")
      .def_property_readonly(
          "q_WB_xyzw",
          [](py::object self) { return BodyStateView(self.cast<Data&>().bodies, 1, self); },
          "orientations as unit quaternions (x, y, z, w), (nbody, 4); a writable view")
      .def_property_readonly(
          "v_W", [](py::object self) { return BodyStateView(self.cast<Data&>().bodies, 2, self); },
          "linear velocities, world frame, (nbody, 3) [m/s]; a writable view")
      .def_property_readonly(
          "w_W", [](py::object self) { return BodyStateView(self.cast<Data&>().bodies, 3, self); },
          "angular velocities, world frame, (nbody, 3) [rad/s]; a writable view")
      .def_property_readonly(
          "qpos", [](const Data& d) { return TreeVector(d, false); },
          "every tree's joint coordinates, tree after tree (MuJoCo's qpos: rad, m, quaternions w "
          "x y z), (nq,); a copy")
      .def_property_readonly(
          "qvel", [](const Data& d) { return TreeVector(d, true); },
          "every tree's joint velocities, tree after tree (rad/s, m/s), (nv,); a copy")
      .def_property_readonly(
          "joint_at_limit",
          [](const Data& d) {
            std::vector<bool> out;
            for (const auto& tree : d.joint_at_limit) {
              for (const unsigned char a : tree) out.push_back(a != 0);
            }
            return py::array_t<bool>(py::cast(out));
          },
          "whether each joint is at or beyond a limit of its range, (njoint,); a copy")
      .def_readonly("ncontact", &Data::ncontact, "valid contacts this tick")
      .def_property_readonly(
          "contacts",
          [](py::object self) {
            const Data& d = self.cast<const Data&>();
            return ContactView(d.contacts, d.ncontact, self);
          },
          "this tick's contacts, a read-only structured view (positions [m], normal from b to "
          "a, depth_m [m], normal_force_N [N], friction_force_N_W [N], impulse_Ns [N s])")
      .def_property_readonly(
          "tool_penalty_force_N_W", [](const Data& d) { return Vec3(d.tool_penalty_force_N_W); },
          "contact penalty force on the tool, last tick [N]")
      .def_property_readonly(
          "tool_coupling_force_N_W", [](const Data& d) { return Vec3(d.tool_coupling_force_N_W); },
          "virtual coupling force on the tool, last tick [N]")
      .def_property_readonly(
          "tool_impulse_Ns_W", [](const Data& d) { return Vec3(d.tool_impulse_Ns_W); },
          "linear impulse on the tool, last tick [N s]")
      .def_readonly("tool_penetration_m", &Data::tool_penetration_m, "deepest tool penetration [m]")
      .def_readonly("tool_contacts", &Data::tool_contacts, "tool contacts this tick")
      .def_property_readonly(
          "impulses",
          [](const Data& d) {
            py::list out;
            for (int k = 0; k < d.nimpulse; ++k) {
              const ImpulseEvent& e = d.impulses[k];
              out.append(py::dict("step"_a = e.step, "time_s"_a = e.time_s, "group"_a = e.group,
                                  "contacts"_a = e.contacts, "index"_a = e.index,
                                  "total"_a = e.total, "tool"_a = e.tool,
                                  "kinetic_energy_before_J"_a = e.kinetic_energy_before_J,
                                  "kinetic_energy_after_J"_a = e.kinetic_energy_after_J,
                                  "impulse_norm_Ns"_a = e.impulse_norm_Ns,
                                  "tool_impulse_Ns_W"_a = Vec3(e.tool_impulse_Ns_W)));
            }
            return out;
          },
          "impulses applied this tick (energies [J], impulses [N s])")
      .def_property_readonly(
          "warnings", [](const Data& d) { return WarningsDict(d.warnings); },
          "warnings counted so far {name: ticks}");
}

// a Data of another scene would be read and written past its buffers: refused before any tick
void RequireDataOf(const Model& model, const Data& data) {
  if (!DataFitsModel(model, data)) {
    throw py::value_error(
        "data was not made by make_data for this model (another scene, or another load of it): "
        "call make_data(model)");
  }
}

// a force or torque on the tool of a scene loaded without one is an error, as in `simulate`
void RequireToolFor(const Model& model, const std::optional<Vec3>& force,
                    const std::optional<Vec3>& torque) {
  const bool pushed = (force && !force->isZero(0.0)) || (torque && !torque->isZero(0.0));
  if (!model.has_tool && pushed) {
    throw py::value_error("tool_force_N / tool_torque_Nm need a tool; the scene '" + model.source +
                          "' was loaded with tool=None");
  }
}

// every joint as `rigidtouch simulate --json` lists it, as arrays: a hinge's or slide's position
// and velocity, NaN for a ball or free joint (whose coordinates are in Data.qpos and qvel)
py::dict JointState(const Model& model, const Data& data) {
  RequireDataOf(model, data);
  const py::array_t<double> qpos = TreeVector(data, false), qvel = TreeVector(data, true);
  std::vector<double> q, v;
  ForEachJoint(model, [&](const JointModel& j, int qa, int va) {
    const bool scalar = j.type == JointKind::kHinge || j.type == JointKind::kSlide;
    q.push_back(scalar ? qpos.at(qa) : std::numeric_limits<double>::quiet_NaN());
    v.push_back(scalar ? qvel.at(va) : std::numeric_limits<double>::quiet_NaN());
  });
  std::vector<bool> limited, at_limit;
  ForEachJoint(model, [&](const JointModel& j, int, int) { limited.push_back(j.limited); });
  for (const auto& tree : data.joint_at_limit) {
    for (const unsigned char a : tree) at_limit.push_back(a != 0);
  }
  return py::dict("names"_a = JointStrings(model, false), "types"_a = JointStrings(model, true),
                  "position"_a = py::array_t<double>(py::cast(q)),
                  "velocity"_a = py::array_t<double>(py::cast(v)), "range"_a = JointRanges(model),
                  "limited"_a = py::array_t<bool>(py::cast(limited)),
                  "at_limit"_a = py::array_t<bool>(py::cast(at_limit)));
}

// loading, configuring and stepping a scene
void DefineTick(py::module_& m) {
  m.def(
      "load_model",
      [](const std::string& path, std::optional<LoadOptions> options, const std::string& config,
         py::object tool) {
        LoadOptions o = options.value_or(LoadOptions{});
        // tool=None: no tool (the CLI's --tool none); a name: that free body; left out: the
        // options' tool_name
        if (tool.is_none()) {
          o.tool_name = "none";
        } else if (py::isinstance<py::str>(tool)) {
          o.tool_name = tool.cast<std::string>();
        } else if (!py::isinstance<py::ellipsis>(tool)) {
          throw py::value_error("tool must be a body's name or None, got " +
                                py::repr(tool).cast<std::string>());
        }
        py::gil_scoped_release release;
        if (!config.empty()) io::ApplyConfigFile(config, o);
        return LoadModel(path, o);
      },
      "path"_a, "options"_a = py::none(), py::kw_only(), "config"_a = "", "tool"_a = py::ellipsis(),
      "Loads an MJCF scene (compiled by MuJoCo) with rigidtouch's options; a JSON config file "
      "(the CLI's --config) overrides the options' fields it gives. tool: the free body that is "
      "the tool (default: options.tool_name, 'tool'), or None for a scene without a tool (as "
      "the CLI's --tool none). Raises ValueError naming the file, element or parameter on bad "
      "input.");
  m.def(
      "configure",
      [](Model& model, std::optional<ContactParams> contact, std::optional<RenderParams> render,
         std::optional<DeviceParams> device) { ConfigureSections(model, contact, render, device); },
      "model"_a, py::kw_only(), "contact"_a = py::none(), "render"_a = py::none(),
      "device"_a = py::none(),
      "Replaces the given sections of `model`, validates them and derives the impulse schedule "
      "(Eq. 6, Eq. 7). Raises ValueError naming the parameter; the model is then unchanged.");
  m.def(
      "make_data", [](const Model& model) { return MakeData(model); }, "model"_a,
      "Allocates all state of `model`, at its initial state.");
  m.def(
      "reset_data",
      [](const Model& model, Data& data) {
        RequireDataOf(model, data);
        ResetData(model, data);
      },
      "model"_a, "data"_a,
      "Puts `data` back to the initial state (keeps its buffers, so views stay valid). Raises "
      "ValueError if `data` was not made for `model`.");
  m.def(
      "tick",
      [](const Model& model, Data& data, std::optional<py::dict> device_state,
         std::optional<Vec3> tool_force_N, std::optional<Vec3> tool_torque_Nm) {
        RequireDataOf(model, data);
        RequireToolFor(model, tool_force_N, tool_torque_Nm);
        TickInput input;
        if (device_state) input.device = MakeDeviceState(*device_state);
        if (tool_force_N) input.tool_wrench.force_N = *tool_force_N;
        if (tool_torque_Nm) input.tool_wrench.torque_Nm = *tool_torque_Nm;
        return CommandDict(Tick(model, data, input));
      },
      "model"_a, "data"_a, "device_state"_a = py::none(), "tool_force_N"_a = py::none(),
      "tool_torque_Nm"_a = py::none(),
      "Advances the world by one step h and returns the device command {force_N [N], "
      "torque_Nm [N m], penalty_force_N [N], impulsive_force_N [N], clipped, safe_fallback, "
      "sequence}. device_state: a dict of position_m [m], velocity_mps [m/s], "
      "angular_velocity_radps [rad/s], orientation_wxyz, time_s [s], sequence, valid, fresh "
      "(used unless the coupling is none); tool_force_N [N] and tool_torque_Nm [N m]: the user "
      "wrench on the tool (coupling none). Raises ValueError for a data not made for `model` or "
      "a malformed device_state, before the tick; the tick itself never raises: problems are "
      "counted in data.warnings.");
  m.def(
      "run",
      [](const Model& model, Data& data, long steps, std::optional<Vec3> tool_force_N) {
        if (steps < 0) throw py::value_error("steps = " + std::to_string(steps) + ": valid >= 0");
        RequireDataOf(model, data);
        RequireToolFor(model, tool_force_N, std::nullopt);
        TickInput input;
        if (tool_force_N) input.tool_wrench.force_N = *tool_force_N;
        py::gil_scoped_release release;
        for (long s = 0; s < steps; ++s) Tick(model, data, input);
      },
      "model"_a, "data"_a, "steps"_a, "tool_force_N"_a = py::none(),
      "Runs `steps` ticks with a constant user force on the tool [N] (coupling none), without "
      "the GIL, as `rigidtouch simulate` does.");
  m.def("joint_state", &JointState, "model"_a, "data"_a,
        "Every tree's joints as numpy arrays: names, types ('hinge', 'slide', 'ball', 'free'), "
        "position [rad or m] and velocity [rad/s or m/s] of each hinge and slide (NaN for a ball "
        "or free joint: see Data.qpos, Data.qvel and Model.joint_qpos_adr), range (njoint, 2), "
        "limited and at_limit; the values `rigidtouch simulate --json` lists.");
  m.def(
      "kinetic_energy",
      [](const Model& model, const Data& data) {
        RequireDataOf(model, data);
        return KineticEnergy(model, data);
      },
      "model"_a, "data"_a, "Total kinetic energy of the dynamic bodies [J].");
}

// the simulated hand and device
void DefineSimulatedDevice(py::module_& m) {
  py::class_<device::SimulatedDevice>(
      m, "SimulatedDevice",
      "A simulated hand holding a simulated haptic device, scripted to tap a wall: read() gives "
      "the device state, write() displays a command, end_period() advances the plant.")
      .def(
          "read",
          [](device::SimulatedDevice& d) {
            const DeviceState s = d.Read();
            return py::dict(
                "sequence"_a = s.sequence, "time_s"_a = s.time_s,
                "position_m"_a = Vec3(s.position_m), "velocity_mps"_a = Vec3(s.velocity_mps),
                "angular_velocity_radps"_a = Vec3(s.angular_velocity_radps),
                "orientation_wxyz"_a = Eigen::Vector4d(s.orientation.w(), s.orientation.x(),
                                                       s.orientation.y(), s.orientation.z()),
                "buttons"_a = s.buttons, "valid"_a = s.valid, "fresh"_a = s.fresh);
          },
          "The device's reading: encoder position [m], filtered velocity [m/s], time [s].")
      .def(
          "write",
          [](device::SimulatedDevice& d, const py::dict& command) {
            DeviceCommand c;
            for (const auto& [key, value] : command) {
              const std::string k = py::cast<std::string>(key);
              if (k == "force_N") c.force_N = py::cast<Vec3>(value);
              if (k == "torque_Nm") c.torque_Nm = py::cast<Vec3>(value);
              if (k == "penalty_force_N") c.penalty_force_N = py::cast<Vec3>(value);
              if (k == "impulsive_force_N") c.impulsive_force_N = py::cast<Vec3>(value);
              if (k == "sequence") c.sequence = py::cast<std::uint64_t>(value);
              if (k == "clipped") c.clipped = py::cast<bool>(value);
              if (k == "safe_fallback") c.safe_fallback = py::cast<bool>(value);
              if (!IsCommandField(k)) {
                throw py::value_error("device command: unknown field '" + k +
                                      "'; valid: force_N, torque_Nm, penalty_force_N, "
                                      "impulsive_force_N, sequence, clipped, safe_fallback");
              }
            }
            d.Write(c);
          },
          "command"_a,
          "Displays a command (as tick() returns it) from now until the next write: force_N "
          "[N], clipped to the device's limit.")
      .def(
          "end_period", [](device::SimulatedDevice& d, double period_s) { d.EndPeriod(period_s); },
          "period_s"_a, "Advances the hand and device plant by one haptic period [s].")
      .def_property_readonly("time_s", &device::SimulatedDevice::time_s, "plant time [s]")
      .def_property_readonly("finished", &device::SimulatedDevice::finished,
                             "the scripted taps are over")
      .def_property_readonly("current_tap", &device::SimulatedDevice::current_tap,
                             "tap in progress, -1 between taps")
      .def_property_readonly(
          "true_position_m", [](const device::SimulatedDevice& d) { return d.true_position_m(); },
          "handle position, unquantized [m]")
      .def_property_readonly(
          "true_velocity_mps",
          [](const device::SimulatedDevice& d) { return d.true_velocity_mps(); },
          "handle velocity [m/s]")
      .def_property_readonly(
          "displayed_force_N",
          [](const device::SimulatedDevice& d) { return d.displayed_force_N(); },
          "force the device displays now [N]")
      .def_property_readonly(
          "hand_force_N", [](const device::SimulatedDevice& d) { return d.hand_force_N(); },
          "force the hand applies to the handle [N]")
      .def_property_readonly("last_command_clipped", &device::SimulatedDevice::last_command_clipped,
                             "the device's limit clipped the last command")
      .def_property_readonly("energy_to_user_J", &device::SimulatedDevice::energy_to_user_J,
                             "energy the device delivered to the user so far [J]")
      .def_property_readonly("duration_s", &device::SimulatedDevice::duration_s,
                             "length of the scripted taps [s]");
}

// the CLI's tap experiment and study analyses in process
void DefineTapAndStudy(py::module_& m) {
  m.def("_tap_flag_names", &cli::TapFlagNames,
        "The long names of `rigidtouch tap`'s flags, without the dashes.");
  m.def(
      "_prepare_tap",
      [](const std::vector<std::string>& args) {
        analysis::TapSetup setup = [&] {
          py::gil_scoped_release release;
          return cli::PrepareTapFlags(args);
        }();
        return py::make_tuple(
            std::move(setup.model),
            std::unique_ptr<device::SimulatedDevice>(std::move(setup.simulated)),
            py::dict("name"_a = setup.device.name, "max_force_N"_a = setup.device.max_force_N,
                     "max_stiffness_N_per_m"_a = setup.device.max_stiffness_N_per_m,
                     "max_damping_Ns_per_m"_a = setup.device.max_damping_Ns_per_m));
      },
      "args"_a,
      "The model (tool coupled to the device) and simulated hand and device that `rigidtouch "
      "tap ARGS` would run, for a loop written in Python.");

  py::class_<TapResultNative>(m, "_TapResultNative")
      .def_readonly("result", &TapResultNative::result)
      .def_readonly("trace", &TapResultNative::trace);
  m.def("_tap", &Tap, "args"_a,
        "Runs `rigidtouch tap ARGS` in process (the CLI's flags and settings resolution); "
        "returns the --json object and the trace (read-only structured array, no copy).");
  m.def("trace_dtype", &TraceDtype,
        "The structured dtype of a trace: the trace CSV's columns, SI units in the names.");
  m.def("contact_dtype", &ContactDtype, "The structured dtype of Data.contacts.");

  m.def("simulate_cohort", &SimulateCohort, "protocol"_a, "participants"_a, "seed"_a, py::kw_only(),
        "observer"_a = "", "scene"_a = "", "device"_a = "", "log_dir"_a = "", "resume"_a = false,
        "Runs a virtual cohort of simulated participants on a study protocol (JSON file) and "
        "analyses it, as `rigidtouch study simulate --json`; returns the report (percent "
        "correct [%], d', exact binomial tests per test and participant).");
  m.def("analyze_logs", &AnalyzeLogs, "logs"_a,
        "Analyses study session logs of one protocol, as `rigidtouch study analyze --json`.");
}

}  // namespace

void DefineModule(py::module_& m) {
  DefineDocAndErrors(m);
  DefineParams(m);
  DefineMaterial(m);
  DefineModel(m);
  DefineData(m);
  DefineTick(m);
  DefineSimulatedDevice(m);
  DefineTapAndStudy(m);
}

}  // namespace rigidtouch::python

PYBIND11_MODULE(_rigidtouch, m) {
  rigidtouch::python::DefineModule(m);
}
