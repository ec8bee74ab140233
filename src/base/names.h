// The names of the renderers and couplings (public enums of rigidtouch/model.h), in one table
// each: the engine's messages, the config reader, the tool's flags and outputs all print them so.
#pragma once

#include <string>
#include <vector>

#include "rigidtouch/model.h"

namespace rigidtouch::text {

/// The renderer names in enum order: "penalty", "impulse", "train", "event".
const std::vector<std::string>& RendererNames();

/// The name of a renderer ("unknown" for a value outside the enum).
const char* RendererName(RendererKind kind);

/// The coupling names in enum order: "none", "direct", "virtual".
const std::vector<std::string>& CouplingNames();

/// The name of a coupling ("unknown" for a value outside the enum).
const char* CouplingName(Coupling coupling);

}  // namespace rigidtouch::text
