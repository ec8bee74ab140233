// `rigidtouch material`: materials from measurements (docs/materials.md). `material fit` fits the
// decaying sinusoid to recorded taps and writes a material file that --material reads;
// `material synth` writes a synthetic recording of a preset material (the shipped data).
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "analysis/figures.h"
#include "analysis/material_fit.h"
#include "base/text.h"
#include "command.h"
#include "device/device_spec.h"
#include "io/materials.h"
#include "io/output_file.h"
#include "io/resources.h"
#include "io/tap_recording.h"
#include "material_run.h"

namespace rigidtouch::cli {
namespace {

struct MaterialFitFlags {
  std::vector<std::string> recordings;
  std::string out;
  std::string plot;
  std::string name;  // default: the output file's stem
  std::string device = "touch";
  double rate_hz = 1000.0;
  double effective_mass_kg = 0.0;  // 0: the device's apparent mass plus the hand's
  bool json = false;
};

struct MaterialSynthFlags {
  std::string material;
  std::string out;
  double snr_db = 20.0;
  double clip_fraction = 0.0;
  unsigned seed = 1;
  int taps_per_speed = 1;
  bool force_quantity = false;  // --force: record force_N instead of acceleration
};

void CheckMaterialFigurePath(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* ok : {".png", ".pdf", ".svg"}) {
    if (ext == ok) return;
  }
  throw Error("--plot '" + path + "': the figure's format comes from its extension, one of .png, " +
              ".pdf, .svg (got '" + ext + "')");
}

// draws the figure from the fit's data (a temporary JSON file, removed after)
void DrawMaterialFigure(const analysis::MaterialFit& fit, const std::string& plot, bool quiet) {
  std::string data =
      (std::filesystem::temp_directory_path() / "rigidtouch_material_XXXXXX").string();
  const int fd = ::mkstemp(data.data());
  if (fd < 0) throw Error("cannot create a temporary file for the figure's data");
  ::close(fd);
  struct Remove {
    std::string path;
    ~Remove() { std::remove(path.c_str()); }
  } remove{data};
  io::WriteFileAtomically(data, analysis::MaterialFigureJson(fit).dump(), "figure data");
  const analysis::FigureResult r =
      analysis::RunPlotScript(io::ShippedFile("python/plot_material.py"), {data, "--out", plot});
  if (r.status == analysis::FigureStatus::kOk) return;
  if (r.status == analysis::FigureStatus::kMissingMatplotlib) {
    std::cerr << "rigidtouch: matplotlib is missing (Debian: apt-get install python3-matplotlib); "
                 "no figure drawn, the material was still written\n";
    return;
  }
  if (!quiet) std::cerr << r.output;
  throw Error("drawing python/plot_material.py failed: " + r.message);
}

void PrintMaterialFit(const analysis::MaterialFit& fit, const std::string& out) {
  const std::string unit(io::TapQuantityUnit(fit.quantity));
  std::printf("%-28s %5s %9s %10s %12s %12s %12s %7s\n", "recording", "tap", "v [m/s]",
              ("A [" + unit + "]").c_str(), "B [1/s]", "f [Hz]", "t0 [s]", "R^2");
  for (const analysis::TapFit& t : fit.taps) {
    std::printf("%-28s %5d %9.4f %10.4g %6.2f+-%-5.2f %6.2f+-%-5.2f %12.6f %7.4f\n",
                std::filesystem::path(t.file).filename().string().c_str(), t.tap,
                t.impact_speed_mps, t.amplitude, t.decay_per_s, t.decay_sd_per_s, t.frequency_hz,
                t.frequency_sd_hz, t.onset_s, t.r2);
  }
  const analysis::AmplitudeLine& l = fit.amplitude;
  std::printf("f = %.4g +- %.2g Hz (spread %.2g), B = %.4g +- %.2g 1/s (spread %.2g)\n",
              fit.frequency_hz.mean, fit.frequency_hz.sd, fit.frequency_hz.spread,
              fit.decay_per_s.mean, fit.decay_per_s.sd, fit.decay_per_s.spread);
  std::printf("A(v) = %.5g +- %.2g %s per m/s x v (residual %.3g %s, R^2 %.4f)\n", l.slope,
              l.slope_sd, unit.c_str(), l.residual_rms, unit.c_str(), l.r2);
  if (fit.quantity == io::TapQuantity::kAcceleration) {
    std::printf("force at the device: %.5g N/(m/s) = %.4g kg (device %s and hand) x %.5g 1/s\n",
                fit.material.amplitude_Ns_per_m, fit.effective_mass_kg, fit.options.device.c_str(),
                l.slope);
  }
  std::printf("wrote material '%s' to %s\n", fit.material.name.c_str(), out.c_str());
}

void RunMaterialFit(const MaterialFitFlags& f) {
  io::CheckOutputPath(f.out, "material file");
  if (!f.plot.empty()) {
    CheckMaterialFigurePath(f.plot);
    io::CheckOutputPath(f.plot, "figure");
  }
  MaterialFitRequest request;
  request.name = f.name.empty() ? std::filesystem::path(f.out).stem().string() : f.name;
  request.device = f.device;
  request.rate_hz = f.rate_hz;
  request.effective_mass_kg = f.effective_mass_kg;
  std::vector<io::TapRecording> recordings;
  for (const std::string& path : f.recordings) recordings.push_back(io::ReadTapRecording(path));
  analysis::MaterialFit fit;
  const nlohmann::json file = FitMaterialFile(recordings, request, fit);
  io::WriteFileAtomically(f.out, file.dump(2) + "\n", "material file");
  if (!f.plot.empty()) DrawMaterialFigure(fit, f.plot, f.json);
  for (const std::string& w : fit.warnings) std::cerr << "rigidtouch: warning: " << w << "\n";
  if (f.json) {
    std::cout << nlohmann::json{{"out", f.out},
                                {"plot",
                                 f.plot.empty() ? nlohmann::json(nullptr) : nlohmann::json(f.plot)},
                                {"material", file}}
                     .dump()
              << "\n";
  } else {
    PrintMaterialFit(fit, f.out);
  }
}

void RunMaterialSynth(const MaterialSynthFlags& f) {
  io::CheckOutputPath(f.out, "recording");
  const Material m = io::ParseMaterial(f.material);
  if (!(f.snr_db >= 0.0 && f.snr_db <= 200.0)) throw Error("--snr-db: valid 0 to 200 dB");
  if (!(f.clip_fraction >= 0.0 && f.clip_fraction < 0.5)) {
    throw Error("--clip-fraction: valid 0 to 0.5");
  }
  analysis::SyntheticTapsOptions o;
  const double mass = device::EffectiveMassKg(device::PresetSpec("touch").model);
  o.quantity = f.force_quantity ? io::TapQuantity::kForce : io::TapQuantity::kAcceleration;
  o.slope = f.force_quantity ? m.amplitude_Ns_per_m : m.amplitude_Ns_per_m / mass;
  o.decay_per_s = m.decay_per_s;
  o.frequency_hz = m.frequency_hz;
  o.snr_db = f.snr_db;
  o.clip_fraction = f.clip_fraction;
  o.seed = f.seed;
  if (f.taps_per_speed < 1 || f.taps_per_speed > 20) throw Error("--taps-per-speed: valid 1 to 20");
  o.taps_per_speed = f.taps_per_speed;
  char comment[512];
  std::snprintf(comment, sizeof comment,
                "# SYNTHETIC recording, not a measurement: rigidtouch material synth %s (seed %u)\n"
                "# model (docs/materials.md): a stylus at constant speed v onto the sample; from "
                "the onset %s = %.6g v e^(-%.6g t) sin(2 pi %.6g t)\n"
                "# %s; white noise at SNR %.3g dB; onset 20 ms +- 2 ms into each tap\n",
                m.name.c_str(), f.seed, std::string(io::TapQuantityColumn(o.quantity)).c_str(),
                o.slope, o.decay_per_s, o.frequency_hz,
                f.force_quantity ? "force at the sample"
                                 : "handle acceleration = the preset's force over 0.599 kg "
                                   "(touch's apparent mass and the hand's)",
                f.snr_db);
  io::WriteFileAtomically(f.out, analysis::SyntheticTapsCsv(o, comment), "recording");
}

void RegisterMaterial(CLI::App& root) {
  CLI::App* app = root.add_subcommand(
      "material", "materials from measurements: fit recorded taps, make synthetic recordings");
  app->require_subcommand(1);
  auto f = std::make_shared<MaterialFitFlags>();
  CLI::App* fit = app->add_subcommand(
      "fit", "fit the decaying sinusoid to recorded taps and write a material file");
  fit->add_option("recordings", f->recordings, "tap recordings (CSV, docs/materials.md)")
      ->required();
  fit->add_option("--out", f->out, "material file to write (JSON)")->required();
  fit->add_option("--plot", f->plot, "figure: taps over the model, A(v), spectra (.png/.pdf/.svg)");
  fit->add_option("--name", f->name, "the material's name (default: --out's file stem)");
  fit->add_option("--device", f->device, device::DeviceSpecHelp() + " (default touch)");
  fit->add_option("--rate", f->rate_hz, "haptic rate the device renders at [Hz] (default 1000)");
  fit->add_option("--effective-mass-kg", f->effective_mass_kg,
                  "mass converting acceleration to force [kg] (default: the device's apparent "
                  "mass plus the hand's 0.554 kg)");
  fit->add_flag("--json", f->json, "print one JSON object");
  fit->callback([f] { RunMaterialFit(*f); });
  auto s = std::make_shared<MaterialSynthFlags>();
  CLI::App* synth = app->add_subcommand(
      "synth", "write a SYNTHETIC tap recording of a material (five speeds, 0.05-0.4 m/s)");
  synth->add_option("material", s->material, "rubber | wood | aluminium | FILE.json")->required();
  synth->add_option("--out", s->out, "recording to write (CSV)")->required();
  synth->add_option("--snr-db", s->snr_db, "signal-to-noise ratio [dB] (default 20)");
  synth->add_option("--clip-fraction", s->clip_fraction,
                    "clip the first tap at the level this fraction of its samples exceed");
  synth->add_option("--seed", s->seed, "noise and onset seed (default 1)");
  synth->add_option("--taps-per-speed", s->taps_per_speed, "taps at each speed (default 1)");
  synth->add_flag("--force", s->force_quantity, "record force_N instead of acceleration_mps2");
  synth->callback([s] { RunMaterialSynth(*s); });
}

const CommandRegistrar material_registrar("material", &RegisterMaterial);

}  // namespace

