// rigidtouch parameters from a JSON config file, kept apart from the MJCF scene (DESIGN.md).
#pragma once

#include <string>

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::io {

/// Reads `path` (a JSON object) into `options`. Keys: "tool", "timestep_s", "contact" {...},
/// "render" {...}, "device" {...}, each field named as in ContactParams / RenderParams /
/// DeviceParams. Throws Error naming the file and the unknown key (listing the valid ones) or the
/// field with a wrong type.
void ApplyConfigFile(const std::string& path, LoadOptions& options);

/// Parses a renderer name: "penalty", "impulse" or "train"; throws Error listing them.
RendererKind ParseRenderer(const std::string& name);

/// The name of a renderer.
const char* RendererName(RendererKind kind);

/// Parses a coupling name: "none", "direct" or "virtual"; throws Error listing them.
Coupling ParseCoupling(const std::string& name);

}  // namespace rigidtouch::io
