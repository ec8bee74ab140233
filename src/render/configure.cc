// Parameter validation (load-time error tier: throw with the parameter and its range).
#include <cmath>
#include <sstream>
#include <string>

#include "contact/schedule.h"
#include "io/text.h"
#include "render/limits.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

void Require(bool ok, const std::string& name, double value, const std::string& range) {
  if (ok) return;
  std::ostringstream msg;
  msg << "parameter " << name << " = " << value << " is out of range: valid " << range;
  throw Error(msg.str());
}

void RequireFinite(const std::string& name, double value, double lo, double hi,
                   const std::string& range) {
  Require(std::isfinite(value) && value >= lo && value <= hi, name, value, range);
}

constexpr double kInf = INFINITY;

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

}  // namespace

void Configure(Model& model) {
  RequireFinite("timestep_s", model.timestep_s, render::kMinTimestep_s, render::kMaxTimestep_s,
                "0 < h <= " + io::FormatNumber(render::kMaxTimestep_s) + " s (at least " +
                    io::FormatNumber(render::kMinTimestep_s * 1e6) + " us)");
  Require(std::isfinite(model.timestep_s) && model.timestep_s > 0.0, "timestep_s", model.timestep_s,
          "h > 0");
  const ContactParams& c = model.contact;
  RequireFinite("stiffness_N_per_m", c.stiffness_N_per_m, 0.0, kInf, "k >= 0 N/m, finite");
  RequireFinite("damping_Ns_per_m", c.damping_Ns_per_m, 0.0, kInf, "b >= 0 N s/m, finite");
  RequireFinite("scene_stiffness_N_per_m", c.scene_stiffness_N_per_m, 0.0, kInf,
                "k >= 0 N/m, finite");
  RequireFinite("scene_damping_Ns_per_m", c.scene_damping_Ns_per_m, 0.0, kInf,
                "b >= 0 N s/m, finite");
  RequireFinite("friction_static", c.friction_static, -1.0, kInf,
                ">= 0, or -1 for the MJCF geom friction");
  RequireFinite("friction_kinetic", c.friction_kinetic, -1.0, kInf,
                ">= 0, or -1 for the MJCF geom friction");
  if (c.friction_static >= 0.0 && c.friction_kinetic >= 0.0) {
    Require(c.friction_static >= c.friction_kinetic, "friction_static", c.friction_static,
            ">= friction_kinetic (" + std::to_string(c.friction_kinetic) + ")");
  }
  RequireFinite("tangential_ratio", c.tangential_ratio, 0.0, kInf, ">= 0");
  RequireFinite("onset_speed_mps", c.onset_speed_mps, 0.0, kInf, ">= 0 m/s");

  const RenderParams& r = model.render;
  RequireFinite("restitution", r.restitution, render::kMinRestitution, render::kMaxRestitution,
                io::FormatNumber(render::kMinRestitution) +
                    " <= e <= " + io::FormatNumber(render::kMaxRestitution) + " (Eq. 4)");
  if (r.renderer == RendererKind::kTrain) {
    const std::string window =
        "0 < t_c <= " + io::FormatNumber(render::kMaxCollisionWindow_s) + " s";
    RequireFinite("t_collision_s", r.t_collision_s, 0.0, render::kMaxCollisionWindow_s,
                  window + " (shorter than human reaction time, docs/method.md)");
    Require(r.t_collision_s > 0.0, "t_collision_s", r.t_collision_s, window);
    Require(std::isfinite(r.frequency_hz) && r.frequency_hz > 0.0, "frequency_hz", r.frequency_hz,
            "f > 0 Hz, within [1/t_c, 1/h] (Eq. 6-7)");
    if (r.restitution != render::kTrainRestitution) {
      std::ostringstream msg;
      msg << "parameter restitution = " << r.restitution
          << " is not allowed with the train renderer: the method requires perfectly plastic "
             "collisions (e = 0), the only post-collision velocity compatible with every "
             "intermediate velocity of the train (Eq. 8, docs/method.md)";
      throw Error(msg.str());
    }
  }
  model.schedule = contact::MakeSchedule(model.timestep_s, r);

  const DeviceParams& d = model.device;
  RequireFinite("max_force_N", d.max_force_N, 0.0, kInf, ">= 0 N (0: unlimited)");
  RequireFinite("coupling_stiffness_N_per_m", d.coupling_stiffness_N_per_m, 0.0, kInf, ">= 0 N/m");
  RequireFinite("coupling_damping_Ns_per_m", d.coupling_damping_Ns_per_m, 0.0, kInf, ">= 0 N s/m");
  Require(d.workspace_offset_m.allFinite(), "workspace_offset_m", d.workspace_offset_m.norm(),
          "finite");
  RequireFinite("max_stiffness_N_per_m", d.max_stiffness_N_per_m, 0.0, kInf,
                ">= 0 N/m (0: unknown)");
  RequireFinite("max_damping_Ns_per_m", d.max_damping_Ns_per_m, 0.0, kInf,
                ">= 0 N s/m (0: unknown)");
  Require(std::isfinite(d.plausible_radius_m) && d.plausible_radius_m > 0.0, "plausible_radius_m",
          d.plausible_radius_m, "> 0 m, finite");
  Require(std::isfinite(d.plausible_speed_mps) && d.plausible_speed_mps > 0.0,
          "plausible_speed_mps", d.plausible_speed_mps, "> 0 m/s, finite");
  Require(std::isfinite(d.plausible_angular_speed_radps) && d.plausible_angular_speed_radps > 0.0,
          "plausible_angular_speed_radps", d.plausible_angular_speed_radps, "> 0 rad/s, finite");
  if (d.coupling == Coupling::kDirect) {
    const std::string why = "direct coupling: the device renders the tool's contact law";
    RequireDisplayable("stiffness_N_per_m", c.stiffness_N_per_m, "max_stiffness_N_per_m",
                       d.max_stiffness_N_per_m, "N/m", why);
    RequireDisplayable("damping_Ns_per_m", c.damping_Ns_per_m, "max_damping_Ns_per_m",
                       d.max_damping_Ns_per_m, "N s/m", why);
  } else if (d.coupling == Coupling::kVirtual) {
    const std::string why = "virtual coupling: the device renders the coupling";
    RequireDisplayable("coupling_stiffness_N_per_m", d.coupling_stiffness_N_per_m,
                       "max_stiffness_N_per_m", d.max_stiffness_N_per_m, "N/m", why);
    RequireDisplayable("coupling_damping_Ns_per_m", d.coupling_damping_Ns_per_m,
                       "max_damping_Ns_per_m", d.max_damping_Ns_per_m, "N s/m", why);
  }
  Require(model.tool >= 0 && model.tool < static_cast<int>(model.bodies.size()), "tool", model.tool,
          "an index of a free body");
  for (auto& b : model.bodies) {
    Require(std::isfinite(b.mass_kg) && b.mass_kg > 0.0, "mass_kg of body '" + b.name + "'",
            b.mass_kg, "> 0 kg");
  }
}

}  // namespace rigidtouch
