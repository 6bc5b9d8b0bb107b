// End-to-end for identify and validate on spatial robots: sample -> simulate -> identify ->
// validate through the binary on a built-in robot and a random asymmetric robot file; the
// estimates against the truth file in their sigmas; the calibrated robot file's round trip;
// --json, --report; hostile inputs (exit 2, one message, nothing written).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "common/format.h"
#include "common/random.h"
#include "model/spatial_robot.h"
#include "tests/support/random_spatial_robot.h"
#include "tests/support/six_mixed_robot.h"
#include "tests/support/temp_dir.h"

namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code;
  std::string output;  // stdout and stderr
};

RunResult RunCablecal(const std::string& args) {
  const std::string command = std::string(CABLECAL_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

class SpatialIdentifyCli : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return tmp_.Path(name); }
  std::string Read(const std::string& name) const { return tmp_.Read(name); }
  static std::string Builtin(const std::string& name) {
    return std::string(CABLECAL_SOURCE_DIR) + "/robots/" + name + ".yaml";
  }
  // A random asymmetric 7-cable robot (tilted swivel axes, offset centre of mass, exits at
  // different heights) with every sensor and every cable stiff, as a file.
  std::string RandomRobotFile(bool relative_sensors = false) const {
    cablecal::Rng rng(107);
    cablecal::SpatialRobot r = cablecal::testing::RandomSpatialRobot(rng, "random-asymmetric", 7);
    const double deg = M_PI / 180.0;
    r.sensors.inclinometer_rad = cablecal::RangedNoise{0.1 * deg, 0.05 * deg};
    r.sensors.laser_m = cablecal::RangedNoise{0.006, 0.0015};
    r.sensors.position = cablecal::SpatialSensors::Position{cablecal::RangedNoise{3e-4, 1e-4}, Eigen::Vector3d(0.02, 0, 0)};
    r.sensors.load_cell_N = cablecal::RangedNoise{3.0, 1.0};
    if (relative_sensors) {
      r.sensors.swivel_rad = cablecal::RangedNoise{0.1 * deg, 0.05 * deg};
      r.sensors.heading_rad = cablecal::RangedNoise{1.0 * deg, 0.5 * deg};
    }
    for (cablecal::SpatialCable& c : r.cables) c.stiffness_N = c.stiffness_N.value_or(2e6);
    const std::string path = Path(relative_sensors ? "random7_all.yaml" : "random7.yaml");
    std::ofstream(path) << cablecal::SpatialRobotToYaml(r);
    return path;
  }
  // The measurement CSV `from` with only the named columns kept (and the provenance lines).
  void KeepColumns(const std::string& from, const std::string& to, const std::vector<std::string>& prefixes) {
    std::istringstream in(Read(from));
    std::ofstream out(Path(to));
    std::vector<bool> keep;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("#", 0) == 0) continue;
      const std::vector<std::string> cells = Split(line);
      if (keep.empty()) {
        for (const std::string& c : cells) {
          bool k = false;
          for (const std::string& p : prefixes) k = k || c == p || (c.rfind(p, 0) == 0 && std::isdigit(c[p.size()]));
          keep.push_back(k);
        }
      }
      std::string row;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (keep[i]) row += (row.empty() ? "" : ",") + cells[i];
      }
      out << row << "\n";
    }
  }
  // sample -> simulate with a geometry error: the plan, the readings and the truth file.
  void Simulate(const std::string& robot, int poses, const std::string& sigma, int seed, const std::string& stem) {
    const std::string s = std::to_string(seed);
    RunResult r = RunCablecal("sample --robot " + robot + " --poses " + std::to_string(poses) + " --seed " + s + " --out " +
                              Path(stem + "_plan.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = RunCablecal("simulate --robot " + robot + " --plan " + Path(stem + "_plan.csv") + " --geometry-sigma " + sigma +
                    " --seed " + s + " --skip-infeasible --out " + Path(stem + ".csv") + " --truth-out " +
                    Path(stem + "_truth.yaml"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // Every identified, not held, exit coordinate against the truth, in its sigma: the largest.
  static double WorstExitSigmas(const YAML::Node& result, const YAML::Node& truth) {
    double worst = 0.0;
    for (std::size_t i = 0; i < truth["cables"].size(); ++i) {
      for (int c = 0; c < 3; ++c) {
        const YAML::Node p = result["parameters"]["a" + std::to_string(i + 1) + "xyz"[c]];
        if (p["held"]) continue;
        const double error = p["value"].as<double>() - truth["cables"][i]["exit"][c].as<double>();
        worst = std::max(worst, std::abs(error) / p["std"].as<double>());
      }
    }
    return worst;
  }
  cablecal::testing_support::TempDir tmp_;
};

// Cogiro (its position sensor) and a random robot (every sensor): the exits within 4.5 sigma of
// the truth (the outlier bound: 24 and 21 coordinates), the calibrated robot file loads and
// holds the identified geometry, and validate prefers it to the nominal robot on held-out poses.
TEST_F(SpatialIdentifyCli, SimulateIdentifyValidateOnABuiltInAndARandomRobot) {
  struct Case {
    std::string robot, sigma;
    int m;
  };
  for (const Case& c : {Case{Builtin("cogiro"), "0.002", 8}, Case{RandomRobotFile(), "0.0003", 7}}) {
    SCOPED_TRACE(c.robot);
    Simulate(c.robot, 24, c.sigma, 1, "cal");
    const RunResult id = RunCablecal("identify --robot " + c.robot + " --measurements " + Path("cal.csv") + " --out " +
                                     Path("result.yaml") + " --calibrated-robot " + Path("calibrated.yaml"));
    ASSERT_EQ(id.exit_code, 0) << id.output;
    EXPECT_NE(id.output.find("(ml, gauge auto, statics)"), std::string::npos) << id.output;
    EXPECT_NE(id.output.find("worst reading: pose "), std::string::npos) << id.output;
    const YAML::Node result = YAML::LoadFile(Path("result.yaml"));
    const YAML::Node truth = YAML::LoadFile(Path("cal_truth.yaml"));
    EXPECT_EQ(result["status"].as<std::string>(), "converged");
    EXPECT_EQ(result["robot"]["kind"].as<std::string>(), "spatial");
    // Exits, lengths, then (the stretch modelled) the platform's mass and centre of mass.
    EXPECT_EQ(result["parameters"].size(), static_cast<std::size_t>(4 * c.m + 4));
    EXPECT_EQ(result["covariance"].size(), static_cast<std::size_t>(4 * c.m + 4));
    EXPECT_GT(result["parameters"]["mass"]["std"].as<double>(), 0.0);
    EXPECT_LT(WorstExitSigmas(result, truth), 4.5);
    // The initial lengths: what the winches paid out at home, the nominal home's commands.
    // The calibrated robot file: every identified value, every other key the nominal file's.
    const cablecal::SpatialRobot nominal = cablecal::LoadSpatialRobotFile(c.robot);
    const cablecal::SpatialRobot calibrated = cablecal::LoadSpatialRobotFile(Path("calibrated.yaml"));
    for (int i = 0; i < c.m; ++i) {
      const std::string k = std::to_string(i + 1);
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(calibrated.cables[i].p_F_exit_m(a), result["parameters"]["a" + k + "xyz"[a]]["value"].as<double>());
      }
      ASSERT_TRUE(calibrated.cables[i].initial_length_m);
      EXPECT_EQ(*calibrated.cables[i].initial_length_m, result["parameters"]["l" + k + "0"]["value"].as<double>());
      EXPECT_EQ(calibrated.cables[i].p_P_anchor_m, nominal.cables[i].p_P_anchor_m);
      EXPECT_EQ(calibrated.cables[i].stiffness_N, nominal.cables[i].stiffness_N);
    }
    EXPECT_EQ(calibrated.name, nominal.name);
    EXPECT_EQ(calibrated.platform_mass_kg, result["parameters"]["mass"]["value"].as<double>());
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(calibrated.p_P_com_m(a), result["parameters"][std::string("com") + "xyz"[a]]["value"].as<double>());
    }
    EXPECT_EQ(calibrated.com_sigma_m, nominal.com_sigma_m);  // the priors stay the file's
    EXPECT_EQ(cablecal::SpatialRobotToYaml(calibrated).find("initial_length") != std::string::npos, true);

    // Held-out poses of the same true robot: the calibrated robot predicts them better.
    const RunResult plan = RunCablecal("sample --robot " + c.robot + " --poses 10 --seed 9 --out " + Path("hold_plan.csv"));
    ASSERT_EQ(plan.exit_code, 0) << plan.output;
    const RunResult sim = RunCablecal("simulate --robot " + c.robot + " --plan " + Path("hold_plan.csv") + " --truth " +
                                      Path("cal_truth.yaml") + " --seed 9 --skip-infeasible --out " + Path("hold.csv"));
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const RunResult val = RunCablecal("validate --robot " + Path("calibrated.yaml") + " --nominal " + c.robot +
                                      " --measurements " + Path("hold.csv") + " --out " + Path("val.csv") +
                                      " --summary " + Path("val.yaml"));
    ASSERT_EQ(val.exit_code, 0) << val.output;
    const YAML::Node summary = YAML::LoadFile(Path("val.yaml"));
    const double ratio = summary["nominal_over_calibrated"]["position_rms"].as<double>();
    EXPECT_GT(ratio, 2.0) << val.output;
    // Within a few times the tracker's noise: the calibration explains the held-out readings.
    EXPECT_LT(summary["calibrated"]["position"]["rms_m"].as<double>(),
              5.0 * summary["sensor_noise"]["position_sigma_m"].as<double>())
        << val.output;
    EXPECT_EQ(Split(Read("val.csv").substr(Read("val.csv").find("\npose,") + 1, 200))[1], c.m == 7 ? "roll" : "px");
    // identify --holdout: the report validates the calibration as validate does.
    const RunResult rep = RunCablecal("identify --robot " + c.robot + " --measurements " + Path("cal.csv") +
                                      " --json --report " + Path("report") + " --holdout " + Path("hold.csv"));
    ASSERT_EQ(rep.exit_code, 0) << rep.output;
    const YAML::Node in_report = YAML::LoadFile(Path("report/validation.yaml"));
    EXPECT_NEAR(in_report["nominal_over_calibrated"]["position_rms"].as<double>(), ratio, 1e-6 * ratio);
    EXPECT_NE(Read("report/report.md").find("## Validation on held-out poses"), std::string::npos);
  }
}

// The readings lack a position sensor: encoders, inclinometer, laser and load cells leave the
// frame's x and y unseen (its yaw is seen through the tilted swivel axes); the default gauge
// holds two exit coordinates and names the directions; --json carries the same content;
// --report writes its files.
// A new user's 4-cable suspended robot: exits at four heights, the centre of mass off in x, y
// and z, cable 3's swivel axis tilted by 10 degrees, a tension floor of 5 N.
const char kLab4Yaml[] = R"(name: lab4
kind: spatial
gravity: 9.81
frame: {min: [-1.5, -1.2, 0.0], max: [1.5, 1.2, 2.5]}
platform:
  mass: 8.0
  com: [0.02, -0.015, -0.06]
  com_sigma: 0.002
  anchors:
    - [-0.15, -0.12, 0.05]
    - [0.15, -0.12, 0.05]
    - [0.15, 0.12, 0.05]
    - [-0.15, 0.12, 0.05]
cables:
  - {exit: [-1.45, -1.15, 2.40], swivel_axis: [0, 0, 1], pulley_radius: 0.025}
  - {exit: [1.45, -1.15, 2.20], swivel_axis: [0, 0, 1], pulley_radius: 0.025}
  - {exit: [1.45, 1.15, 2.45], swivel_axis: [0.17, 0.0, 0.985], pulley_radius: 0.025}
  - {exit: [-1.45, 1.15, 2.30], swivel_axis: [0, 0, 1], pulley_radius: 0.025}
tension: {min: 5.0, max: 300.0}
limits: {tilt_max_deg: 25, margin: 0.05}
home: [0.0, 0.0, 1.2]
home_rpy_deg: [0, 0, 0.15]
sensors:
  encoder: {sigma: 0.00005}
  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}
  swivel: {accuracy_deg: 0.1, repeatability_deg: 0.05}
  laser: {accuracy: 0.006, repeatability: 0.0015}
)";

