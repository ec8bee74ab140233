// Parameter validation (load-time error tier: throw with the parameter and its range), the scene
// contact defaults derived from the bodies' masses and h, and the load-time warnings about contact
// laws that cannot hold a body or are unstable for it (docs/method.md, "Contact defaults from the
// scene").
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "base/limits.h"
#include "base/names.h"
#include "base/text.h"
#include "contact/schedule.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

void RequireInRange(bool ok, const std::string& name, double value, const std::string& range) {
  if (ok) return;
  std::ostringstream msg;
  msg << "parameter " << name << " = " << value << " is out of range: valid " << range;
  throw Error(msg.str());
}

void RequireFinite(const std::string& name, double value, double lo, double hi,
                   const std::string& range) {
  RequireInRange(std::isfinite(value) && value >= lo && value <= hi, name, value, range);
}

constexpr double kInfinity = INFINITY;

// A device cannot display a stiffness or damping above its closed-loop maximum (it goes unstable
// or saturates against the user's hand); such a value is refused, never clamped silently.
void RequireDisplayable(const std::string& name, double value, const std::string& limit_name,
                        double limit, const std::string& unit, const std::string& why) {
  if (!(limit > 0.0) || value <= limit) return;
  std::ostringstream msg;
  msg << "parameter " << name << " = " << value << " " << unit
      << " is above what the device can display: device " << limit_name << " = " << limit << " "
      << unit << " (" << why << "); lower it or use a device that can display it";
  throw Error(msg.str());
}

// Contact defaults from the scene (docs/method.md): the static sink m g / k of a body resting on
// one contact pair is at most kSinkFraction of its smallest geom size; the lightest body's implicit
// scene contact keeps k h^2 / m <= kStableStiffness and b h / m <= kStableDamping (measured: a
// 0.2 g plate dropped tilted at h = 2 ms rests up to k h^2 / m = 16 and is thrown off from 32);
// explicit tool contacts keep the symplectic-Euler limits k h^2 / m < 4 and b h / m < 2; damping
// gives the heaviest body at least kDampingRatio of critical.
constexpr double kSinkFraction = 0.01;
constexpr double kStableStiffness = 8.0;
constexpr double kStableDamping = 4.0;
constexpr double kExplicitStableStiffness = 4.0;
constexpr double kExplicitStableDamping = 2.0;
constexpr double kDampingRatio = 0.2;

std::string ConfigNumber(double x) {
  return text::FormatNumber(x);
}

// The smallest size of a body's colliding geoms: radius, or smallest box half-extent, or a mesh's
// bounding radius [m]; infinity if the body has none.
double BodySize(const Model& model, int body) {
  double size = kInfinity;
  for (const GeomModel& g : model.geoms) {
    if (g.body != body || (g.contype == 0 && g.conaffinity == 0)) continue;
    switch (g.type) {
      case GeomType::kSphere:
      case GeomType::kCapsule:
        size = std::min(size, g.size.x());
        break;
      case GeomType::kBox:
        size = std::min(size, g.size.minCoeff());
        break;
      case GeomType::kMesh:
        size = std::min(size, g.rbound_m);
        break;
      case GeomType::kPlane:
        break;
    }
  }
  return size;
}

std::string Body(const Model& model, int i) {
  return "body '" + model.bodies[i].name + "' (" + ConfigNumber(model.bodies[i].mass_kg) + " kg)";
}

// Warns if stiffness k (named `name`) cannot hold body i on one contact pair: m g / k > size.
void CheckHold(const Model& model, int i, const std::string& name, double k,
               std::vector<std::string>& warnings) {
  const double weight = model.bodies[i].mass_kg * model.gravity_W.norm();
  const double size = BodySize(model, i);
  if (!(weight > 0.0) || !std::isfinite(size) || weight <= k * size) return;
  warnings.push_back(name + " = " + ConfigNumber(k) + " N/m cannot hold " + Body(model, i) +
                     ": it would sink m g / k = " + ConfigNumber(weight / k) +
                     " m into what it rests on, more than its size " + ConfigNumber(size) + " m");
}

