// Materials of the event renderer: presets and JSON files whose mistakes name the field.
#include "io/materials.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "analysis/spectrum.h"
#include "analysis/tap_experiment.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {
namespace {

std::string Write(const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rigidtouch_material_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << text;
  return path.string();
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseMaterial(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MaterialsTest, PresetsAndFiles) {
  ASSERT_EQ(MaterialPresets().size(), 3u);
  EXPECT_EQ(ParseMaterial("wood").frequency_hz, 100.0);
  // f rises and the decay quickens from rubber to wood to aluminium
  EXPECT_LT(ParseMaterial("rubber").frequency_hz, ParseMaterial("wood").frequency_hz);
  EXPECT_LT(ParseMaterial("wood").frequency_hz, ParseMaterial("aluminium").frequency_hz);
  EXPECT_LT(ParseMaterial("rubber").decay_per_s, ParseMaterial("aluminium").decay_per_s);
  const std::string path = Write(R"({"name": "steel", "amplitude_Ns_per_m": 30, "decay_per_s": 120,
                "frequency_hz": 400})");
  const Material m = ParseMaterial(path);
  EXPECT_EQ(m.name, "steel");
  EXPECT_EQ(m.amplitude_Ns_per_m, 30.0);
  EXPECT_EQ(m.decay_per_s, 120.0);
  EXPECT_EQ(m.frequency_hz, 400.0);
  std::filesystem::remove(path);
}

TEST(MaterialsTest, BadMaterialsNameTheField) {
  const std::pair<std::string, std::string> cases[] = {
      {R"({"amplitude_Ns_per_m": -1, "decay_per_s": 60, "frequency_hz": 100})",
       "amplitude_Ns_per_m"},
      {R"({"amplitude_Ns_per_m": 10, "frequency_hz": 100})", "decay_per_s"},
      {R"({"amplitude_Ns_per_m": 10, "decay_per_s": 60, "frequency_hz": "high"})", "frequency_hz"},
      {R"({"amplitude_Ns_per_m": 10, "decay_per_s": 60, "frequency_hz": 100, "q": 1})", "q"},
  };
  for (const auto& [text, field] : cases) {
    const std::string path = Write(text);
    const std::string e = ErrorOf(path);
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find(field), std::string::npos) << text << ": " << e;
    std::filesystem::remove(path);
  }
  const std::string e = ErrorOf("glass");
  EXPECT_NE(e.find("'glass'"), std::string::npos) << e;
  EXPECT_NE(e.find("aluminium"), std::string::npos) << e;
}

// an acceleration material keeps its form when read, and a device converts it with its own
// effective mass: A = amplitude_mps2_per_mps x the device's mass; on the fit's mass the file's A
// to the last bit, no note; a force material is the same on every device
TEST(MaterialsTest, AnAccelerationMaterialIsConvertedWithTheDevicesMass) {
  const std::string path = Write(R"({"name": "fitted", "amplitude_Ns_per_m": 15.0,
      "decay_per_s": 60, "frequency_hz": 100, "amplitude_quantity": "acceleration",
      "amplitude_mps2_per_mps": 25.0, "effective_mass_kg": 0.6})");
  const Material file = ParseMaterial(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(file.acceleration());
  EXPECT_EQ(file.amplitude_Ns_per_m, 15.0);
  EXPECT_EQ(file.amplitude_mps2_per_mps, 25.0);
  EXPECT_EQ(file.effective_mass_kg, 0.6);
  EXPECT_EQ(FindPreset(file), nullptr);

  const Material same = MaterialOnDevice(file, 0.6);
  EXPECT_EQ(same.amplitude_Ns_per_m, 15.0);
  EXPECT_EQ(MaterialDeviceNote(file, same, "touch"), "");

  const Material heavy = MaterialOnDevice(file, 1.2);
  EXPECT_DOUBLE_EQ(heavy.amplitude_Ns_per_m, 25.0 * 1.2);
  EXPECT_EQ(heavy.effective_mass_kg, 1.2);
  EXPECT_EQ(heavy.amplitude_mps2_per_mps, 25.0);
  EXPECT_EQ(heavy.decay_per_s, file.decay_per_s);
  EXPECT_EQ(heavy.frequency_hz, file.frequency_hz);
  EXPECT_EQ(MaterialOnDevice(heavy, 1.2).amplitude_Ns_per_m, heavy.amplitude_Ns_per_m);
  const std::string note = MaterialDeviceNote(file, heavy, "heavy");
  for (const char* part : {"'fitted'", "0.6 kg", "1.2 kg", "heavy", "30 N/(m/s)"}) {
    EXPECT_NE(note.find(part), std::string::npos) << part << ": " << note;
  }

  RenderParams event;
  event.renderer = RendererKind::kEvent;
  event.material = file;
  EXPECT_EQ(RenderMaterialOnDevice(event, 1.2, "heavy"), note);
  EXPECT_DOUBLE_EQ(event.material.amplitude_Ns_per_m, 30.0);
  // a material train plays f and t_c only: converted, no note
  RenderParams train;
  train.renderer = RendererKind::kTrain;
  train.material = file;
  EXPECT_EQ(RenderMaterialOnDevice(train, 1.2, "heavy"), "");
  EXPECT_DOUBLE_EQ(train.material.amplitude_Ns_per_m, 30.0);

  const Material wood = ParseMaterial("wood");
  EXPECT_FALSE(wood.acceleration());
  EXPECT_EQ(MaterialOnDevice(wood, 1.2).amplitude_Ns_per_m, wood.amplitude_Ns_per_m);
  EXPECT_EQ(MaterialDeviceNote(wood, MaterialOnDevice(wood, 1.2), "heavy"), "");

  try {
    MaterialOnDevice(file, 0.0);
    ADD_FAILURE() << "a zero mass converted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fitted"), std::string::npos) << e.what();
  }
}

