// A device as the user names it: a preset (presets.h) or a JSON device spec file. One parser for
// every subcommand that takes --device (tap, serve, study), so the word means the same everywhere.
#pragma once

#include <string>
#include <string_view>

#include "device/simulated_device.h"
#include "rigidtouch/device.h"

namespace rigidtouch::device {

/// Everything rigidtouch needs to know about a device: what it can display (limits: max force,
/// max closed-loop stiffness and damping; 0 means none or unknown) and how it senses and moves
/// (apparent mass, encoder resolution, velocity filter, delay), which the simulated device uses
/// and a real device's model needs (the tool's mass under direct coupling).
struct DeviceSpec {
  DeviceLimits limits;
  DeviceModelParams model;  // tick_rate_hz and substeps are the run's, not the device's
  std::string file;         // the JSON file it was read from; empty for a preset
};

/// The mass the device's force moves at the handle [kg]: the device's apparent mass plus the
/// hand's (HandParams, 0.554 kg by default). `material fit` converts a recorded acceleration to
/// a force with it, and every device renders an acceleration material with it
/// (io::MaterialOnDevice, docs/materials.md "From acceleration to force").
double EffectiveMassKg(const DeviceModelParams& model, const HandParams& hand = HandParams{});

/// The spec of the preset `name`: the preset's limits, and the sensing and inertia of
/// DeviceModelParams' defaults (the PHANToM Omni's), except `ideal`: no force limit, a 1 um
/// encoder, no delay. Throws Error listing the presets for an unknown name.
DeviceSpec PresetSpec(std::string_view name);

/// Reads a JSON device spec. Fields (all required except "name", which defaults to the file's
/// stem): max_force_N (0: no limit), max_stiffness_N_per_m and max_damping_Ns_per_m (0: unknown),
/// apparent_mass_kg, encoder_resolution_m (0: no quantization), velocity_filter_hz (cutoff of
/// the first-order low-pass on the finite-difference velocity), delay_ticks (0 or 1). Throws
/// Error "FILE: FIELD: ..." naming the field for a missing, unknown, mistyped or out-of-range one.
DeviceSpec ReadDeviceSpec(const std::string& path);

/// `text` is a preset name or a path ending in ".json": PresetSpec or ReadDeviceSpec. Anything
/// else is an Error listing the presets and the file form.
DeviceSpec ParseDeviceSpec(std::string_view text);

/// The device-spec syntax for --help: "touch | omni | ... | ideal | FILE.json".
std::string DeviceSpecHelp();

}  // namespace rigidtouch::device
