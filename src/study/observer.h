// Simulated participants: a perceptual observer that hears nothing and sees nothing, and decides
// from the force its hand feels (TapPercept). docs/study.md gives every parameter with its source.
//
// Each tap is mapped to a point in a 4-dimensional perceptual space whose unit on every axis is
// one just-noticeable difference (JND):
//   onset     20 log10(peak force / 1 N) / intensity JND
//   P level   sensation level of the Pacinian channel (dB above threshold) / intensity JND
//   NP level  sensation level of the non-Pacinian (NP I) channel / intensity JND
//   pitch     salience * ln(dominant frequency / P best frequency) / ln(1 + Weber fraction)
// Internal noise adds an independent unit normal to every axis of every tap. The observer keeps a
// memory template of each wall from the familiarization taps (averaged, plus encoding noise, plus
// a random-walk drift per series: trace memory, Durlach & Braida 1969), averages the taps of a
// series and names the wall whose template is nearer. It lapses (guesses) with a small
// probability and can hold the labels swapped.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/plan.h"
#include "study/protocol.h"
#include "study/session.h"
#include "study/stimulus.h"

namespace rigidtouch::study {

/// Parameters of the simulated observer. Defaults and sources: docs/study.md.
struct ObserverParams {
  double intensity_jnd_dB = 2.3;                        ///< amplitude discrimination threshold
  double frequency_weber_fraction = 0.2;                ///< frequency discrimination Weber fraction
  double pacinian_best_frequency_hz = 250.0;            ///< P channel's most sensitive frequency
  double pacinian_low_slope_dB_per_octave = 12.0;       ///< P sensitivity loss below it
  double pacinian_high_slope_dB_per_octave = 12.0;      ///< P sensitivity loss above it
  double non_pacinian_corner_hz = 40.0;                 ///< NP I flat below, crossing P here
  double non_pacinian_high_slope_dB_per_octave = 12.0;  ///< NP I sensitivity loss above corner
  double vibration_threshold_rms_N = 1e-3;  ///< P detection threshold at its best frequency [N]
  double pitch_salience_dB = 10.0;          ///< sensation level at which pitch is fully available
  double onset_floor_N = 0.01;              ///< onset forces below this feel alike [N]
  double memory_encoding_sd_jnd = 0.5;      ///< template noise at familiarization [JND]
  double memory_drift_sd_jnd_per_series = 0.25;  ///< template random walk per series [JND]
  double label_swap_probability = 0.0;  ///< chance that a participant holds a test's labels swapped
  double lapse_rate = 0.02;             ///< chance of guessing a series regardless of the stimulus
  double individual_jnd_log_sd = 0.2;   ///< SD across participants of ln(JND scale factor)

