// Renderer specs of `tap --compare`: "name[:material]" -> the renderer settings of one entry.
// One parser for every spec, so a new renderer or material is added in one place.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigidtouch/model.h"

namespace rigidtouch::analysis {

/// One renderer to compare.
struct RendererSpec {
  std::string name;   // the spec as written, e.g. "train" or "wall1"; names its output files
  std::string label;  // for tables and figure titles, e.g. "wall 1: train 250 Hz"
  RendererKind renderer = RendererKind::kPenalty;
  /// Set when the spec fixes every render parameter (the method's walls: e, t_c and f); unset,
  /// the entry takes them from the flags, the config or the defaults like `--renderer` does.
  std::optional<RenderParams> render;
  /// The material after the colon (event:wood, train:wood; io::ParseMaterial): the event
  /// renderer's transient, or a passive material train's frequency, window and shares.
  std::optional<Material> material;
};

/// Parses "name[:material]". Names: penalty, impulse, train, event (the renderers), wall0, wall1,
/// wall2 (the method's walls, WallRenderParams). A material (a preset name or FILE.json) goes
/// with event and train only. Throws Error naming the spec and the valid names for an unknown
/// name, and the material's error for an unknown material.
RendererSpec ParseRendererSpec(std::string_view spec);

/// Parses a comma-separated list of specs (ParseRendererSpec each). Throws Error for an empty
/// list, an empty entry or an entry given twice.
std::vector<RendererSpec> ParseRendererList(std::string_view list);

/// The set `--compare-walls` runs: pure penalty, then walls 0, 1 and 2.
inline constexpr std::string_view kWallsSet = "penalty,wall0,wall1,wall2";

}  // namespace rigidtouch::analysis
