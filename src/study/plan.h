// The plan of one session: every familiarization and series step in the order they happen. It is
// a pure function of the protocol and the session seed, so an interrupted session resumes with
// exactly the remaining steps of the original order.
#pragma once

#include <cstdint>
#include <vector>

#include "study/protocol.h"

namespace rigidtouch::study {

/// What one step of a session does.
enum class StepKind {
  kFamiliarization,  ///< the participant taps a named wall
  kSeries,           ///< the participant taps an unnamed wall, then names it
};

/// One step of a session plan.
struct Step {
  StepKind kind = StepKind::kFamiliarization;
  int index = 0;          ///< position in the plan, 0-based
  int test = 0;           ///< index into Protocol::tests
  int test_position = 0;  ///< position of the test in this session's order, 0-based
  int series = -1;        ///< series number within the test (0-based); -1 for familiarization
  int condition = 0;      ///< 0 to k - 1: which of the test's k conditions is rendered
  int taps = 0;           ///< taps the participant makes in this step
};

/// Builds the plan: tests in the protocol's order (or a seeded permutation); per test the
/// familiarization of each condition in the test's order, then the series in seeded random order.
std::vector<Step> MakePlan(const Protocol& protocol, std::uint64_t seed);

}  // namespace rigidtouch::study