// validate on that robot's own noise-free readings at poses tilted by up to 22 degrees and up
// to a metre above home: every reading kept and predicted to rounding. Its sensors' pose guess
// had stopped short of three of the ten (Gauss-Newton from home), which validate then refused
// as another assembly.
// A pose id read again after other poses is taken as a repeated reading of that pose, and said
// (as the planar reader says it, naming the line and the first reading's); repeats in a row are
// the usual layout of repeated readings and say nothing.
TEST_F(SpatialIdentifyCli, APoseIdReadAgainAfterOtherPosesIsSaid) {
  Simulate(Builtin("cogiro"), 12, "0.002", 3, "cal");
  std::ifstream in(Path("cal.csv"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::size_t first = 0;  // pose 1's row: the first that is not a comment or the header
  while (first < lines.size() && (lines[first].empty() || lines[first][0] == '#' || lines[first].rfind("pose", 0) == 0)) {
    ++first;
  }
  ASSERT_LT(first, lines.size());
  ASSERT_EQ(lines[first].rfind("1,", 0), 0u) << lines[first];
  const auto write = [&](const std::string& name, std::size_t insert_after) {
    std::ofstream out(Path(name));
    for (std::size_t k = 0; k < lines.size(); ++k) {
      out << lines[k] << "\n";
      if (k == insert_after) out << lines[first] << "\n";
    }
  };
  write("again.csv", lines.size() - 1);
  const RunResult again = RunCablecal("identify --robot " + Builtin("cogiro") + " --measurements " + Path("again.csv") +
                                      " --out " + Path("r.yaml"));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  const std::string said = "cablecal: warning: " + Path("again.csv") + ":" + std::to_string(lines.size() + 1) +
                           ": pose 1 read again after other poses (first at " + Path("again.csv") + ":" +
                           std::to_string(first + 1) + ")";
  EXPECT_NE(again.output.find(said), std::string::npos) << again.output;
  write("in_a_row.csv", first);
  const RunResult row = RunCablecal("identify --robot " + Builtin("cogiro") + " --measurements " + Path("in_a_row.csv") +
                                    " --out " + Path("r.yaml"));
  EXPECT_EQ(row.exit_code, 0) << row.output;
  EXPECT_EQ(row.output.find("read again"), std::string::npos) << row.output;
}

TEST_F(SpatialIdentifyCli, AFourCableRobotPredictsItsOwnTiltedNoiseFreeReadings) {
  std::ofstream(Path("lab4.yaml")) << kLab4Yaml;
  RunResult r = RunCablecal("sample --robot " + Path("lab4.yaml") + " --poses 10 --seed 7 --yaw-range-deg 1 --out " +
                            Path("plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("simulate --robot " + Path("lab4.yaml") + " --plan " + Path("plan.csv") +
                  " --geometry-sigma 0 --sensors none --no-encoder-noise --out " + Path("m.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("validate --robot " + Path("lab4.yaml") + " --measurements " + Path("m.csv") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const YAML::Node v = YAML::Load(r.output);
  EXPECT_EQ(v["readings"].as<int>(), 10) << r.output;
  EXPECT_EQ(v["rows"].size(), 10u) << r.output;
  EXPECT_LT(v["calibrated"]["inclinometer"]["max_abs_rad"].as<double>(), 1e-9) << r.output;
  EXPECT_LT(v["calibrated"]["laser"]["max_abs_m"].as<double>(), 1e-9) << r.output;
  EXPECT_LT(v["calibrated"]["swivel"]["max_abs_rad"].as<double>(), 1e-9) << r.output;
  // The console counts in the singular for one pose, and says nothing of skipping when nothing
  // was skipped.
  r = RunCablecal("sample --robot " + Path("lab4.yaml") + " --poses 1 --seed 3 --out " + Path("one.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("simulate --robot " + Path("lab4.yaml") + " --plan " + Path("one.csv") + " --out " + Path("m1.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("validate --robot " + Path("lab4.yaml") + " --measurements " + Path("m1.csv") + " --out " +
                  Path("v1.csv") + " --skip-infeasible");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("validated on 1 pose of "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("cablecal: skipped"), std::string::npos) << r.output;
}

// Another new user's 4-cable robot with stretching cables (E*A 2e4 N) read by its encoders and an
// inclinometer alone: a true robot 2 mm off predicts its own noise-free readings at every pose.
// The sensors' guess takes the cables as rigid and lay far off (a yaw of -2.1 rad) at one pose
// of ten, which validate refused as another assembly; the forward model is now started again
// there, at home and at what the sensors read, and the equilibrium that agrees with them kept.
TEST_F(SpatialIdentifyCli, AStretchingFourCableTruthPredictsItsOwnNoiseFreeReadings) {
  std::ofstream(Path("lab4s.yaml")) << R"(name: lab4s
kind: spatial
gravity: 9.81
frame: {min: [-1.5, -1.0, 0.0], max: [1.5, 1.0, 2.5]}
platform:
  mass: 10.0
  com: [0.012, -0.008, 0.03]
  anchors:
    - [-0.10, -0.08, 0.12]
    - [0.10, -0.08, 0.12]
    - [0.10, 0.08, 0.12]
    - [-0.10, 0.08, 0.12]
cables:
  - {exit: [-1.5, -1.0, 2.30], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 20000.0}
  - {exit: [1.5, -1.0, 2.40], swivel_axis: [0.1736, 0, 0.9848], pulley_radius: 0.03, stiffness: 20000.0}
  - {exit: [1.5, 1.0, 2.20], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 20000.0}
  - {exit: [-1.5, 1.0, 2.35], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 20000.0}
tension: {min: 5.0, max: 500.0}
limits: {tilt_max_deg: 20, margin: 0.05}
home: [0.0, 0.0, 1.0]
sensors:
  encoder: {sigma: 0.00005}
  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}
)";
  RunResult r = RunCablecal("sample --robot " + Path("lab4s.yaml") + " --poses 10 --seed 7 --yaw-range-deg 1 --out " +
                            Path("plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* seed : {"1", "3"}) {
    r = RunCablecal("simulate --robot " + Path("lab4s.yaml") + " --plan " + Path("plan.csv") +
                    " --geometry-sigma 0.002 --sensors none --no-encoder-noise --seed " + seed + " --out " +
                    Path("m.csv") + " --truth-out " + Path("truth.yaml"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = RunCablecal("validate --robot " + Path("truth.yaml") + " --measurements " + Path("m.csv") + " --json");
    ASSERT_EQ(r.exit_code, 0) << seed << ": " << r.output;
    const YAML::Node v = YAML::Load(r.output);
    EXPECT_EQ(v["rows"].size(), 10u) << r.output;
    EXPECT_LT(v["calibrated"]["inclinometer"]["max_abs_rad"].as<double>(), 1e-9) << r.output;
  }
}

// The 4-cable robot below with tension.min raised to 22.5 N, just under its home's smallest
// tension (22.94 N, cable 1): a true robot 0.3 mm off (seed 3), identified, holds that home with
// cable 1 below the bound, so the calibrated file does not load (tension_low). The warning's
// advice is about the bound, not about moving home (its initial lengths are the home's). (A new
// user's 5-cable robot did this before 5-cable equilibria were walked along their curve.)
TEST_F(SpatialIdentifyCli, ACalibratedRobotBeyondATensionBoundAtHomeIsToldAboutTheBound) {
  std::string yaml = kLab4Yaml;
  const std::string bounds = "tension: {min: 5.0, max: 300.0}";
  ASSERT_NE(yaml.find(bounds), std::string::npos);
  yaml.replace(yaml.find(bounds), bounds.size(), "tension: {min: 22.5, max: 300.0}");
  std::ofstream(Path("lab4m.yaml")) << yaml;
  ASSERT_EQ(RunCablecal("sample --robot " + Path("lab4m.yaml") + " --poses 12 --seed 7 --yaw-range-deg 1 --out " +
                        Path("plan.csv"))
                .exit_code,
            0);
  ASSERT_EQ(RunCablecal("simulate --robot " + Path("lab4m.yaml") + " --plan " + Path("plan.csv") +
                        " --geometry-sigma 0.0003 --seed 3 --skip-infeasible --out " + Path("m.csv"))
                .exit_code,
            0);
  const RunResult id = RunCablecal("identify --robot " + Path("lab4m.yaml") + " --measurements " + Path("m.csv") +
                                   " --out " + Path("r.yaml") + " --calibrated-robot " + Path("cal.yaml"));
  ASSERT_EQ(id.exit_code, 0) << id.output;
  EXPECT_NE(id.output.find("the file was written but does not load"), std::string::npos) << id.output;
  EXPECT_NE(id.output.find("tension_low (cable 1"), std::string::npos) << id.output;
  EXPECT_NE(id.output.find("holds only beyond a tension bound"), std::string::npos) << id.output;
  EXPECT_EQ(id.output.find("cannot hold: identify with a nominal home nearer"), std::string::npos) << id.output;
}

// A new user's 4-cable robot that holds its home only in a yaw band of 0.1 degrees (tension
// min 5 N): identified from 3 designed poses, its calibrated file keeps the nominal home, which
// the identified robot cannot hold (no_equilibrium). The file is written with the result, and a
// warning says it does not load and why, before any later command finds it.
TEST_F(SpatialIdentifyCli, ACalibratedRobotThatCannotHoldTheNominalHomeIsSaid) {
  std::ofstream(Path("lab4.yaml")) << kLab4Yaml;
  std::ofstream(Path("lab4.csv")) << R"(pose,dl1,dl2,dl3,dl4,roll,pitch,z,sw1,sw2,sw3,sw4
1,-0.056030688552647624,1.296645110938713,0.493128581450505,-1.8764287835677156,0.08560845762465168,0.16465523848731073,2.2322114038292664,0.8779242453108226,0.011071736534192382,-0.7334082966966924,-0.34543583824510876
2,0.45275408261562466,-1.0729147616091097,-0.694100056567956,0.6910539826158995,0.015105394261672917,-0.22518148444608155,1.9517027802605873,-0.3385175376044606,-0.5472801752697858,0.6372514587499957,0.1693131724874341
3,0.9355165638409344,1.1123144628567068,0.7446980357724348,0.46915574238371843,0.41414072089087245,0.13978842679183884,0.11284214684293445,0.28900658550795066,-0.11781574337091823,-0.30379601822426966,0.20405935356846278
)";
  const RunResult id = RunCablecal("identify --robot " + Path("lab4.yaml") + " --measurements " + Path("lab4.csv") +
                                   " --out " + Path("r.yaml") + " --calibrated-robot " + Path("cal.yaml"));
  ASSERT_EQ(id.exit_code, 0) << id.output;
  EXPECT_NE(id.output.find("cablecal: warning: --calibrated-robot: the file was written but does not load: " +
                           Path("cal.yaml") + ":"),
            std::string::npos)
      << id.output;
  EXPECT_NE(id.output.find("no_equilibrium"), std::string::npos) << id.output;
  // The advice fits the reason, and no longer says to move home (the lengths are home's).
  EXPECT_NE(id.output.find("which the identified robot cannot hold"), std::string::npos) << id.output;
  EXPECT_NE(id.output.find("moving home alone does not mend it"), std::string::npos) << id.output;
  EXPECT_TRUE(fs::exists(Path("cal.yaml")));
  EXPECT_TRUE(fs::exists(Path("r.yaml")));
  // The nominal file loads (the band holds its home); the calibrated one does not, as warned.
  EXPECT_EQ(RunCablecal("workspace --robot " + Path("lab4.yaml") + " --out " + Path("w.csv")).exit_code, 0);
  EXPECT_EQ(RunCablecal("validate --robot " + Path("cal.yaml") + " --measurements " + Path("lab4.csv") + " --out " +
                        Path("v.csv")).exit_code,
            2);
}

// A new user's robot with two stretching cables (tests/support/six_mixed_robot.h), its fewest
// designed poses read without noise: identified with the statics, with a warning that nothing is
// left to check the fit; with --equilibrium off (every cable inextensible) the readings do not
// fit, and the message says the stretch is what was left out (it blamed a laser reading).
TEST_F(SpatialIdentifyCli, TheFewestPosesOfAStretchingRobotWarnAndEquilibriumOffNamesTheStretch) {
  // Its two elastic cables ten times softer than the support file's (E A 6000 and 8000 N: about 3
  // cm of stretch at its tensions). With the file's (3 mm) the inclinometer's and the laser's
  // sigmas absorb the stretch left out: measured at 7, 10, 20 and 30 sampled poses and at the 7
  // poses designed since the design's solves end when their criterion stalls, every fit passed.
  std::string yaml = cablecal::testing::SixMixedRobotYaml();
  for (const auto& [stiff, soft] : {std::pair<std::string, std::string>{"stiffness: 60000.0", "stiffness: 6000.0"},
                                    {"stiffness: 80000.0", "stiffness: 8000.0"}}) {
    const std::size_t at = yaml.find(stiff);
    ASSERT_NE(at, std::string::npos) << stiff;
    yaml.replace(at, stiff.size(), soft);
  }
  std::ofstream(Path("six.yaml")) << yaml;
  RunResult r = RunCablecal("design --robot " + Path("six.yaml") + " --poses 7 --starts 1 --random-sets 0 "
                            "--geometry-sigma 0 --out " + Path("d7.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("simulate --robot " + Path("six.yaml") + " --plan " + Path("d7.csv") +
                  " --sensors none --no-encoder-noise --out " + Path("m7.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("identify --robot " + Path("six.yaml") + " --measurements " + Path("m7.csv") + " --out " +
                  Path("r.yaml"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cablecal: warning: no redundancy: 109 reading values for as many unknowns"),
            std::string::npos)
      << r.output;
  EXPECT_NE(Read("r.yaml").find("no redundancy"), std::string::npos);
  r = RunCablecal("identify --robot " + Path("six.yaml") + " --measurements " + Path("m7.csv") +
                  " --equilibrium off --out " + Path("off.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("(--equilibrium off models every cable as inextensible, and this robot's cables with a "
                          "stiffness stretch under load"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(Path("off.yaml")));
}

TEST_F(SpatialIdentifyCli, TheGaugeFromTheDataJsonAndReport) {
  const std::string robot = RandomRobotFile();
  Simulate(robot, 20, "0.00002", 3, "m");
  KeepColumns("m.csv", "tilt.csv", {"pose", "dl", "roll", "pitch", "z", "f"});
  const RunResult id = RunCablecal("identify --robot " + robot + " --measurements " + Path("tilt.csv") + " --out " +
                                   Path("r.yaml") + " --report " + Path("report"));
  ASSERT_EQ(id.exit_code, 0) << id.output;
  EXPECT_NE(id.output.find("unseen by the readings (2): a translation along x of the frame; a translation along y "
                           "of the frame"),
            std::string::npos)
      << id.output;
  EXPECT_NE(id.output.find("held at nominal (the gauge): "), std::string::npos) << id.output;
  EXPECT_NE(id.output.find("not in the data (no columns): position"), std::string::npos) << id.output;
  const YAML::Node r = YAML::LoadFile(Path("r.yaml"));
  EXPECT_EQ(r["held"].size(), 2u);
  EXPECT_EQ(r["null_directions"].size(), 2u);
  EXPECT_EQ(r["null_directions"][0]["vector"].size(), 32u);  // 7 exits, 7 lengths, mass and centre of mass
  for (const YAML::Node& h : r["held"]) EXPECT_TRUE(r["parameters"][h.as<std::string>()]["held"].as<bool>());
  EXPECT_EQ(r["missing_sensors"][0].as<std::string>(), "position");
  for (const char* file : {"report.md", "result.yaml", "parameters.csv", "exits.csv", "residuals.csv", "exits.png",
                           "residuals.png"}) {
    EXPECT_TRUE(fs::exists(Path(std::string("report/") + file))) << file;
  }
  EXPECT_NE(Read("report/report.md").find("## The gauge"), std::string::npos);
  // The estimates' table names each cell's unit: the mass's sigma in g, not "mm or mrad".
  const std::string report = Read("report/report.md");
  EXPECT_TRUE(std::regex_search(report, std::regex("\\| mass \\| [0-9.]+ kg \\| [0-9.]+ kg \\| [0-9.e+-]+ g \\| [0-9.e+-]+ g \\|")))
      << report;
  EXPECT_TRUE(std::regex_search(report, std::regex("\\| l10 \\| [0-9.]+ m \\| [0-9.]+ m \\| [0-9.e+-]+ mm \\| [0-9.e+-]+ mm \\|")))
      << report;
  const RunResult json = RunCablecal("identify --robot " + robot + " --measurements " + Path("tilt.csv") + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const YAML::Node j = YAML::Load(json.output);  // JSON is YAML
  EXPECT_EQ(j["held"].size(), 2u);
  // Two runs of the solver agree to rounding (the heap's alignment changes Eigen's summation
  // order in the last bits), not bit for bit.
  EXPECT_NEAR(j["parameters"]["l10"]["value"].as<double>(), r["parameters"]["l10"]["value"].as<double>(), 1e-9);
  EXPECT_EQ(j["poses"].size(), r["poses"].size());
  EXPECT_EQ(j["readings"].size(), r["readings"].size());
}

// validate's model of the lab against simulate's: the truth file (its initial lengths the
// nominal home's commands) predicts its own noise-free readings, every sensor (the swivel
// encoders and the heading zeroed where it settles at home), to rounding.
TEST_F(SpatialIdentifyCli, TheTruthPredictsItsOwnNoiseFreeReadings) {
  const std::string robot = RandomRobotFile(true);
  RunResult r = RunCablecal("sample --robot " + robot + " --poses 8 --seed 2 --out " + Path("plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("simulate --robot " + robot + " --plan " + Path("plan.csv") +
                  " --geometry-sigma 0.00002 --sensors none --no-encoder-noise --skip-infeasible --seed 2 --out " +
                  Path("m.csv") + " --truth-out " + Path("truth.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("validate --robot " + Path("truth.yaml") + " --nominal " + robot + " --measurements " + Path("m.csv") +
                  " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const YAML::Node v = YAML::Load(r.output);
  ASSERT_EQ(v["compared"].size(), 6u) << r.output;
  const std::vector<std::pair<std::string, double>> bounds = {
      {"inclinometer", 1e-9}, {"laser", 1e-9}, {"position", 1e-9}, {"swivel", 1e-9}, {"heading", 1e-9}, {"load_cell", 1e-5}};
  for (const auto& [sensor, bound] : bounds) {
    const YAML::Node e = v["calibrated"][sensor];
    ASSERT_TRUE(e.IsMap()) << sensor;
    const std::string unit = sensor == "load_cell" ? "N" : (sensor == "laser" || sensor == "position" ? "m" : "rad");
    EXPECT_LT(e["max_abs_" + unit].as<double>(), bound) << sensor;
    // The nominal robot, 20 um off in every exit coordinate, is seen off by more.
    EXPECT_GT(v["nominal"][sensor]["max_abs_" + unit].as<double>(), 100 * bound) << sensor;
  }
  EXPECT_EQ(v["rows"].size(), v["readings"].as<std::size_t>());
}

// --identify anchors on the random robot with every sensor (the tracker and the inclinometer
// see the anchors): b1x .. b7z in result.yaml and --json, within 4.5 sigma of the truth (the
// simulation's anchors are the nominal file's), and the calibrated robot file carries them.
TEST_F(SpatialIdentifyCli, IdentifyAnchorsEndToEnd) {
  const std::string robot = RandomRobotFile();
  Simulate(robot, 60, "0.00002", 4, "m");  // 43 poses the true robot holds
  const RunResult id = RunCablecal("identify --robot " + robot + " --measurements " + Path("m.csv") +
                                   " --identify anchors --out " + Path("r.yaml") + " --calibrated-robot " +
                                   Path("cal.yaml"));
  ASSERT_EQ(id.exit_code, 0) << id.output;
  EXPECT_NE(id.output.find("(ml, gauge auto, anchors, statics)"), std::string::npos) << id.output;
  EXPECT_NE(id.output.find("  b7z = "), std::string::npos) << id.output;
  const YAML::Node r = YAML::LoadFile(Path("r.yaml"));
  EXPECT_EQ(r["identify"].as<std::string>(), "anchors");
  EXPECT_EQ(r["held"].size(), 0u);
  const cablecal::SpatialRobot nominal = cablecal::LoadSpatialRobotFile(robot);
  const cablecal::SpatialRobot calibrated = cablecal::LoadSpatialRobotFile(Path("cal.yaml"));
  for (int i = 0; i < 7; ++i) {
    for (int c = 0; c < 3; ++c) {
      const YAML::Node b = r["parameters"]["b" + std::to_string(i + 1) + "xyz"[c]];
      ASSERT_TRUE(b.IsMap()) << i << c;
      const double value = b["value"].as<double>(), std = b["std"].as<double>();
      EXPECT_GT(std, 0.0);
      EXPECT_LT(std::abs(value - nominal.cables[i].p_P_anchor_m(c)), 4.5 * std) << "b" << i + 1 << "xyz"[c];
      EXPECT_NEAR(calibrated.cables[i].p_P_anchor_m(c), value, 1e-12 * (1.0 + std::abs(value)));
    }
  }
  EXPECT_NE(Read("cal.yaml").find("platform anchors identified"), std::string::npos);
  const RunResult json = RunCablecal("identify --robot " + robot + " --measurements " + Path("m.csv") +
                                     " --identify anchors --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const YAML::Node j = YAML::Load(json.output);
  EXPECT_EQ(j["parameters"].size(), r["parameters"].size());
  EXPECT_NEAR(j["parameters"]["b3y"]["value"].as<double>(), r["parameters"]["b3y"]["value"].as<double>(), 1e-9);
}

// identify --plan on the random asymmetric robot: the result the starts from home give (the
// same parameters to a twentieth of their sigma), a warning naming the poses the plan lacks, and
// refusals naming the plan file for another experiment's pose ids or another robot's plan.
TEST_F(SpatialIdentifyCli, ThePlanStartsEachPoseFromItsCommandedPose) {
  const std::string robot = RandomRobotFile();
  Simulate(robot, 24, "0.0003", 1, "p");
  const std::string id = "identify --robot " + robot + " --measurements " + Path("p.csv");
  RunResult r = RunCablecal(id + " --out " + Path("home.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal(id + " --plan " + Path("p_plan.csv") + " --out " + Path("planned.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("no row in the plan"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("settled more than"), std::string::npos) << r.output;
  const YAML::Node home = YAML::LoadFile(Path("home.yaml"));
  const YAML::Node planned = YAML::LoadFile(Path("planned.yaml"));
  for (const auto& p : home["parameters"]) {
    const std::string name = p.first.as<std::string>();
    if (p.second["held"]) continue;
    EXPECT_LT(std::abs(planned["parameters"][name]["value"].as<double>() - p.second["value"].as<double>()),
              0.05 * p.second["std"].as<double>())
        << name;
  }
  // The plan without its rows of the second and third poses read (its header and comments kept).
  std::vector<std::string> read_ids;
  std::istringstream readings(Read("p.csv"));
  for (std::string line; std::getline(readings, line) && read_ids.size() < 3;) {
    if (!line.empty() && std::isdigit(line[0])) read_ids.push_back(Split(line)[0]);
  }
  ASSERT_EQ(read_ids.size(), 3u);
  std::istringstream in(Read("p_plan.csv"));
  std::ofstream part(Path("part_plan.csv"));
  std::ofstream other(Path("other_plan.csv"));
  for (std::string line; std::getline(in, line);) {
    const bool row = !line.empty() && std::isdigit(line[0]);
    if (!row || (Split(line)[0] != read_ids[1] && Split(line)[0] != read_ids[2])) part << line << "\n";
    other << (row ? "100" : "") << line << "\n";
  }
  part.close();
  other.close();
  r = RunCablecal(id + " --plan " + Path("part_plan.csv") + " --out " + Path("part.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: poses " + read_ids[1] + ", " + read_ids[2] +
                          " have no row in the plan: started from home"),
            std::string::npos)
      << r.output;
  r = RunCablecal(id + " --plan " + Path("other_plan.csv") + " --out " + Path("other.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(Path("other_plan.csv") + ": column 'pose': none of the readings' "), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(Path("other.yaml")));
  // simulate numbers the readings by the plan's pose column: that plan's own readings match it.
  r = RunCablecal("simulate --robot " + robot + " --plan " + Path("other_plan.csv") +
                  " --geometry-sigma 0.0003 --seed 1 --skip-infeasible --out " + Path("other.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(Read("other.csv").find("\n100" + read_ids[0] + ","), std::string::npos) << Read("other.csv");
  r = RunCablecal("identify --robot " + robot + " --measurements " + Path("other.csv") + " --plan " +
                  Path("other_plan.csv") + " --out " + Path("other.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("no row in the plan"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("settled more than"), std::string::npos) << r.output;
  fs::remove(Path("other.yaml"));
  r = RunCablecal("sample --robot " + Builtin("cogiro") + " --poses 3 --out " + Path("cogiro_plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal(id + " --plan " + Path("cogiro_plan.csv") + " --out " + Path("other.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(Path("cogiro_plan.csv") + ":"), std::string::npos) << r.output;  // another robot's
  EXPECT_FALSE(fs::exists(Path("other.yaml")));
  r = RunCablecal("identify --measurements " + Path("p.csv") + " --plan " + Path("p_plan.csv") + " --out " +
                  Path("other.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--plan: serves spatial robots only"), std::string::npos) << r.output;
}

// A fit may end with a cable estimated pushing (the tensions are unknowns without bounds): a
// new user's soft 8-cable robot, 10 of 30 sampled poses held by a true robot 2 cm off, converged
// with tensions down to -55 N and said nothing. It now warns, naming the poses.
TEST_F(SpatialIdentifyCli, ACableEstimatedPushingIsWarnedOf) {
  std::ofstream(Path("soft8b.yaml")) <<
      "name: soft8b\n"
      "kind: spatial\n"
      "gravity: 9.81\n"
      "frame: {min: [-2.0, -1.5, 0.0], max: [2.0, 1.5, 3.0]}\n"
      "platform:\n"
      "  mass: 40.0\n"
      "  com: [0.03, -0.02, 0.10]\n"
      "  anchors:\n"
      "    - [0.15, -0.14, 0.0]\n"
      "    - [-0.15, 0.10, 0.25]\n"
      "    - [-0.15, -0.08, 0.0]\n"
      "    - [0.14, 0.10, 0.25]\n"
      "    - [-0.15, 0.14, 0.0]\n"
      "    - [0.15, -0.10, 0.25]\n"
      "    - [0.15, 0.08, 0.0]\n"
      "    - [-0.15, -0.10, 0.25]\n"
      "cables:\n"
      "  - {exit: [-1.93, -1.46, 2.85], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [-2.00, -1.38, 2.70], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [-1.98, 1.40, 2.95], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [-1.90, 1.47, 2.80], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [1.94, 1.44, 2.60], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [2.00, 1.36, 2.75], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [1.99, -1.41, 2.90], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "  - {exit: [1.92, -1.48, 2.65], swivel_axis: [0, 0, 1], pulley_radius: 0.03, stiffness: 2.0e4}\n"
      "tension: {min: 15.0, max: 1000.0}\n"
      "limits: {tilt_max_deg: 25, margin: 0.05}\n"
      "home: [0.1, -0.05, 1.2]\n"
      "home_rpy_deg: [0, 0, 0]\n"
      "sensors:\n"
      "  encoder: {sigma: 0.00005}\n"
      "  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}\n"
      "  laser: {accuracy: 0.003, repeatability: 0.001}\n";
  const std::string robot = Path("soft8b.yaml");
  RunResult r = RunCablecal("sample --robot " + robot + " --poses 30 --seed 12 --yaw-range-deg 90 --out " + Path("plan.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("simulate --robot " + robot + " --plan " + Path("plan.csv") +
                  " --geometry-sigma 0.02 --seed 12 --skip-infeasible --out " + Path("meas.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCablecal("identify --robot " + robot + " --measurements " + Path("meas.csv") + " --out " + Path("res.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const YAML::Node result = YAML::LoadFile(Path("res.yaml"));
  double lowest_N = 0.0;
  for (const auto& pose : result["poses"]) {
    for (const auto& t : pose["tensions_N"]) lowest_N = std::min(lowest_N, t.as<double>());
  }
  ASSERT_LT(lowest_N, 0.0) << "the case this test is about: a cable estimated pushing";
  EXPECT_NE(r.output.find("have a cable estimated pushing, a negative tension"), std::string::npos) << r.output;
  EXPECT_NE(Read("res.yaml").find("estimated pushing"), std::string::npos);  // among result.yaml's warnings
}

TEST_F(SpatialIdentifyCli, HostileInputsExitTwoWithOneMessageAndWriteNothing) {
  const std::string robot = RandomRobotFile();
  Simulate(robot, 12, "0", 5, "m");
  KeepColumns("m.csv", "tilt.csv", {"pose", "dl", "roll", "pitch", "z", "f"});
  KeepColumns("m.csv", "pos.csv", {"pose", "dl", "px", "py", "pz"});  // the anchors' rotations unseen
  KeepColumns("m.csv", "enc.csv", {"pose", "dl"});  // stretching cables, their tensions unread: too few values
  std::string other = Read("m.csv");
  other.replace(other.find("\npose,dl1"), 9, "\npose,dx1");
  std::ofstream(Path("misspelt.csv")) << other;
  const std::string out = " --out " + Path("out.yaml") + " --calibrated-robot " + Path("cal.yaml");
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"--measurements " + Path("misspelt.csv"), "dx1"},
      {"--measurements " + Path("m.csv") + " --gauge hold:a8x", "'a8x' is not an exit coordinate of this 7-cable robot"},
      {"--measurements " + Path("tilt.csv") + " --gauge hold:a1x", "does not fix the gauge: no reading fixes"},
      // What the readings as a whole cannot do is named by their file.
      {"--measurements " + Path("enc.csv"), Path("enc.csv") + ": "},
      {"--measurements " + Path("enc.csv"), "too few to determine the geometry; measure more poses or add a sensor"},
      {"--measurements " + Path("m.csv") + " --estimator paper", "--estimator paper: serves planar robots only"},
      {"--measurements " + Path("m.csv") + " --geometry-prior 0.001", "--geometry-prior: serves planar robots only"},
      // The planar and the spatial choices both named (helper-23: the planar list alone read as
      // though auto were refused).
      {"--measurements " + Path("m.csv") + " --gauge bogus",
       "'bogus' is no gauge: a1x, prior or none for a planar robot; auto, none, prior or hold:"},
      {"--measurements " + Path("m.csv") + " --gauge hold:a1x,a1y,", "an empty name in the hold list"},
      {"--measurements " + Path("m.csv") + " --gauge \"hold:a1x, a1y\"", "' a1y': a space in the hold list"},
      {"--measurements " + Path("m.csv") + " --identify foo", "--identify: foo: expected exits"},
      {"--measurements " + Path("m.csv") + " --gauge hold:b1x", "'b1x' is a platform anchor coordinate"},
      {"--measurements " + Path("pos.csv") + " --identify anchors --gauge prior --equilibrium off",
       "the tracker's prior is on the exit points"},
      {"--measurements " + Builtin("cogiro"), "column"},
  };
  for (const Case& c : cases) {
    const RunResult r = RunCablecal("identify --robot " + robot + " " + c.args + out);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\nexpected: " << c.expected << "\ngot: " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), c.args.find("bogus") != std::string::npos ? 2 : 1)
        << r.output;
    EXPECT_FALSE(fs::exists(Path("out.yaml"))) << c.args;
    EXPECT_FALSE(fs::exists(Path("cal.yaml"))) << c.args;
    fs::remove(Path("out.yaml"));  // so that a case wrongly accepted leaves no trace for the next
    fs::remove(Path("cal.yaml"));
  }
  // A solve that stops short is exit 3 with Ceres' reason, and writes nothing.
  const RunResult stopped =
      RunCablecal("identify --robot " + robot + " --measurements " + Path("m.csv") + " --max-iterations 1" + out);
  EXPECT_EQ(stopped.exit_code, 3) << stopped.output;
  EXPECT_NE(stopped.output.find(Path("m.csv") + ": "), std::string::npos) << stopped.output;
  EXPECT_FALSE(fs::exists(Path("out.yaml")));
  EXPECT_FALSE(fs::exists(Path("cal.yaml")));
  // The spatial gauges are refused on a planar robot, naming the flag.
  const RunResult planar = RunCablecal("identify --measurements " + Path("m.csv") + " --gauge auto" + out);
  EXPECT_EQ(planar.exit_code, 2) << planar.output;
  EXPECT_NE(planar.output.find("--gauge auto: serves spatial robots only"), std::string::npos) << planar.output;
  const RunResult planar_anchors = RunCablecal("identify --measurements " + Path("m.csv") + " --identify anchors" + out);
  EXPECT_EQ(planar_anchors.exit_code, 2) << planar_anchors.output;
  EXPECT_NE(planar_anchors.output.find("--identify anchors: serves spatial robots only"), std::string::npos)
      << planar_anchors.output;
  // validate: another robot's readings, a planar nominal.
  RunResult r = RunCablecal("validate --robot " + robot + " --nominal " + std::string(CABLECAL_SOURCE_DIR) +
                            "/robots/wang2022.yaml --measurements " + Path("m.csv") + " --out " + Path("v.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--nominal: "), std::string::npos) << r.output;
  r = RunCablecal("validate --robot " + robot + " --measurements " + Path("enc.csv") + " --out " + Path("v.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("nothing to compare the predictions with"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(Path("v.csv")));
  // A reading whose cable 1 was paid out 1.5 m more: the platform would settle far from where
  // the sensors read it. Named by its line and by the flag of the robot that cannot hold it.
  std::vector<std::string> lines;
  {
    std::istringstream in(Read("m.csv"));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  std::size_t first_row = 0;
  while (first_row < lines.size() && (lines[first_row].empty() || lines[first_row][0] == '#' ||
                                      lines[first_row].rfind("pose", 0) == 0)) {
    ++first_row;
  }
  ASSERT_LT(first_row, lines.size());
  std::vector<std::string> cells = Split(lines[first_row]);
  cells[1] = cablecal::FormatDouble(std::stod(cells[1]) + 1.5);
  std::string joined;
  for (const std::string& c : cells) joined += (joined.empty() ? "" : ",") + c;
  lines[first_row] = joined;
  {
    std::ofstream out(Path("far.csv"));
    for (const std::string& line : lines) out << line << "\n";
  }
  r = RunCablecal("validate --robot " + robot + " --measurements " + Path("far.csv") + " --out " + Path("v.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(Path("far.csv") + ":" + std::to_string(first_row + 1) + ": --robot's robot random-asymmetric "
                          "cannot hold the commanded lengths ("),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(Path("v.csv")));
}

}  // namespace