nlohmann::json FitMaterialFile(const std::vector<io::TapRecording>& recordings,
                               const MaterialFitRequest& request, analysis::MaterialFit& fit) {
  if (!(request.rate_hz >= 100.0 && request.rate_hz <= 100000.0)) {
    throw Error("--rate " + text::FormatNumber(request.rate_hz) + ": valid 100 to 100000 Hz");
  }
  if (!(request.effective_mass_kg >= 0.0 && request.effective_mass_kg <= 1000.0)) {
    throw Error("--effective-mass-kg " + text::FormatNumber(request.effective_mass_kg) +
                ": valid 0 (the device's and the hand's) to 1000 kg");
  }
  const device::DeviceSpec spec = device::ParseDeviceSpec(request.device);
  analysis::MaterialFitOptions o;
  o.name = request.name;
  o.device = request.device;
  o.effective_mass_kg = request.effective_mass_kg > 0.0 ? request.effective_mass_kg
                                                        : device::EffectiveMassKg(spec.model);
  o.display_limit_hz = 0.5 * request.rate_hz;
  o.max_force_N = spec.limits.max_force_N;
  fit = analysis::FitMaterial(recordings, o);
  nlohmann::json file = analysis::MaterialFileJson(fit);
  file["fit"]["version"] = RIGIDTOUCH_VERSION;
  // the reader must take what is written: checked before any file exists
  io::ReadMaterialJson(io::JsonSource(request.name), file, "", o.name);
  return file;
}
}  // namespace rigidtouch::cli