  /// All parameters as a JSON object (field names as above).
  nlohmann::json ToJson() const;
};

/// Reads observer parameters from a JSON object with the strict reader (io/strict_json.h); absent
/// fields keep their defaults. `source` names the input in errors. Throws rigidtouch::Error naming
/// an unknown field (with the valid ones), a wrong type, or a value out of range.
ObserverParams ParseObserverParams(const nlohmann::json& document, std::string_view source);

/// Reads and parses an observer parameter file; throws rigidtouch::Error naming the file if it
/// cannot be read, is empty or is not JSON, and as ParseObserverParams.
ObserverParams LoadObserverParams(const std::string& path);

/// Number of axes of the perceptual space.
inline constexpr int kPerceptDimensions = 4;

/// A point in the perceptual space, in JND units of the nominal observer.
using PerceptVector = std::array<double, kPerceptDimensions>;

/// Relative sensitivity of the Pacinian channel at `frequency_hz` (0 dB at its best frequency).
double PacinianGain_dB(const ObserverParams& params, double frequency_hz);

/// Relative sensitivity of the non-Pacinian channel at `frequency_hz`, on the same scale as
/// PacinianGain_dB (the two cross at the corner frequency).
double NonPacinianGain_dB(const ObserverParams& params, double frequency_hz);

/// Frequency that stands for each band of TapPercept::band_energy_fraction: the geometric centre
/// of [10, 40), [40, 100), [100, 400), [400, 800] Hz.
std::array<double, kPerceptBands> PerceptBandCentres_hz();

/// Maps one tap to the perceptual space (no internal noise). Throws rigidtouch::Error if the
/// percept has non-finite or negative fields.
PerceptVector ToPerceptVector(const ObserverParams& params, const TapPercept& percept);

/// Euclidean distance between two perceptual points [JND].
double PerceptDistance(const PerceptVector& a, const PerceptVector& b);

/// Probability that a nearest-template decision is right, for two walls `distance` JND apart
/// along any direction, when the series mean has variance `series_variance` per axis and each
/// template `template_variance` per axis, in `dimensions` axes (lapses and swaps excluded).
/// With P = b - a + D and Q = 2e - a - b - D (e series noise, a and b template noises, D the
/// difference of the walls), P and Q are independent and the answer is right when P.Q < 0, so
/// the probability is E[Phi(|D| cos(angle(P, D)) / sqrt(4 vs + 2 vm))] with P ~ N(D, 2 vm I):
/// closed form for one axis or vm = 0, two-dimensional Simpson quadrature otherwise.
double NearestTemplateProbabilityCorrect(double distance, double series_variance,
                                         double template_variance, int dimensions);

/// Expected percent correct of the nominal observer over a test's series, for walls whose mean
/// percepts are `a` (condition 0) and `b` (condition 1): the average over series positions of
/// lapse / 2 + (1 - lapse) (swap (1 - P) + (1 - swap) P). Tap-to-tap variability of the stimulus
/// and differences between participants are not included (the simulation includes both).
double PredictPercentCorrect(const ObserverParams& params, const StudyTest& test,
                             const PerceptVector& a, const PerceptVector& b);

/// Mean perceptual point of `condition` over `taps` taps rendered with seeds derived from `seed`.
PerceptVector MeanPerceptVector(const ObserverParams& params, StimulusSource& source,
                                const Condition& condition, int taps, std::uint64_t seed);

/// A simulated participant: presents nothing itself (its hand taps through the StimulusSource
/// when asked) and answers as the observer model decides. Every decision is a pure function of
/// the participant seed and the step, so a resumed session answers as an uninterrupted one.
class SimulatedParticipant : public WallPresenter, public Responder {
 public:
  /// `protocol` and `source` must outlive the participant.
  SimulatedParticipant(const Protocol& protocol, const ObserverParams& params,
                       StimulusSource& source, std::uint64_t seed);

  void Present(const Condition& condition, int taps) override;
  std::string Describe() const override;
  bool dry_run() const override { return true; }  // no person: a simulated participant
  void Show(std::string_view text) override;
  std::optional<int> Ask(const Protocol& protocol, const Step& step) override;

  /// The observer's answer (0 or 1) to series `step`.
  int Decide(const Step& step);
  /// This participant's JND scale factor (1 for the nominal observer).
  double jnd_factor() const { return jnd_factor_; }
  /// Whether this participant holds the labels of `test` swapped.
  bool labels_swapped(int test) const;

 private:
  struct Memory {
    std::array<PerceptVector, 2> templates;           // after familiarization
    std::vector<std::array<PerceptVector, 2>> drift;  // cumulative drift before each series
  };
  const Memory& MemoryOf(int test);
  PerceptVector FeltMean(const Condition& condition, int taps, std::uint64_t tap_stream,
                         std::uint64_t noise_stream);

  const Protocol& protocol_;
  ObserverParams params_;
  StimulusSource& source_;
  std::uint64_t seed_;
  double jnd_factor_ = 1.0;
  std::map<int, Memory> memories_;
};

}  // namespace rigidtouch::study
