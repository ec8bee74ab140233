// Simulated participants: a perceptual observer that hears nothing and sees nothing, and decides
// from the force its hand feels (TapPercept). docs/study.md gives every parameter with its source.
//
// Each tap is mapped to a point in a 5-dimensional perceptual space whose unit on every axis is
// one just-noticeable difference (JND):
//   onset        20 log10(peak force / 1 N) / intensity JND
//   P level      sensation level of the Pacinian channel (dB above threshold) / intensity JND
//   NP level     sensation level of the non-Pacinian (NP I) channel / intensity JND
//   pitch        salience * ln(pitch / kPitchAxisOrigin_hz) / ln(1 + Weber fraction); 0 without
//   periodicity  salience * periodicity * pitch_salience_dB / intensity JND; 0 without pitch
// Internal noise adds an independent unit normal to every axis of every tap. Each participant has
// its own JND scale and detection threshold. The observer keeps a memory template of each wall
// from the familiarization taps (averaged, plus encoding noise, plus a random-walk drift per
// series: trace memory, Durlach & Braida 1969), averages the taps of a series and takes the wall
// whose template is nearest among the test's k walls (discrimination). Naming it rests on a
// separate label memory: the association of labels and templates can be lost before any series
// (more often when walls of earlier tests felt alike) and is then re-derived from a coarse coded
// memory, possibly with labels exchanged (identification). It lapses (guesses among the k) with a
// small probability.
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
  double individual_jnd_log_sd = 0.35;  ///< SD across participants of ln(JND scale factor)
  double individual_threshold_sd_dB = 5.0;  ///< SD across participants of the detection threshold
  double label_loss_per_series =
      0.05;                         ///< chance per series that the wall-label association is lost
  double label_code_sd_jnd = 4.0;   ///< noise of the coded memory the labels are re-derived from
  double label_interference = 1.0;  ///< added loss rate per earlier wall that feels alike

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
inline constexpr int kPerceptDimensions = 5;

/// A tap without pitch (a click, or no vibration) sits here on the pitch axis: the geometric
/// centre of the 40-400 Hz range in which the source reports a pitch, so a click is not placed
/// at any end of the range (it is told from a pitched train by the periodicity axis) [Hz].
inline constexpr double kPitchAxisOrigin_hz = 126.49110640673518;  // sqrt(40 * 400)

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

/// Probability that the observer holds a test's labels swapped at series `series` (0-based) for
/// walls `distance` JND apart (label memory, docs/study.md): the association of labels and walls
/// survives each series with probability 1 - h (h = label_loss_per_series); until the first loss
/// the labels are swapped with label_swap_probability p; after a loss they are re-derived from a
/// coded memory with noise sigma = label_code_sd_jnd per axis and per wall, which swaps them with
/// q = Phi(-distance / (sqrt(2) sigma)). So P = (1 - h)^(s + 1) p + (1 - (1 - h)^(s + 1)) q.
/// Exact when the templates equal the walls' mean percepts (the simulation draws each
/// re-derivation from the participant's current templates).
double LabelSwapProbability(const ObserverParams& params, double distance, int series,
                            double interference = 0.0);

/// How alike two walls `distance` JND apart are in the coded memory: the probability that their
/// coded memories (noise label_code_sd_jnd per axis each) fall in the other's order along their
/// difference, doubled: 2 Phi(-distance / (sqrt(2) sigma)); 1 for identical walls.
double LabelSimilarity(const ObserverParams& params, double distance);

/// Probability per series that a test's label association is lost: 1 - (1 - h)^(1 + lambda I),
/// with h = label_loss_per_series, lambda = label_interference and `interference` I the summed
/// LabelSimilarity of this test's walls to the walls of earlier tests that are not in this test
/// (their labels compete for the same feeling: proactive interference).
double LabelLossProbability(const ObserverParams& params, double interference);

/// Expected percent correct of the nominal observer over a two-condition test's series (the closed
/// form exists for two walls only; tests of more are predicted by simulated cohorts), for walls
/// whose mean percepts are `a` (condition 0) and `b` (condition 1): the average over series
/// positions s of lapse / 2 + (1 - lapse) (w_s (1 - P_s) + (1 - w_s) P_s), w_s =
/// LabelSwapProbability. Tap-to-tap variability of the stimulus and differences between
/// participants are not included (the simulation, and PredictProtocol's cohorts, include both).
double PredictPercentCorrect(const ObserverParams& params, const StudyTest& test,
                             const PerceptVector& a, const PerceptVector& b,
                             double interference = 0.0);

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

  /// The observer's answer (0 to k - 1, k the test's conditions) to series `step`.
  int Decide(const Step& step);
  /// This participant's JND scale factor (1 for the nominal observer).
  double jnd_factor() const { return jnd_factor_; }
  /// This participant's detection threshold offset [dB] (0 for the nominal observer).
  double threshold_offset_dB() const { return threshold_offset_dB_; }
  /// Whether this participant holds the labels of `test` swapped from the start (explicit swap,
  /// label_swap_probability).
  bool labels_swapped(int test) const;
  /// The labels this participant holds for `test` before its first series: the identity, or
  /// with label_swap_probability one pair exchanged (k = 2: the two; k > 2: a pair at random).
  std::vector<int> InitialLabels(int test) const;
  /// Whether this participant holds the labels of `test` swapped at series `series`, after any
  /// losses of the label association (label memory): any label on another wall's template.
  bool labels_swapped(int test, int series);
  /// The labels held at series `series` of `test`: element c is the condition whose template the
  /// label of condition c is attached to (the identity when every label is right).
  const std::vector<int>& LabelsAt(int test, int series);
  /// The label interference of `test` (LabelLossProbability) from the tests before it in this
  /// participant's plan, from this participant's templates.
  double interference(int test);
  /// The remembered template of condition `condition` of `test` as used at series `series`
  /// (familiarization mean, encoding noise and the drift up to that series), in this
  /// participant's perceptual units.
  PerceptVector TemplateAt(int test, int series, int condition);

 private:
  struct Memory {
    std::vector<PerceptVector> templates;           // after familiarization, one per condition
    std::vector<std::vector<PerceptVector>> drift;  // cumulative drift before each series [s][c]
    std::vector<std::vector<int>> labels;           // labels held at each series (LabelsAt)
    double interference = 0.0;                      // from the walls of earlier tests
  };
  const Memory& MemoryOf(int test);
  PerceptVector FeltMean(const Condition& condition, int taps, std::uint64_t tap_stream,
                         std::uint64_t noise_stream);

  const Protocol& protocol_;
  ObserverParams params_;
  StimulusSource& source_;
  std::uint64_t seed_;
  double jnd_factor_ = 1.0;
  double threshold_offset_dB_ = 0.0;
  std::map<int, Memory> memories_;
  std::vector<int> test_order_;  // tests in the order of this participant's plan
};

}  // namespace rigidtouch::study
