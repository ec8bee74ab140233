// A value the user wrote is used or refused with the reason (docs/config.md): flag > config file
// > device preset > default, in tap, serve and simulate; errors say where a value was written.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

namespace fs = std::filesystem;

class SettingsCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = TempDir("settings"); }
  void TearDown() override { fs::remove_all(dir_); }
  // writes a config file and returns its path
  std::string Config(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  static nlohmann::json Json(const CliResult& r) {
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  }
  fs::path dir_;
};

// every JSON input, nested 100,000 deep (an array, an object) or 1 GiB long, is refused with
// exit 2 and the file named: the depth before parsing, the size after reading one byte past the
// 64 MiB limit (a sparse file: it takes no disk space)
TEST_F(SettingsCliTest, DeepOrHugeJsonInputsAreRefusedNamingTheFile) {
  const std::string deep_array =
      Config("deep_array.json", std::string(100000, '[') + std::string(100000, ']'));
  std::string object;
  for (int i = 0; i < 100000; ++i) object += "{\"a\":";
  const std::string deep_object =
      Config("deep_object.json", object + "1" + std::string(100000, '}'));
  const std::string huge = Config("huge.json", "");
  fs::resize_file(huge, std::uintmax_t{1} << 30);
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";
  const std::vector<std::string> commands = {
      "tap --config ",
      "simulate --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/tap.xml --config ",
      "study predict --protocol ",
      "study predict --protocol " + protocol + " --observer ",
      "tap --device ",
      "tap --material "};
  for (const std::string& command : commands) {
    for (const std::string& file : {deep_array, deep_object, huge}) {
      const CliResult r = RunCli(command + file);
      EXPECT_EQ(r.exit_code, 2) << command << file << "\n" << r.err;
      EXPECT_EQ(r.err.rfind("rigidtouch: error: ", 0), 0u) << command << file << "\n" << r.err;
      EXPECT_NE(r.err.find(file), std::string::npos) << command << file << "\n" << r.err;
      const std::string why = file == huge ? "is larger than 64 MiB" : "nested more than 64 deep";
      EXPECT_NE(r.err.find(why), std::string::npos) << command << file << "\n" << r.err;
    }
  }
  fs::remove(huge);
}

// a first word that names no subcommand is named, with the valid ones (CLI11 said only "A
// subcommand is required", and pointed at `rigidtouch nosuch --help`)
TEST_F(SettingsCliTest, AnUnknownSubcommandIsNamed) {
  const CliResult r = RunCli("nosuch --json");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: unknown subcommand 'nosuch'; valid: bench, "),
            std::string::npos)
      << r.err;
  // (view is there when the viewer is built, as in the release build; not in the sanitizer ones)
  EXPECT_NE(r.err.find("simulate, study, sweep, tap"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("nosuch --help"), std::string::npos) << r.err;
  // an unknown flag of a known subcommand keeps CLI11's words and that subcommand's help
  const CliResult flag = RunCli("tap --nosuch");
  EXPECT_EQ(flag.exit_code, 2);
  EXPECT_NE(flag.err.find("--nosuch"), std::string::npos) << flag.err;
  EXPECT_NE(flag.err.find("tap --help"), std::string::npos) << flag.err;
}

TEST_F(SettingsCliTest, StiffnessFromTheConfigBeatsThePresetAndTheFlagBeatsTheConfig) {
  const std::string k = Config("k.json", R"({"contact": {"stiffness_N_per_m": 300}})");
  // the Touch preset's 400 N/m is the default; the file's 300 wins over it; the flag over both
  EXPECT_EQ(Json(RunCli("tap --taps 1 --json"))["stiffness_N_per_m"], 400.0);
  const auto from_file = Json(RunCli("tap --taps 1 --json --config " + k));
  EXPECT_EQ(from_file["stiffness_N_per_m"], 300.0);
  EXPECT_DOUBLE_EQ(from_file["damping_Ns_per_m"].get<double>(), 0.3);  // k h, under the 4 cap
  EXPECT_EQ(Json(RunCli("tap --taps 1 --json --stiffness 350 --config " + k))["stiffness_N_per_m"],
            350.0);
  // serve on the simulated device reads the same file the same way
  const auto served = Json(RunCli("serve --device sim --taps 1 --json --config " + k));
  EXPECT_EQ(served["contact"]["stiffness_N_per_m"], 300.0);
}

