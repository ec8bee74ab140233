// The narrow interfaces between the study toolkit and the engine: "render one tap of a condition
// and report what the hand felt" (StimulusSource, for simulated participants) and "render a wall
// for a person to tap" (WallPresenter, for real sessions). The engine side implements them; the
// study code only depends on these declarations.
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <span>
#include <string>

#include "study/protocol.h"

namespace rigidtouch::study {

/// Number of frequency bands in TapPercept::band_energy_fraction.
inline constexpr int kPerceptBands = 4;

/// Band edges in Hz: [0, 40), [40, 100), [100, 400), [400, inf).
inline constexpr std::array<double, kPerceptBands - 1> kPerceptBandEdges_hz = {40.0, 100.0, 400.0};

/// What the hand felt during one tap, summarised from the force the device applied to the hand
/// (normal component, world frame) from contact onset to the end of the collision window (at
/// least 100 ms after onset for walls without a window, so every renderer is summarised over the
/// same span). The vibration fields describe the transient part: the displayed force minus the
/// penalty force, i.e. what the collision impulses add (zero for a pure penalty wall).
struct TapPercept {
  /// Largest force magnitude on the hand during the span [N].
  double peak_force_N = 0.0;
  /// Rate hardness (Lawrence et al., IEEE T-RA 2000): initial rate of change of the contact force
  /// divided by the approach speed at onset [N/s per m/s = N/m].
  double rate_hardness_N_per_m = 0.0;
  /// Pitch of the transient: its repetition rate [Hz] when it is periodic
  /// (analysis::TapMetrics::transient_repetition_hz); 0 when it has none (a single click, a ring
  /// slower than 40 Hz, or no transient).
  double dominant_frequency_hz = 0.0;
  /// How periodic the transient is, in [0, 1]: its normalised autocorrelation at the pitch
  /// period (1 for an endless train of equal pulses, (N - 1) / N for N of them); 0 without pitch.
  double periodicity = 0.0;
  /// Spectral peak over mean power of the transient at or above 40 Hz (about 1 for a click, about
  /// N for N periodic pulses); 0 when there is no transient.
  double transient_peak_to_mean = 0.0;
  /// Fraction of the transient's energy in each band (kPerceptBandEdges_hz); sums to 1 when
  /// vibration_rms_N > 0.
  std::array<double, kPerceptBands> band_energy_fraction{};
  /// RMS over the span of the transient part, its mean removed: the vibration the impulses add
  /// on top of the press [N].
  double vibration_rms_N = 0.0;
  /// Hand speed towards the wall just before contact, as drawn for this tap [m/s].
  double approach_speed_mps = 0.0;
};

/// Renders single taps offline (simulated hand + device + engine) for simulated participants.
class StimulusSource {
 public:
  virtual ~StimulusSource() = default;
  /// Renders one tap of `condition` and reports what the hand felt. The tap's variability (hand
  /// speed spread, etc.) is drawn from `tap_seed` only: the same seed gives the same percept.
  /// Throws rigidtouch::Error if the condition cannot be rendered.
  virtual TapPercept RenderTap(const Condition& condition, std::uint64_t tap_seed) = 0;
  /// One-line description recorded in simulated session logs (what renders the taps).
  virtual std::string Describe() const = 0;
};

/// Renders walls for a person to tap during `study run`.
class WallPresenter {
 public:
  virtual ~WallPresenter() = default;
  /// Switches the rendered wall to `condition` and returns once the participant has made `taps`
  /// taps on it (a device presenter waits for them; a text presenter returns at once).
  virtual void Present(const Condition& condition, int taps) = 0;
  /// One-line description recorded in the session log (which device, which scene).
  virtual std::string Describe() const = 0;
  /// True when no person feels what is presented (text, or the in-process simulated device):
  /// recorded in the log's session_start as "dry_run".
  virtual bool dry_run() const = 0;
};

/// A presenter that renders nothing and prints "rendering wall X for N taps" to a stream: for dry
/// runs and scripted tests of the session flow. It reveals the condition, so never use it with a
/// participant.
class TextPresenter : public WallPresenter {
 public:
  /// Prints to `out`, which must outlive the presenter.
  explicit TextPresenter(std::ostream& out) : out_(out) {}
  void Present(const Condition& condition, int taps) override;
  std::string Describe() const override;
  bool dry_run() const override { return true; }

 private:
  std::ostream& out_;
};

/// Options for the engine-backed tap source used by `study simulate`.
struct TapSourceOptions {
  std::string scene;   ///< MJCF scene path; empty: the engine's default tap scene
  std::string device;  ///< a device preset or JSON device spec; empty: the engine's default
  /// Mean hand approach speed when a condition does not set one [m/s]; 0: the engine's default.
  double approach_speed_mps = 0.0;
  /// Relative standard deviation of the hand approach speed across taps; < 0: engine default.
  double approach_speed_relative_sd = -1.0;
};

/// Options for the device-backed presenter used by `study run`.
struct PresenterOptions {
  std::string scene;   ///< MJCF scene path; empty: the engine's default wall scene
  std::string device;  ///< "udp://HOST:PORT" (a device through the bridge) or "sim" (dry run)
  std::string preset = "touch";  ///< the device: a preset or a JSON device spec; its limits apply
  std::string key_file;          ///< bridge key file; empty: the per-user key
};

/// Builds the tap source backed by the real tap experiment (simulated device + engine + tap
/// metrics). NOT IMPLEMENTED in src/study: the engine integration defines it. Throws
/// rigidtouch::Error on bad options.
std::unique_ptr<StimulusSource> MakeTapStimulusSource(const TapSourceOptions& options);

/// Builds the presenter that renders walls on a (simulated or networked) device for a person.
/// NOT IMPLEMENTED in src/study: the engine integration defines it. Throws rigidtouch::Error on
/// bad options or when the device cannot be opened.
std::unique_ptr<WallPresenter> MakeDeviceWallPresenter(const PresenterOptions& options);

}  // namespace rigidtouch::study