// Warns if k h^2 / m or b h / m of body i exceeds the stability bounds (`verdict`: "is" for the
// explicit law's linear limits, "may be" for the implicit law's measured, margined ones).
void CheckStable(const Model& model, int i, const std::string& k_name, double k,
                 const std::string& b_name, double b, double k_bound, double b_bound,
                 const std::string& solve, const std::string& verdict,
                 std::vector<std::string>& warnings) {
  const double h = model.timestep_s, m = model.bodies[i].mass_kg;
  if (k * h * h / m > k_bound) {
    warnings.push_back(k_name + " = " + ConfigNumber(k) + " N/m " + verdict + " unstable for " +
                       Body(model, i) + " at h = " + ConfigNumber(h) + " s: k h^2 / m = " +
                       ConfigNumber(k * h * h / m) + " > " + ConfigNumber(k_bound) + " (" + solve +
                       "); at most " + ConfigNumber(k_bound * m / (h * h)) + " N/m");
  }
  if (b * h / m > b_bound) {
    warnings.push_back(b_name + " = " + ConfigNumber(b) + " N s/m " + verdict + " unstable for " +
                       Body(model, i) + " at h = " + ConfigNumber(h) +
                       " s: b h / m = " + ConfigNumber(b * h / m) + " > " + ConfigNumber(b_bound) +
                       " (" + solve + "); at most " + ConfigNumber(b_bound * m / h) + " N s/m");
  }
}

// Scene contacts (every contact without the tool, implicit): derives the stiffness and damping
// the user left at their defaults, and warns about the ones the user set.
void SceneContactDefaults(Model& model, std::vector<std::string>& warnings) {
  const ContactParams defaults;
  ContactParams& c = model.contact;
  // not given and equal to the built-in default, or what an earlier Configure derived: derive
  const bool derive_k = !c.scene_stiffness_given &&
                        (c.scene_stiffness_N_per_m == defaults.scene_stiffness_N_per_m ||
                         (model.derived_scene_stiffness_N_per_m > 0.0 &&
                          c.scene_stiffness_N_per_m == model.derived_scene_stiffness_N_per_m));
  const bool derive_b = !c.scene_damping_given &&
                        (c.scene_damping_Ns_per_m == defaults.scene_damping_Ns_per_m ||
                         (model.derived_scene_damping_Ns_per_m > 0.0 &&
                          c.scene_damping_Ns_per_m == model.derived_scene_damping_Ns_per_m));
  const double h = model.timestep_s, g = model.gravity_W.norm();
  int lightest = -1, heaviest = -1;
  double k_hold = 0.0;
  for (int i = 0; i < static_cast<int>(model.bodies.size()); ++i) {
    if (i == model.tool) continue;
    const double m = model.bodies[i].mass_kg;
    if (lightest < 0 || m < model.bodies[lightest].mass_kg) lightest = i;
    if (heaviest < 0 || m > model.bodies[heaviest].mass_kg) heaviest = i;
    const double size = BodySize(model, i);
    if (std::isfinite(size) && size > 0.0 && m * g / (kSinkFraction * size) > k_hold) {
      k_hold = m * g / (kSinkFraction * size);
    }
  }
  if (derive_k) {
    double k = defaults.scene_stiffness_N_per_m;
    if (lightest >= 0) {
      const double k_stable = kStableStiffness * model.bodies[lightest].mass_kg / (h * h);
      k = std::min(std::max(k, k_hold), k_stable);
      // the stable bound wins; a body it cannot hold (sinks more than its size) is reported
      for (int i = 0; k < k_hold && i < static_cast<int>(model.bodies.size()); ++i) {
        const double size = BodySize(model, i);
        const double sink = model.bodies[i].mass_kg * g / k;
        if (i == model.tool || !std::isfinite(size) || sink <= size) continue;
        warnings.push_back(
            "no scene contact stiffness both holds " + Body(model, i) + " and is stable for " +
            Body(model, lightest) + " at h = " + ConfigNumber(h) +
            " s (k h^2 / m <= " + ConfigNumber(kStableStiffness) +
            "): the derived scene_stiffness_N_per_m = " + ConfigNumber(k) +
            " N/m lets it sink m g / k = " + ConfigNumber(sink) + " m, more than its size " +
            ConfigNumber(size) + " m; lower the time step or set the stiffness");
      }
    }
    c.scene_stiffness_N_per_m = k;
    model.derived_scene_stiffness_N_per_m = k;
  } else {
    model.derived_scene_stiffness_N_per_m = 0.0;
  }
  if (derive_b) {
    double b = defaults.scene_damping_Ns_per_m;
    if (lightest >= 0) {
      const double b_ratio = 2.0 * kDampingRatio *
                             std::sqrt(c.scene_stiffness_N_per_m * model.bodies[heaviest].mass_kg);
      b = std::min(std::max(b, b_ratio), kStableDamping * model.bodies[lightest].mass_kg / h);
    }
    c.scene_damping_Ns_per_m = b;
    model.derived_scene_damping_Ns_per_m = b;
  } else {
    model.derived_scene_damping_Ns_per_m = 0.0;
  }
  if (lightest < 0) return;
  if (!derive_k) {
    for (int i = 0; i < static_cast<int>(model.bodies.size()); ++i) {
      if (i != model.tool)
        CheckHold(model, i, "scene_stiffness_N_per_m", c.scene_stiffness_N_per_m, warnings);
    }
  }
  if (!derive_k || !derive_b) {
    CheckStable(model, lightest, "scene_stiffness_N_per_m",
                derive_k ? 0.0 : c.scene_stiffness_N_per_m, "scene_damping_Ns_per_m",
                derive_b ? 0.0 : c.scene_damping_Ns_per_m, kStableStiffness, kStableDamping,
                "implicit scene contact", "may be", warnings);
  }
}