TEST_F(SettingsCliTest, ForceLimitFromTheConfigIsUsedBelowThePresetsAndRefusedAbove) {
  const std::string gentle = Config("gentle.json", R"({"device": {"max_force_N": 2}})");
  const auto j = Json(RunCli("tap --taps 1 --json --config " + gentle));
  EXPECT_EQ(j["max_force_N"], 2.0);
  for (const auto& tap : j["taps"]) EXPECT_LE(tap["peak_force_N"].get<double>(), 2.0);
  const std::string strong = Config("strong.json", R"({"device": {"max_force_N": 100}})");
  for (const std::string command : {"tap --taps 1 --config ", "serve --device sim --config "}) {
    const CliResult r = RunCli(command + strong);
    EXPECT_EQ(r.exit_code, 2) << command << r.err;
    EXPECT_NE(r.err.find("rigidtouch: error: device.max_force_N = 100 N (set in " + strong +
                         " as device.max_force_N) is above the touch preset's force limit, 3.3 N"),
              std::string::npos)
        << r.err;
  }
}

TEST_F(SettingsCliTest, ToolFromTheConfigIsUsedUnlessTheFlagSaysOtherwise) {
  const std::string t = Config("t.json", R"({"tool": "probe"})");
  for (const std::string& command :
       {"tap --taps 1 --config " + t, "simulate --steps 1 --scene " +
                                          std::string(RIGIDTOUCH_SCENES) + "/wall.xml --config " +
                                          t}) {
    const CliResult r = RunCli(command);
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_NE(r.err.find("no free body named 'probe'"), std::string::npos) << r.err;
  }
  EXPECT_EQ(RunCli("tap --taps 1 --tool tool --config " + t).exit_code, 0);
}

TEST_F(SettingsCliTest, ValuesThatCannotBeUsedAreRefusedSayingWhereTheyWereWritten) {
  const std::string r = Config("r.json", R"({"render": {"restitution": 2}})");
  CliResult c = RunCli("simulate --steps 1 --scene " + std::string(RIGIDTOUCH_SCENES) +
                       "/wall.xml --config " + r);
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("restitution = 2 is out of range"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("(set in " + r + " as render.restitution)"), std::string::npos) << c.err;
  c = RunCli("tap --taps 1 --renderer impulse --restitution 3");
  EXPECT_NE(c.err.find("(set by --restitution)"), std::string::npos) << c.err;
  // the time step of tap and serve is the haptic period
  const std::string h = Config("h.json", R"({"timestep_s": 0.002})");
  c = RunCli("tap --taps 1 --config " + h);
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("differs from the haptic period"), std::string::npos) << c.err;
  // coupling settings where the coupling is direct, or a coupling serve does not run
  const std::string cs = Config("cs.json", R"({"device": {"coupling_stiffness_N_per_m": 300}})");
  c = RunCli("tap --taps 1 --config " + cs);
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("has no effect here: the coupling is direct"), std::string::npos) << c.err;
  const std::string v = Config("v.json", R"({"device": {"coupling": "virtual"}})");
  c = RunCli("serve --device sim --config " + v);
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("serve couples the tool to the device directly"), std::string::npos)
      << c.err;
  // tap takes the config's coupling when --coupling is not given
  EXPECT_EQ(Json(RunCli("tap --taps 1 --json --config " + v))["coupling"], "virtual");
}

