// `material fit` as a function, for the command line and Python's rigidtouch.fit_material: one
// place that turns a device and a rate into the fit's options, so both give the same material.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/material_fit.h"
#include "io/tap_recording.h"

namespace rigidtouch::cli {

/// What `material fit` takes besides the recordings (its flags).
struct MaterialFitRequest {
  std::string name = "fitted";
  std::string device = "touch";    // a preset or a device spec FILE.json
  double rate_hz = 1000.0;         // the haptic rate: its Nyquist frequency is the display limit
  double effective_mass_kg = 0.0;  // 0: the device's apparent mass plus the hand's 0.554 kg
};

/// Fits the recordings; `fit` gets the fit, and the return value is the material file's JSON
/// (checked to be readable by io::ReadMaterialJson). Throws Error as analysis::FitMaterial.
nlohmann::json FitMaterialFile(const std::vector<io::TapRecording>& recordings,
                               const MaterialFitRequest& request, analysis::MaterialFit& fit);

}  // namespace rigidtouch::cli
