// rigidtouch.fit_material: `material fit` on numpy arrays (docs/materials.md, docs/python.md).
// The arrays become the recording the CSV reader would build, then the CLI's own function fits
// them, so Python and the command line give the same material.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/material_fit.h"
#include "arrays.h"
#include "io/tap_recording.h"
#include "rigidtouch/material_run.h"

namespace rigidtouch::python {
namespace {

using py::literals::operator""_a;

// one column of a tap: a 1-D array of `n` finite numbers (n = the time column's length; -1: any)
std::vector<double> MaterialColumn(const py::dict& tap, const std::string& key, long n,
                                   const std::string& where) {
  const auto a =
      py::cast<py::array_t<double, py::array::c_style | py::array::forcecast>>(tap[key.c_str()]);
  if (a.ndim() != 1) throw Error(where + ": " + key + " must be a 1-D array");
  if (n >= 0 && a.shape(0) != n) {
    throw Error(where + ": " + key + " has " + std::to_string(a.shape(0)) + " values; time_s has " +
                std::to_string(n));
  }
  std::vector<double> v(a.data(), a.data() + a.shape(0));
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw Error(where + ": " + key + "[" + std::to_string(i) + "] is not a finite number");
    }
  }
  return v;
}

// the taps as the reader would build them: `line` is the sample's index + 1
io::TapRecording MaterialRecording(const py::list& taps, const std::string& name) {
  io::TapRecording r;
  r.path = name;
  bool have_quantity = false;
  for (std::size_t k = 0; k < taps.size(); ++k) {
    const py::dict tap = py::cast<py::dict>(taps[k]);
    const std::string where = name + ": taps[" + std::to_string(k) + "]";
    for (const auto& [key, value] : tap) {
      const std::string column = py::cast<std::string>(key);
      const auto& valid = io::TapRecordingColumns();
      if (std::find(valid.begin(), valid.end(), column) == valid.end() || column == "tap") {
        throw Error(where + ": unknown column " + column +
                    "; valid: time_s, acceleration_mps2 or " +
                    "force_N, velocity_mps or position_m, impact_speed_mps");
      }
    }
    if (!tap.contains("time_s")) throw Error(where + ": time_s is missing");
    if (tap.contains("acceleration_mps2") == tap.contains("force_N")) {
      throw Error(where + ": give exactly one of acceleration_mps2 and force_N");
    }
    const io::TapQuantity q =
        tap.contains("force_N") ? io::TapQuantity::kForce : io::TapQuantity::kAcceleration;
    if (have_quantity && q != r.quantity) throw Error(where + ": one quantity for all taps");
    r.quantity = q;
    have_quantity = true;
    io::RecordedTap t;
    t.tap = static_cast<int>(k);
    t.time_s = MaterialColumn(tap, "time_s", -1, where);
    const auto n = static_cast<long>(t.time_s.size());
    if (n < 2) throw Error(where + ": a tap needs at least two samples");
    for (long i = 1; i < n; ++i) {
      if (!(t.time_s[i] > t.time_s[i - 1])) {
        throw Error(where + ": time_s[" + std::to_string(i) + "] is not after the one before");
      }
    }
    t.signal = MaterialColumn(tap, std::string(io::TapQuantityColumn(q)), n, where);
    for (const char* key : {"velocity_mps", "position_m", "impact_speed_mps"}) {
      if (!tap.contains(key)) continue;
      std::vector<double>& out = std::string(key) == "velocity_mps" ? t.velocity_mps
                                 : std::string(key) == "position_m" ? t.position_m
                                                                    : t.impact_speed_mps;
      if (std::string(key) == "impact_speed_mps" && py::isinstance<py::float_>(tap[key])) {
        out.assign(t.time_s.size(), py::cast<double>(tap[key]));
      } else {
        out = MaterialColumn(tap, key, n, where);
      }
    }
    for (long i = 0; i < n; ++i) t.line.push_back(static_cast<int>(i + 1));
    r.taps.push_back(std::move(t));
  }
  if (r.taps.empty()) throw Error(name + ": no taps");
  return r;
}

py::object FitMaterial(const py::list& taps, const std::string& name, const std::string& device,
                       double rate_hz, double effective_mass_kg) {
  cli::MaterialFitRequest request;
  request.name = name;
  request.device = device;
  request.rate_hz = rate_hz;
  request.effective_mass_kg = effective_mass_kg;
  analysis::MaterialFit fit;
  const nlohmann::json file = cli::FitMaterialFile({MaterialRecording(taps, name)}, request, fit);
  return py::module_::import("json").attr("loads")(file.dump());
}

}  // namespace

void DefineMaterial(py::module_& m) {
  m.def("_fit_material", &FitMaterial, "taps"_a, py::kw_only(), "name"_a = "fitted",
        "device"_a = "touch", "rate_hz"_a = 1000.0, "effective_mass_kg"_a = 0.0,
        "material fit on arrays: returns the material file's content as a dict");
}

}  // namespace rigidtouch::python
