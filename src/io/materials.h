// Materials for the event renderer's contact transient (Material in rigidtouch/model.h): presets
// and JSON files, read by one function for every subcommand that takes --material.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "io/strict_json.h"
#include "rigidtouch/model.h"

namespace rigidtouch::io {

/// The presets, in a fixed order: rubber, wood, aluminium. Their A, B and f are assumptions in
/// the range of the decaying-sinusoid fits of Okamura, Cutkosky and Dennerlein 2001 (the
/// published tables could not be consulted; docs/renderers.md says so).
std::span<const Material> MaterialPresets();

/// Reads a JSON material: {"name": optional (default the file's stem), "amplitude_Ns_per_m",
/// "decay_per_s", "frequency_hz"}, all three required; optional "amplitude_quantity" ("force",
/// the default, or "acceleration" with "amplitude_mps2_per_mps" and "effective_mass_kg", whose
/// product must be amplitude_Ns_per_m to 1e-6; both are kept in the Material, so a device can
/// convert with its own mass: MaterialOnDevice) and "fit" (`material fit`'s record: its field
/// names are checked, its values not used; docs/materials.md). Throws Error "FILE: FIELD: ..."
/// naming the field.
Material ReadMaterial(const std::string& path);

/// Reads a material from a parsed JSON object, the way ReadMaterial reads a file's: the fields
/// above, `name` defaulting to `default_name`. `path` is the object's field path in `source`
/// ("" for a whole file); errors read "SOURCE: PATH.FIELD: ...". One reader for material files and
/// materials written inline (a study protocol's canonical form).
Material ReadMaterialJson(const io::JsonSource& source, const nlohmann::json& value,
                          const std::string& path, const std::string& default_name);

/// The preset `material` is, or nullptr: same name and the same A, B and f.
const Material* FindPreset(const Material& material);

/// `text` is a preset name or a path ending in ".json". Anything else is an Error listing the
/// presets and the file form.
Material ParseMaterial(std::string_view text);

/// A passive material train's frequency and window (docs/renderers.md): f the material's, the
/// window three decay time constants (the envelope at 5 %, ln 20 / B), at most the method's
/// 100 ms and at least one period 1 / f.
struct MaterialTrainParams {
  double frequency_hz = 0.0;
  double t_collision_s = 0.0;
};
MaterialTrainParams MaterialTrain(const Material& material);

/// Masses within this relative difference are the same (no conversion note): a material file
/// holds the fit's mass as written, to the last bit.
inline constexpr double kSameMassRelative = 1e-9;

/// `material` as rendered on a device whose effective mass is `effective_mass_kg` [kg] (the
/// device's apparent mass plus the hand's: device::EffectiveMassKg, the mass `material fit`
/// converts with): an acceleration material's A becomes amplitude_mps2_per_mps x
/// effective_mass_kg and its effective_mass_kg that mass; a force material is returned as it is.
/// Throws Error for a mass that is not > 0 and finite (acceleration materials only).
Material MaterialOnDevice(const Material& material, double effective_mass_kg);

/// The note for the user when `rendered` (MaterialOnDevice of `material`) has another mass than
/// the file's (relative difference above kSameMassRelative): the material's name, both masses, the
/// rendered amplitude, `device` naming the device. Empty when nothing was converted.
std::string MaterialDeviceNote(const Material& material, const Material& rendered,
                               const std::string& device);

/// Converts `render.material` for a device (MaterialOnDevice) and returns the note
/// (MaterialDeviceNote) when the event renderer plays a converted amplitude, else "". One call
/// for every path where a material meets a device: tap, serve, view, study.
std::string RenderMaterialOnDevice(RenderParams& render, double effective_mass_kg,
                                   const std::string& device);

/// Gives `render` the material `material` as `--material` does: the event renderer's transient,
/// or, for the train renderer, a passive material train (its f and t_c from MaterialTrain). One
/// place for the CLI, `tap --compare` and study conditions, so all render a material alike.
void ApplyMaterial(RenderParams& render, const Material& material);

}  // namespace rigidtouch::io
