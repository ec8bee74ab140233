// libFuzzer: a tap recording's CSV reader (io::ParseTapRecording) on arbitrary bytes, and the
// material fit on whatever it accepts. Bad input must be a rigidtouch::Error, never a crash, a
// leak or another exception; a fit that returns has a finite material, and the file `material fit`
// would write from it is read back or refused with an Error (the CLI refuses to write it then).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "analysis/material_fit.h"
#include "io/materials.h"
#include "io/strict_json.h"
#include "io/tap_recording.h"
#include "rigidtouch/types.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  rigidtouch::io::TapRecording recording;
  try {
    recording = rigidtouch::io::ParseTapRecording(text, "fuzz.csv");
  } catch (const rigidtouch::Error&) {
    return 0;
  }
  rigidtouch::analysis::MaterialFitOptions options;
  options.effective_mass_kg = 0.5;
  options.display_limit_hz = 500.0;
  options.max_force_N = 10.0;
  try {
    const rigidtouch::analysis::MaterialFit fit = rigidtouch::analysis::FitMaterial(
        std::span<const rigidtouch::io::TapRecording>(&recording, 1), options);
    const rigidtouch::Material& m = fit.material;
    if (!std::isfinite(m.amplitude_Ns_per_m) || !std::isfinite(m.decay_per_s) ||
        !std::isfinite(m.frequency_hz)) {
      __builtin_trap();
    }
    rigidtouch::io::ReadMaterialJson(rigidtouch::io::JsonSource("fuzz.json"),
                                     rigidtouch::analysis::MaterialFileJson(fit), "", "fitted");
  } catch (const rigidtouch::Error&) {
  }
  return 0;
}