// expects exit status 2 and every one of `parts` in stderr
void ExpectRefused(const std::string& command, const std::vector<std::string>& parts) {
  const CliResult r = RunCli(command);
  EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("rigidtouch: error: ", 0), 0u) << command << "\n" << r.err;
  for (const std::string& part : parts) {
    EXPECT_NE(r.err.find(part), std::string::npos) << command << "\n" << r.err;
  }
}

// a renderer parameter the chosen renderer does not use is refused, naming the flag or the
// config field and the renderers that use it (it was accepted and dropped, even out of range)
TEST_F(SettingsCliTest, RendererParametersTheRendererDoesNotUseAreRefused) {
  const std::string simulate =
      "simulate --steps 1 --scene " + std::string(RIGIDTOUCH_SCENES) + "/wall.xml";
  ExpectRefused(simulate +
                    " --renderer penalty --frequency -5 --t-collision 9 --restitution 0.7 "
                    "--reference-solver",
                {"render.restitution (set by --restitution) has no effect here",
                 "used only by the impulse and train renderers"});
  const std::string f_why =
      "render.frequency_hz (set by --frequency) has no effect here: "
      "frequency_hz is used only by the train renderer, not by the ";
  const std::string tc_why =
      "render.t_collision_s (set by --t-collision) has no effect here: "
      "t_collision_s is used only by the train renderer";
  ExpectRefused(simulate + " --renderer penalty --frequency -5", {f_why + "penalty renderer"});
  ExpectRefused(simulate + " --renderer impulse --frequency -5", {f_why + "impulse renderer"});
  ExpectRefused(simulate + " --renderer impulse --frequency -5 --t-collision 9",
                {tc_why + ", not by the impulse renderer"});
  ExpectRefused(simulate + " --renderer penalty --reference-solver",
                {"render.reference_solver (set by --reference-solver) has no effect here"});
  ExpectRefused(simulate + " --renderer event --material wood --restitution 0.5",
                {"render.restitution (set by --restitution)", "not by the event renderer"});
  // the same fields in a config file's render section, with the renderer from the file or a flag
  const std::string p = Config("p.json", R"({"render": {"renderer": "penalty",
                                                        "frequency_hz": -5}})");
  ExpectRefused(simulate + " --config " + p,
                {"render.frequency_hz (set in " + p + " as render.frequency_hz) has no effect"});
  const std::string tc = Config("tc.json", R"({"render": {"t_collision_s": 9}})");
  ExpectRefused(simulate + " --renderer impulse --config " + tc,
                {"render.t_collision_s (set in " + tc + " as render.t_collision_s)"});
  ExpectRefused("bench --steps 1 --warmup 0 --scene " + std::string(RIGIDTOUCH_SCENES) +
                    "/wall.xml --renderer penalty --restitution 0.5",
                {"render.restitution (set by --restitution) has no effect here"});
  // tap and serve, and a comparison where no renderer of the list uses the value
  ExpectRefused("tap --taps 1 --renderer penalty --frequency 77", {f_why + "penalty renderer"});
  ExpectRefused("tap --taps 1 --config " + tc + " --renderer impulse",
                {"render.t_collision_s (set in " + tc + " as render.t_collision_s)"});
  ExpectRefused("tap --taps 1 --compare penalty,impulse --frequency 77 --out-dir " +
                    (dir_ / "compare").string(),
                {f_why + "penalty or impulse renderers"});
  EXPECT_FALSE(fs::exists(dir_ / "compare"));
  ExpectRefused("serve --device sim --taps 1 --renderer impulse --t-collision 0.05", {tc_why});
  // what the renderer uses, the defaults, and a reference solver switched off are accepted
  EXPECT_EQ(RunCli(simulate + " --renderer impulse --restitution 0.5 --reference-solver").exit_code,
            0);
  EXPECT_EQ(RunCli(simulate + " --renderer train --frequency 100 --t-collision 0.05 "
                              "--restitution 0 --reference-solver")
                .exit_code,
            0);
  EXPECT_EQ(RunCli(simulate + " --renderer penalty").exit_code, 0);
  const std::string off = Config("off.json", R"({"render": {"reference_solver": false}})");
  EXPECT_EQ(RunCli(simulate + " --renderer penalty --config " + off).exit_code, 0);
  EXPECT_EQ(Json(RunCli("tap --taps 1 --json --renderer impulse"))["renderer"], "impulse");
}