// Tool contacts (explicit, the law the device renders): never derived, but a law that cannot
// hold the tool under gravity (no device: nothing compensates it) or is unstable for a body the
// tool can push is reported.
void ToolContactWarnings(const Model& model, std::vector<std::string>& warnings) {
  if (!model.has_tool) return;  // --tool none: no tool contacts
  const ContactParams& c = model.contact;
  if (model.device.coupling == Coupling::kNone) {
    CheckHold(model, model.tool, "stiffness_N_per_m", c.stiffness_N_per_m, warnings);
  }
  int lightest = -1;
  for (int i = 0; i < static_cast<int>(model.bodies.size()); ++i) {
    // a directly coupled tool is not integrated: its pose is the device's
    if (i == model.tool && model.device.coupling == Coupling::kDirect) continue;
    if (lightest < 0 || model.bodies[i].mass_kg < model.bodies[lightest].mass_kg) lightest = i;
  }
  if (lightest < 0) return;
  CheckStable(model, lightest, "stiffness_N_per_m", c.stiffness_N_per_m, "damping_Ns_per_m",
              c.damping_Ns_per_m, kExplicitStableStiffness, kExplicitStableDamping,
              lightest == model.tool ? "explicit tool contact"
                                     : "explicit tool contact, if the tool pushes it",
              "is", warnings);
}

// contact law parameters (the tool's and the scene's)
void RequireContact(const ContactParams& c) {
  RequireFinite("stiffness_N_per_m", c.stiffness_N_per_m, 0.0, kInfinity, "k >= 0 N/m, finite");
  RequireFinite("damping_Ns_per_m", c.damping_Ns_per_m, 0.0, kInfinity, "b >= 0 N s/m, finite");
  RequireFinite("scene_stiffness_N_per_m", c.scene_stiffness_N_per_m, 0.0, kInfinity,
                "k >= 0 N/m, finite");
  RequireFinite("scene_damping_Ns_per_m", c.scene_damping_Ns_per_m, 0.0, kInfinity,
                "b >= 0 N s/m, finite");
  // -1 exactly stands for the MJCF geom friction; any other negative value is not a coefficient
  for (const auto& [name, mu] : {std::pair{"friction_static", c.friction_static},
                                 std::pair{"friction_kinetic", c.friction_kinetic}}) {
    RequireInRange(mu == -1.0 || (std::isfinite(mu) && mu >= 0.0), name, mu,
                   ">= 0, or -1 for the MJCF geom friction");
  }
  if (c.friction_static >= 0.0 && c.friction_kinetic >= 0.0) {
    RequireInRange(c.friction_static >= c.friction_kinetic, "friction_static", c.friction_static,
                   ">= friction_kinetic (" + std::to_string(c.friction_kinetic) + ")");
  }
  RequireFinite("tangential_ratio", c.tangential_ratio, 0.0, kInfinity, ">= 0");
  RequireFinite("onset_speed_mps", c.onset_speed_mps, 0.0, kInfinity, ">= 0 m/s");
}

