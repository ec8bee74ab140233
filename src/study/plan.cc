#include "study/plan.h"

#include <numeric>
#include <utility>

#include "study/random.h"

namespace rigidtouch::study {

namespace {

// stream tags keep the random decisions of a session independent of each other
constexpr std::uint64_t kTestOrderStream = 1;
constexpr std::uint64_t kSeriesOrderStream = 2;

template <typename T>
void Shuffle(std::vector<T>& items, Rng& rng) {
  // Fisher-Yates, from the back
  for (std::size_t i = items.size(); i > 1; --i) {
    const std::size_t j = rng.Below(i);
    std::swap(items[i - 1], items[j]);
  }
}

std::vector<int> SeriesConditions(const StudyTest& test, SeriesOrder order, Rng& rng) {
  const int k = static_cast<int>(test.conditions.size());
  std::vector<int> conditions(test.series);
  if (order == SeriesOrder::kIndependent) {
    // two conditions: the coin of earlier versions, so their logs keep their plans
    for (int& c : conditions) {
      c = k == 2 ? (rng.Bernoulli(0.5) ? 1 : 0) : static_cast<int>(rng.Below(k));
    }
    return conditions;
  }
  // series / k of each; the remainder r < k one each to r conditions drawn without replacement
  // (two conditions: a coin gives condition 1 the odd series, as earlier versions did)
  std::vector<int> count(k, test.series / k);
  const int remainder = test.series % k;
  if (k == 2) {
    if (remainder == 1) ++count[rng.Bernoulli(0.5) ? 1 : 0];
  } else if (remainder > 0) {
    std::vector<int> order(k);
    std::iota(order.begin(), order.end(), 0);
    Shuffle(order, rng);
    for (int i = 0; i < remainder; ++i) ++count[order[i]];
  }
  // filled from the last condition down, as the two-condition plan always was (ones first)
  int i = 0;
  for (int c = k - 1; c >= 0; --c) {
    for (int n = 0; n < count[c]; ++n) conditions[i++] = c;
  }
  Shuffle(conditions, rng);
  return conditions;
}

}  // namespace

std::vector<Step> MakePlan(const Protocol& protocol, std::uint64_t seed) {
  std::vector<int> test_order(protocol.tests.size());
  std::iota(test_order.begin(), test_order.end(), 0);
  if (protocol.randomization.test_order == TestOrder::kShuffled) {
    Rng rng(DeriveSeed(seed, {kTestOrderStream}));
    Shuffle(test_order, rng);
  }

  std::vector<Step> plan;
  for (std::size_t position = 0; position < test_order.size(); ++position) {
    const int t = test_order[position];
    const StudyTest& test = protocol.tests[t];
    // appends the next step of this test
    auto add = [&](StepKind kind, int series, int condition, int taps) {
      Step step;
      step.kind = kind;
      step.index = static_cast<int>(plan.size());
      step.test = t;
      step.test_position = static_cast<int>(position);
      step.series = series;
      step.condition = condition;
      step.taps = taps;
      plan.push_back(step);
    };
    for (int c = 0; c < static_cast<int>(test.conditions.size()); ++c) {
      add(StepKind::kFamiliarization, /*series=*/-1, c, test.familiarization_taps);
    }
    // each test's series order has its own stream: reordering tests does not change it
    Rng rng(DeriveSeed(seed, {kSeriesOrderStream, static_cast<std::uint64_t>(t)}));
    const std::vector<int> conditions =
        SeriesConditions(test, protocol.randomization.series_order, rng);
    for (int s = 0; s < test.series; ++s) {
      add(StepKind::kSeries, s, conditions[s], test.taps_per_series);
    }
  }
  return plan;
}

}  // namespace rigidtouch::study