// friction coefficients: >= 0, or exactly -1 for the MJCF geom friction; another negative value
// was taken as -1
TEST_F(SettingsCliTest, NegativeFrictionOtherThanMinusOneIsRefused) {
  const std::string simulate =
      "simulate --steps 1 --scene " + std::string(RIGIDTOUCH_SCENES) + "/wall.xml --config ";
  const std::string both =
      Config("mu.json", R"({"contact": {"friction_static": -0.5, "friction_kinetic": -0.2}})");
  ExpectRefused(simulate + both, {"parameter friction_static = -0.5 is out of range: valid >= 0, "
                                  "or -1 for the MJCF geom friction",
                                  "(set in " + both + " as contact.friction_static)"});
  const std::string kinetic = Config("k.json", R"({"contact": {"friction_kinetic": -0.2}})");
  ExpectRefused(simulate + kinetic, {"parameter friction_kinetic = -0.2 is out of range",
                                     "(set in " + kinetic + " as contact.friction_kinetic)"});
  const std::string mjcf =
      Config("m.json", R"({"contact": {"friction_static": -1, "friction_kinetic": 0}})");
  EXPECT_EQ(RunCli(simulate + mjcf).exit_code, 0);
}

// simulate and bench have no device (a constant tool force): a device setting is refused
// instead of dropped (or, for a coupling, moving the tool to a device that is not there)
TEST_F(SettingsCliTest, SimulateAndBenchRefuseDeviceSettings) {
  const std::string wall = " --steps 1 --scene " + std::string(RIGIDTOUCH_SCENES) + "/wall.xml";
  const std::string device = Config("d.json", R"({"device": {"max_force_N": 5,
      "coupling_stiffness_N_per_m": 1, "coupling_damping_Ns_per_m": 7}})");
  const std::string direct = Config("direct.json", R"({"device": {"coupling": "direct"}})");
  for (const std::string command : {"simulate", "bench --warmup 0"}) {
    const std::string name = command.substr(0, command.find(' '));
    ExpectRefused(command + wall + " --config " + device, {"device.max_force_N (set in " + device +
                                                           " as device.max_force_N) has no "
                                                           "effect here: " +
                                                           name + " has no device"});
    ExpectRefused(command + wall + " --config " + direct,
                  {"device.coupling (set in " + direct + " as device.coupling) has no effect"});
    for (const char* field :
         {"coupling_stiffness_N_per_m", "coupling_damping_Ns_per_m", "plausible_radius_m",
          "plausible_speed_mps", "plausible_angular_speed_radps"}) {
      const std::string one =
          Config(std::string(field) + ".json", "{\"device\": {\"" + std::string(field) + "\": 1}}");
      ExpectRefused(command + wall + " --config " + one,
                    {"device." + std::string(field) + " (set in " + one});
    }
    const std::string connect = Config("connect.json", R"({"device": {"connect": "sim"}})");
    ExpectRefused(command + wall + " --config " + connect, {"device.connect (set in " + connect});
    // the coupling simulate and bench run is none: writing it is not refused
    const std::string none = Config("none.json", R"({"device": {"coupling": "none"}})");
    EXPECT_EQ(RunCli(command + wall + " --config " + none).exit_code, 0) << command;
  }
}