// the renderer's parameters, which depend on the renderer kind and on h (a material's Nyquist)
void RequireRender(const Model& model) {
  const RenderParams& r = model.render;
  RequireFinite("restitution", r.restitution, limits::kMinRestitution, limits::kMaxRestitution,
                text::FormatNumber(limits::kMinRestitution) +
                    " <= e <= " + text::FormatNumber(limits::kMaxRestitution) + " (Eq. 4)");
  if (r.renderer == RendererKind::kTrain) {
    const std::string window =
        "0 < t_c <= " + text::FormatNumber(limits::kMaxCollisionWindow_s) + " s";
    RequireFinite("t_collision_s", r.t_collision_s, 0.0, limits::kMaxCollisionWindow_s,
                  window + " (shorter than human reaction time, docs/method.md)");
    RequireInRange(r.t_collision_s > 0.0, "t_collision_s", r.t_collision_s, window);
    RequireInRange(std::isfinite(r.frequency_hz) && r.frequency_hz > 0.0, "frequency_hz",
                   r.frequency_hz, "f > 0 Hz, within [1/t_c, 1/h] (Eq. 6-7)");
    if (r.restitution != limits::kTrainRestitution) {
      std::ostringstream msg;
      msg << "parameter restitution = " << r.restitution
          << " is not allowed with the train renderer: the method requires perfectly plastic "
             "collisions (e = 0), the only post-collision velocity compatible with every "
             "intermediate velocity of the train (Eq. 8, docs/method.md)";
      throw Error(msg.str());
    }
  }
  if (r.renderer == RendererKind::kEvent) {
    const Material& m = r.material;
    if (m.name.empty()) {
      throw Error(
          "parameter material is missing: the event renderer plays a material's transient "
          "(--material rubber|wood|aluminium|FILE.json)");
    }
    RequireFinite("amplitude_Ns_per_m", m.amplitude_Ns_per_m, 0.0, kInfinity, ">= 0 N/(m/s)");
    RequireInRange(std::isfinite(m.decay_per_s) && m.decay_per_s > 0.0, "decay_per_s",
                   m.decay_per_s, "> 0 1/s, finite");
    const double nyquist_hz = 0.5 / model.timestep_s;
    RequireInRange(
        std::isfinite(m.frequency_hz) && m.frequency_hz > 0.0 && m.frequency_hz < nyquist_hz,
        "frequency_hz", m.frequency_hz,
        "in (0, 1 / (2 h)) = (0, " + text::FormatNumber(nyquist_hz) +
            ") Hz: a sampled transient cannot show more");
  } else if (r.renderer == RendererKind::kTrain && !r.material.name.empty()) {
    // a material train: its shares follow e^(-B t) (contact::TrainShare); f and t_c are the
    // render parameters' (io::MaterialTrain derives them from the material)
    RequireInRange(std::isfinite(r.material.decay_per_s) && r.material.decay_per_s > 0.0,
                   "decay_per_s", r.material.decay_per_s, "> 0 1/s, finite");
    if (r.reference_solver) {
      throw Error(
          "parameter reference_solver = true cannot give a material train's decaying shares "
          "(it applies Eq. 8's equal shares); drop it or the material");
    }
  } else if (!r.material.name.empty()) {
    throw Error("parameter material = " + r.material.name +
                " is used only by the event and train renderers; the " +
                text::RendererName(r.renderer) + " renderer takes none");
  }
}

// a joint limit's onset rendering (RenderParams::joint_limit_renderer): penalty, impulse or a
// plastic train over the render's t_c at f (Eq. 6-7, the same bounds as the wall's train)
void RequireJointLimitRenderer(Model& model) {
  const RenderParams& r = model.render;
  const RendererKind k = r.joint_limit_renderer;
  if (k != RendererKind::kPenalty && k != RendererKind::kImpulse && k != RendererKind::kTrain) {
    throw Error(std::string("parameter joint_limit_renderer = ") + text::RendererName(k) +
                " is not a joint-limit renderer; valid: penalty, impulse, train");
  }
  model.joint_limit_schedule = Schedule{};
  if (k != RendererKind::kTrain) return;
  const std::string window =
      "0 < t_c <= " + text::FormatNumber(limits::kMaxCollisionWindow_s) + " s";
  RequireFinite("t_collision_s", r.t_collision_s, 0.0, limits::kMaxCollisionWindow_s,
                window + " (joint_limit_renderer train)");
  RequireInRange(r.t_collision_s > 0.0, "t_collision_s", r.t_collision_s, window);
  RequireInRange(std::isfinite(r.frequency_hz) && r.frequency_hz > 0.0, "frequency_hz",
                 r.frequency_hz, "f > 0 Hz, within [1/t_c, 1/h] (Eq. 6-7)");
  RenderParams train = r;
  train.renderer = RendererKind::kTrain;
  train.material = Material{};
  model.joint_limit_schedule = contact::MakeSchedule(model.timestep_s, train);
}

