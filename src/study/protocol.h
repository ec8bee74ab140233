// Perception-study protocols: which walls (renderer configurations) each test compares, how many
// taps and series, how the order is randomized and what the participant is told. Protocols are
// JSON files (docs/study.md); they are parsed once, validated with messages naming the file, the
// field and the valid range, and identified by a hash of their canonical JSON.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "rigidtouch/model.h"

namespace rigidtouch::study {

/// One rendered wall: a renderer configuration and the label participants know it by. Optional
/// fields left empty mean "the engine's default" and are omitted from the canonical JSON.
struct Condition {
  std::string label;                               ///< e.g. "wall 1"; unique within the protocol
  RendererKind renderer = RendererKind::kPenalty;  ///< rendering method (text::RendererName)
  double restitution = 0.0;                  ///< e in Eq. 4/5; impulse: [0, 1], train: 0 (Eq. 8)
  double t_collision_s = 0.0;                ///< train only: window t_c in (0, 0.1] s (II.a)
  double frequency_hz = 0.0;                 ///< train only: f >= 1 / t_c (II.b, Eq. 7)
  std::optional<double> stiffness_N_per_m;   ///< penalty spring stiffness, > 0
  std::optional<double> damping_Ns_per_m;    ///< penalty damping, >= 0
  std::optional<std::string> scene;          ///< MJCF scene, as written in the protocol
  std::optional<std::string> device;         ///< device preset name, e.g. "touch"
  std::optional<double> approach_speed_mps;  ///< hand approach speed for simulated taps, > 0
  /// event (required) and train only: a material as `--material` takes it (a preset name or a
  /// JSON material file, io::ParseMaterial), or the same fields written inline; a material
  /// train takes its f and t_c from it (io::ApplyMaterial). Read when the protocol is parsed:
  /// the canonical JSON holds a preset's name, or else the material's own fields (an
  /// acceleration material's with its acceleration and mass: each device converts it with its
  /// own, io::MaterialOnDevice), so the hash covers what is rendered and a log does not need the
  /// file
  std::optional<Material> material;
  bool passivity_control = false;  ///< the passivity observer and controller, as the CLI flag
  /// an articulated scene's joint limits: penalty, impulse or train, as --joint-limit-renderer
  std::optional<RendererKind> joint_limit_renderer;
  /// what the simulated taps aim at, as `tap --wall-geom` (a static plane or box, or a link's
  /// geom) or `--wall-point X Y Z --wall-normal X Y Z`; default the scene's wall
  std::optional<std::string> wall_geom;
  std::optional<Vec3> wall_point_m;
  std::optional<Vec3> wall_normal;

  /// The render parameters of this condition, as `rigidtouch tap --renderer R [--restitution e]
  /// [--t-collision t --frequency f] [--material M] [--passivity-control]` gives them.
  RenderParams ToRenderParams() const;

  /// The canonical JSON of the renderer configuration (the object stored in the protocol's
  /// "conditions" map, without the label). Logs record it as the condition rendered.
  nlohmann::json ToJson() const;
};

/// Fewest and most conditions one test compares.
inline constexpr int kMinTestConditions = 2;
inline constexpr int kMaxTestConditions = 8;

/// One identification test among 2 to 8 conditions (two: the method's discrimination tests).
struct StudyTest {
  std::string name;               ///< e.g. "test 1"; unique within the protocol
  std::vector<int> conditions;    ///< indices into Protocol::conditions, distinct, 2 to 8
  std::vector<std::string> keys;  ///< what the participant types, one per condition, distinct
  std::string instructions;       ///< shown before the test's familiarization
  int familiarization_taps = 3;   ///< taps on each condition before the series
  int series = 20;                ///< number of series (each renders one condition)
  int taps_per_series = 3;        ///< taps in each series
};

/// How the series of each test are assigned to conditions.
enum class SeriesOrder {
  kBalanced,     ///< series / k of each condition, the remainder one each to conditions drawn
                 ///< at random (k = 2: a coin flip gives condition 1 the odd one), shuffled
  kIndependent,  ///< a fair draw among the k conditions per series (k = 2: a fair coin)
};

/// Order in which the tests are run.
enum class TestOrder {
  kFixed,     ///< as listed in the protocol
  kShuffled,  ///< a permutation drawn from the session seed
};

/// Randomization settings. The order of a session is a pure function of the session seed.
struct Randomization {
  SeriesOrder series_order = SeriesOrder::kBalanced;
  TestOrder test_order = TestOrder::kFixed;
  std::optional<std::uint64_t> seed;  ///< used when the command line gives none
};

/// A whole study protocol.
struct Protocol {
  std::string name;                   ///< short identifier, e.g. "walls"
  std::string description;            ///< free text for the experimenter
  std::string instructions;           ///< shown to the participant at the start of a session
  std::vector<Condition> conditions;  ///< every wall the tests refer to
  std::vector<StudyTest> tests;       ///< at least one
  Randomization randomization;

  /// Canonical JSON: every default filled in, per-test values resolved, keys sorted, no
  /// whitespace when dumped. Two files that mean the same protocol have the same canonical JSON.
  nlohmann::json ToJson() const;
};

/// Builds a protocol from parsed JSON. `source` names the input (usually the file path) in error
/// messages. Throws rigidtouch::Error naming the field and the valid values on any problem.
Protocol ParseProtocol(const nlohmann::json& document, std::string_view source);

/// Reads and parses a protocol file. Throws rigidtouch::Error if the file cannot be read, is not
/// JSON, or is not a valid protocol.
Protocol LoadProtocol(const std::string& path);

/// FNV-1a 64-bit hash of a byte string.
std::uint64_t Fnv1a64(std::string_view bytes);

/// Identity of a protocol: "fnv1a64:" followed by 16 lowercase hex digits of the FNV-1a 64 hash of
/// `protocol.ToJson().dump()` (compact, sorted keys, UTF-8).
std::string ProtocolHash(const Protocol& protocol);

}  // namespace rigidtouch::study