// passive material trains: f the material's, the window three decay time constants; over the
// walls' passivity sweep no tap gives the user energy, and the train's impulsive force peaks
// within 10 % of f over its window. Aluminium's 300 Hz needs 2 kHz: at 1 kHz the nearest whole
// interval (3 steps) gives 333 Hz, 11 % off (Eq. 7)
TEST(MaterialsTest, MaterialTrainsArePassiveAndRingAtTheMaterialsFrequency) {
  for (const Material& m : MaterialPresets()) {
    const MaterialTrainParams t = MaterialTrain(m);
    EXPECT_EQ(t.frequency_hz, m.frequency_hz);
    EXPECT_NEAR(t.t_collision_s, std::min(std::log(20.0) / m.decay_per_s, 0.1), 1e-12);
    for (const std::string device : {"touch", "omni", "falcon", "ideal"}) {
      for (const double speed : {0.05, 0.15, 0.3, 0.5}) {
        analysis::TapExperimentConfig c;
        c.scene_path = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml";
        c.device_preset = device;
        c.rate_hz = m.frequency_hz > 200.0 ? 2000.0 : 1000.0;
        c.load.render.renderer = RendererKind::kTrain;
        c.load.render.material = m;
        c.load.render.frequency_hz = t.frequency_hz;
        c.load.render.t_collision_s = t.t_collision_s;
        c.script.approach_speed_mps = speed;
        c.script.taps = 2;
        if (device == "ideal") {
          c.stiffness_N_per_m = 400.0;
          c.damping_Ns_per_m = 10.0;
        }
        const analysis::TapRun run = analysis::RunTapExperiment(c);
        for (const analysis::TapMetrics& tap : run.taps) {
          // tolerance: 1e-9 J, as the walls' passivity test
          EXPECT_LE(tap.energy_to_user_J, 1e-9)
              << m.name << " " << device << " " << speed << " m/s tap " << tap.tap;
        }
        if (device != "ideal" || speed != 0.15) continue;
        // the impulsive force over the window from onset
        std::vector<double> f;
        bool on = false;
        for (const TraceSample& s : run.trace) {
          on = on || s.tool_contacts > 0;
          if (!on) continue;
          f.push_back(s.impulsive_force_N.dot(s.wall_normal));
          if (static_cast<double>(f.size()) * run.model.timestep_s >= t.t_collision_s) break;
        }
        analysis::SpectrumOptions o;
        o.window = analysis::SpectrumOptions::Window::kTaperedEnd;
        o.remove_mean = false;  // the comb's line at 0 Hz stays at 0 Hz
        o.min_fft_length = 8192;
        const analysis::Spectrum sp = analysis::PowerSpectrum(f, 1.0 / run.model.timestep_s, o);
        const double peak = analysis::DominantFrequencyHz(sp);
        // a train of one-tick impulses is a comb: its lines at f, 2 f, ... are equally strong up
        // to the window, so the largest may be a harmonic; the train's own frequency is the
        // comb's lowest line, the first local maximum above DC with at least half the largest
        // power
        double largest = 0.0;
        for (std::size_t k = 1; k < sp.power.size(); ++k) largest = std::max(largest, sp.power[k]);
        double fundamental = 0.0;
        for (std::size_t k = 2; k + 1 < sp.power.size(); ++k) {
          if (sp.power[k] >= 0.5 * largest && sp.power[k] >= sp.power[k - 1] &&
              sp.power[k] >= sp.power[k + 1]) {
            fundamental = static_cast<double>(k) * sp.bin_hz;
            break;
          }
        }
        EXPECT_NEAR(fundamental, m.frequency_hz, 0.1 * m.frequency_hz) << m.name;
        // and the largest line is one of the comb's, a multiple of the train's frequency
        const double f_train = 1.0 / (run.model.schedule.interval_steps * run.model.timestep_s);
        const double harmonic = std::round(peak / f_train);
        EXPECT_GE(harmonic, 1.0) << m.name;
        EXPECT_NEAR(peak, harmonic * f_train, 0.05 * f_train) << m.name;
        std::cout << m.name << ": train at "
                  << 1.0 / (run.model.schedule.interval_steps * run.model.timestep_s) << " Hz, "
                  << run.model.schedule.impulses << " impulses, window " << t.t_collision_s
                  << " s, impulsive force: lowest comb line " << fundamental << " Hz, largest "
                  << peak << " Hz\n";
      }
    }
  }
}

}  // namespace
}  // namespace rigidtouch::io