// the device port, and the laws it renders against what the device can display
void RequireDevice(const Model& model) {
  const ContactParams& c = model.contact;
  const RenderParams& r = model.render;
  const DeviceParams& d = model.device;
  RequireFinite("max_force_N", d.limits.max_force_N, 0.0, kInfinity, ">= 0 N (0: unlimited)");
  RequireFinite("coupling_stiffness_N_per_m", d.coupling_stiffness_N_per_m, 0.0, kInfinity,
                ">= 0 N/m");
  RequireFinite("coupling_damping_Ns_per_m", d.coupling_damping_Ns_per_m, 0.0, kInfinity,
                ">= 0 N s/m");
  RequireInRange(d.workspace_offset_m.allFinite(), "workspace_offset_m",
                 d.workspace_offset_m.norm(), "finite");
  RequireFinite("max_stiffness_N_per_m", d.limits.max_stiffness_N_per_m, 0.0, kInfinity,
                ">= 0 N/m (0: unknown)");
  RequireFinite("max_damping_Ns_per_m", d.limits.max_damping_Ns_per_m, 0.0, kInfinity,
                ">= 0 N s/m (0: unknown)");
  RequireInRange(std::isfinite(d.plausible_radius_m) && d.plausible_radius_m > 0.0,
                 "plausible_radius_m", d.plausible_radius_m, "> 0 m, finite");
  RequireInRange(std::isfinite(d.plausible_speed_mps) && d.plausible_speed_mps > 0.0,
                 "plausible_speed_mps", d.plausible_speed_mps, "> 0 m/s, finite");
  RequireInRange(
      std::isfinite(d.plausible_angular_speed_radps) && d.plausible_angular_speed_radps > 0.0,
      "plausible_angular_speed_radps", d.plausible_angular_speed_radps, "> 0 rad/s, finite");
  if (r.passivity_control && d.coupling == Coupling::kNone) {
    throw Error(
        "parameter passivity_control = true needs a device port to observe: direct or virtual "
        "coupling (this model has none, the offline simulation's)");
  }
  if (d.coupling == Coupling::kDirect) {
    const std::string why = "direct coupling: the device renders the tool's contact law";
    RequireDisplayable("stiffness_N_per_m", c.stiffness_N_per_m, "max_stiffness_N_per_m",
                       d.limits.max_stiffness_N_per_m, "N/m", why);
    RequireDisplayable("damping_Ns_per_m", c.damping_Ns_per_m, "max_damping_Ns_per_m",
                       d.limits.max_damping_Ns_per_m, "N s/m", why);
  } else if (d.coupling == Coupling::kVirtual) {
    const std::string why = "virtual coupling: the device renders the coupling";
    RequireDisplayable("coupling_stiffness_N_per_m", d.coupling_stiffness_N_per_m,
                       "max_stiffness_N_per_m", d.limits.max_stiffness_N_per_m, "N/m", why);
    RequireDisplayable("coupling_damping_Ns_per_m", d.coupling_damping_Ns_per_m,
                       "max_damping_Ns_per_m", d.limits.max_damping_Ns_per_m, "N s/m", why);
  }
}

}  // namespace

void Configure(Model& model) {
  RequireFinite("timestep_s", model.timestep_s, limits::kMinTimestep_s, limits::kMaxTimestep_s,
                "0 < h <= " + text::FormatNumber(limits::kMaxTimestep_s) + " s (at least " +
                    text::FormatNumber(limits::kMinTimestep_s * 1e6) + " us)");
  RequireInRange(std::isfinite(model.timestep_s) && model.timestep_s > 0.0, "timestep_s",
                 model.timestep_s, "h > 0");
  RequireContact(model.contact);
  RequireRender(model);
  model.schedule = contact::MakeSchedule(model.timestep_s, model.render);
  RequireJointLimitRenderer(model);

  RequireDevice(model);
  RequireInRange(model.tool >= 0 && model.tool < static_cast<int>(model.bodies.size()), "tool",
                 model.tool, "an index of a free body");
  for (auto& b : model.bodies) {
    RequireInRange(std::isfinite(b.mass_kg) && b.mass_kg > 0.0, "mass_kg of body '" + b.name + "'",
                   b.mass_kg, "> 0 kg");
  }
  std::vector<std::string> warnings;
  SceneContactDefaults(model, warnings);
  ToolContactWarnings(model, warnings);
  if (!model.has_tool && model.device.coupling != Coupling::kNone) {
    throw Error("a device needs a tool; the scene is loaded with --tool none");
  }
  for (std::string& w : warnings) {
    // Configure may run again on the same model (serve sets the device's law): no repeats
    if (std::find(model.load_warnings.begin(), model.load_warnings.end(), w) ==
        model.load_warnings.end()) {
      model.load_warnings.push_back(std::move(w));
    }
  }
}

}  // namespace rigidtouch
