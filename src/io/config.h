// rigidtouch parameters from a JSON config file, kept apart from the MJCF scene
// (docs/architecture.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "base/names.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::io {

/// Reads `path` (a JSON object) into `options`; absent fields keep their values. Keys: "tool",
/// "timestep_s", "contact" {...}, "render" {...}, "device" {...}, each field named as in
/// ContactParams / RenderParams / DeviceParams. Read with the strict reader (io/strict_json.h):
/// throws Error naming the file and the field's path ("contact.stiffness_N_per_m") for an unknown
/// field (listing the valid ones), a wrong type or a non-finite number, and naming the file when
/// it is missing, empty or not JSON (with line and column). Ranges are checked by Configure.
/// Returns the fields the file gives, as paths ("tool", "contact.stiffness_N_per_m"), so a caller
/// can tell a value the user wrote from a default. "device" may also name the connection to the
/// device, "connect": sim, udp://HOST:PORT or replay:LOG (a relative LOG is taken from the
/// file's folder); it is checked (any other value throws Error naming the file and
/// "device.connect") and stored in `*connect` when `connect` is given.
std::vector<std::string> ApplyConfigFile(const std::string& path, LoadOptions& options,
                                         std::optional<std::string>* connect = nullptr);

/// Parses a renderer name (text::RendererNames); throws Error listing them.
RendererKind ParseRenderer(const std::string& name);

/// Parses a coupling name (text::CouplingNames); throws Error listing them.
Coupling ParseCoupling(const std::string& name);

}  // namespace rigidtouch::io