// a scene law the user wrote that cannot hold a body is used and warned about, in tap as in
// simulate (tap loads its scene inside the library and printed no load warning)
// threads (issue 19): the flag beats the config file, both are used (bench reports them) and
// give the same run bit for bit; a count other than 1 or 2 is refused, naming where it was written
TEST_F(SettingsCliTest, ThreadsFromTheFlagOrTheConfigAreUsedAndOtherCountsRefused) {
  const std::string scene = std::string(RIGIDTOUCH_SCENES) + "/pile.xml";
  const std::string bench = "bench --json --steps 200 --warmup 0 --scene " + scene;
  const std::string two = Config("two.json", R"({"threads": 2})");
  const auto one_thread = Json(RunCli(bench));
  const auto from_file = Json(RunCli(bench + " --config " + two));
  const auto from_flag = Json(RunCli(bench + " --threads 1 --config " + two));
  EXPECT_EQ(one_thread["threads"], 1);
  EXPECT_EQ(from_file["threads"], 2);
  EXPECT_EQ(from_flag["threads"], 1);
  EXPECT_EQ(from_file["deepest_penetration_m"], one_thread["deepest_penetration_m"]);
  EXPECT_EQ(from_file["contacts"], one_thread["contacts"]);
  const CliResult flag = RunCli(bench + " --threads 3");
  EXPECT_EQ(flag.exit_code, 2);
  EXPECT_NE(flag.err.find("rigidtouch: error: --threads: 3 is out of range: valid 1 to 2"),
            std::string::npos)
      << flag.err;
  const std::string five = Config("five.json", R"({"threads": 5})");
  const CliResult file = RunCli(bench + " --config " + five);
  EXPECT_EQ(file.exit_code, 2);
  EXPECT_NE(file.err.find("rigidtouch: error: " + five + ": threads: 5 is out of range"),
            std::string::npos)
      << file.err;
}

TEST_F(SettingsCliTest, TapPrintsTheScenesLoadWarnings) {
  const std::string scene = Config("heavy.xml", R"(<mujoco><worldbody>
    <geom name="wall" type="plane" size="1 1 0.1"/>
    <body name="tool" pos="0 0 0.02"><freejoint/><geom type="sphere" size="0.005" mass="0.1"/></body>
    <body name="heavy" pos="0.3 0 0.1"><freejoint/><geom type="box" size="0.05 0.05 0.05"
      mass="20"/></body></worldbody></mujoco>)");
  const std::string soft = Config("soft.json", R"({"contact": {"scene_stiffness_N_per_m": 100}})");
  const CliResult r = RunCli("tap --taps 1 --scene " + scene + " --config " + soft);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: warning: scene_stiffness_N_per_m = 100 N/m cannot hold body "
                       "'heavy'"),
            std::string::npos)
      << r.err;
}

TEST_F(SettingsCliTest, HelpStatesTheOrder) {
  for (const char* command : {"tap", "serve", "simulate", "bench"}) {
    const CliResult r = RunCli(std::string(command) + " --help");
    EXPECT_NE(r.out.find("a flag overrides the config file"), std::string::npos) << command;
  }
}

// one voice: a malformed command line is bad input (status 2) with the one prefix, and --rate has
// one range in every subcommand
TEST(CliVoiceTest, MalformedCommandLinesExitTwoWithThePrefix) {
  for (const std::string args : {"tap --bogus", "tap --taps", "tap --taps x", "serve --duration -1",
                                 "device-sim --duration -2", "nosuchcommand"}) {
    const CliResult r = RunCli(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_EQ(r.err.rfind("rigidtouch: error: ", 0), 0u) << args << ": " << r.err;
  }
  for (const std::string command : {"tap", "serve", "device-sim"}) {
    for (const std::string rate : {"50", "50000"}) {
      const CliResult r = RunCli(command + " --rate " + rate);
      EXPECT_EQ(r.exit_code, 2) << command;
      EXPECT_NE(r.err.find("--rate: " + rate + " is out of range: valid 100 to 20000 Hz"),
                std::string::npos)
          << command << ": " << r.err;
    }
  }
  EXPECT_EQ(RunCli("tap --help").exit_code, 0);
}

}  // namespace
}  // namespace rigidtouch::test
