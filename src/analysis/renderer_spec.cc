#include "analysis/renderer_spec.h"

#include <algorithm>

#include "analysis/tap_experiment.h"
#include "io/materials.h"
#include "rigidtouch/types.h"

namespace rigidtouch::analysis {

namespace {

constexpr const char* kValidNames = "penalty, impulse, train, event, wall0, wall1, wall2";

std::string Quote(std::string_view s) {
  return "'" + std::string(s) + "'";
}

}  // namespace

RendererSpec ParseRendererSpec(std::string_view spec) {
  const std::size_t colon = spec.find(':');
  const std::string_view name = spec.substr(0, colon);
  RendererSpec r;
  r.name = std::string(spec);
  if (name == "penalty") {
    r.renderer = RendererKind::kPenalty;
    r.label = "penalty (no impulses)";
  } else if (name == "impulse") {
    r.renderer = RendererKind::kImpulse;
    r.label = "single impulse";
  } else if (name == "train") {
    r.renderer = RendererKind::kTrain;
    r.label = "impulse train";
  } else if (name == "event") {
    r.renderer = RendererKind::kEvent;
    r.label = "event-based transient";
  } else if (name.size() == 5 && name.substr(0, 4) == "wall" && name[4] >= '0' && name[4] <= '2') {
    const int wall = name[4] - '0';
    r.render = WallRenderParams(wall);
    r.renderer = r.render->renderer;
    const char* labels[] = {"wall 0: single impulse", "wall 1: train 250 Hz",
                            "wall 2: train 50 Hz"};
    r.label = labels[wall];
  } else {
    throw Error("unknown renderer " + Quote(name) + " in " + Quote(spec) +
                "; valid names: " + kValidNames + " (as name or name:material)");
  }
  if (colon != std::string_view::npos) {
    if (r.renderer != RendererKind::kEvent && r.renderer != RendererKind::kTrain) {
      throw Error("a material goes with event or train, not with " + Quote(name) + " in " +
                  Quote(spec));
    }
    r.material = io::ParseMaterial(spec.substr(colon + 1));
    r.label =
        (r.renderer == RendererKind::kEvent ? "event-based transient: " : "material train: ") +
        r.material->name;
  }
  return r;
}

std::vector<RendererSpec> ParseRendererList(std::string_view list) {
  std::vector<RendererSpec> specs;
  if (list.empty()) throw Error("the renderer list is empty; e.g. penalty,impulse,train");
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = list.find(',', begin);
    const std::string_view entry = list.substr(
        begin, comma == std::string_view::npos ? std::string_view::npos : comma - begin);
    if (entry.empty()) {
      throw Error("empty entry in the renderer list " + Quote(list) +
                  "; separate names by single commas, e.g. penalty,impulse,train");
    }
    RendererSpec spec = ParseRendererSpec(entry);
    if (std::any_of(specs.begin(), specs.end(),
                    [&spec](const RendererSpec& s) { return s.name == spec.name; })) {
      throw Error("renderer " + Quote(spec.name) + " is given twice in " + Quote(list));
    }
    specs.push_back(std::move(spec));
    if (comma == std::string_view::npos) break;
    begin = comma + 1;
  }
  return specs;
}

}  // namespace rigidtouch::analysis
