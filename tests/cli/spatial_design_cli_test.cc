// End-to-end for `cablecal design` on spatial robots: on irma4u and on a random asymmetric robot
// file written here, the plan CSV reads back as the robot's plan and simulate takes it, the
// summary carries its provenance, --json prints the same; too few poses, planar-only flags and a
// design with no verified start exit 2 or 3 with one message and nothing written. Few poses,
// two starts and few random sets: the point is the command, tests/design checks the design.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "common/random.h"
#include "common/version.h"
#include "experiment/spatial_plan.h"
#include "model/spatial_robot.h"
#include "tests/support/random_spatial_robot.h"
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

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class SpatialDesignCli : public ::testing::Test {
 protected:
  std::string Path(const std::string& name) const { return tmp_.Path(name); }
  std::string Read(const std::string& name) const { return tmp_.Read(name); }
  static std::string Irma4u() { return std::string(CABLECAL_SOURCE_DIR) + "/robots/irma4u.yaml"; }
  // A random asymmetric robot with 7 cables (tilted swivel axes, offset centre of mass, exits
  // at different heights), stiff cables and every sensor.
  std::string RandomRobotFile() const {
    cablecal::Rng rng(107);
    cablecal::SpatialRobot r = cablecal::testing::RandomSpatialRobot(rng, "random-asymmetric", 7);
    const double deg = M_PI / 180.0;
    r.sensors.inclinometer_rad = cablecal::RangedNoise{0.1 * deg, 0.05 * deg};
    r.sensors.laser_m = cablecal::RangedNoise{0.006, 0.0015};
    r.sensors.position = cablecal::SpatialSensors::Position{cablecal::RangedNoise{3e-4, 1e-4}, Eigen::Vector3d(0.02, 0, 0)};
    r.sensors.swivel_rad = cablecal::RangedNoise{0.1 * deg, 0.05 * deg};
    r.sensors.heading_rad = cablecal::RangedNoise{1.0 * deg, 0.5 * deg};
    r.sensors.load_cell_N = cablecal::RangedNoise{3.0, 1.0};
    for (cablecal::SpatialCable& c : r.cables) c.stiffness_N = c.stiffness_N.value_or(2e6);
    const std::string path = Path("random7.yaml");
    std::ofstream(path) << cablecal::SpatialRobotToYaml(r);
    return path;
  }
  cablecal::testing_support::TempDir tmp_;
};

// The fewest poses, as the refusal of one pose names them ("at least N poses are needed").
int FewestPoses(const std::string& robot, const std::string& out) {
  const RunResult r = RunCablecal("design --robot " + robot + " --poses 1 --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  std::smatch m;
  if (!std::regex_search(r.output, m, std::regex("--poses: at least ([0-9]+) poses are needed"))) {
    ADD_FAILURE() << r.output;
    return -1;
  }
  EXPECT_EQ(Count(r.output, "error"), 1) << r.output;
  EXPECT_FALSE(fs::exists(out));
  return std::stoi(m[1]);
}

TEST_F(SpatialDesignCli, PlanReadsBackAndSimulatesOnIrma4uAndARandomRobot) {
  // irma4u at its fewest poses (its sampler is the slow part: 0.25 s a pose); the random robot
  // at two more, as tests/design (at the fewest the information is barely regular).
  for (const auto& [robot, extra] : std::vector<std::pair<std::string, int>>{{Irma4u(), 0}, {RandomRobotFile(), 2}}) {
    SCOPED_TRACE(robot);
    fs::remove(Path("plan.csv"));
    const cablecal::SpatialRobot model = cablecal::LoadSpatialRobotFile(robot);
    const int fewest = FewestPoses(robot, Path("plan.csv"));
    ASSERT_GE(fewest, 2);
    const int n = fewest + extra;
    const std::string args = "design --robot " + robot + " --poses " + std::to_string(n) +
                             " --starts 2 --random-sets 3 --seed 5";
    const RunResult r = RunCablecal(args + " --out " + Path("plan.csv") + " --summary " + Path("summary.yaml"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::regex line("designed " + std::to_string(n) + " poses of " + model.name +
                          " \\(criterion a, best of 2 starts, [12] converged, [12] verified\\): trace of the "
                          "covariance [0-9.e+-]+ m\\^2, [0-9.]+ x (better|worse) than the median of 3 random sets");
    EXPECT_TRUE(std::regex_search(r.output, line)) << r.output;
    EXPECT_NE(r.output.find("the gauge holds "), std::string::npos) << r.output;
    // At the fewest poses a warning (and summary.yaml) says how little the readings leave over;
    // two more, nothing.
    const bool fewest_warned = r.output.find("poses are the fewest for these sensors") != std::string::npos;
    EXPECT_EQ(fewest_warned, extra == 0) << r.output;
    EXPECT_EQ(static_cast<bool>(YAML::LoadFile(Path("summary.yaml"))["information"]["redundancy_note"]), extra == 0)
        << Read("summary.yaml");

    // The robot's own plan: the reader and the check simulate applies accept it.
    const std::vector<cablecal::SpatialPlanPose> plan = cablecal::ReadSpatialPlanCsv(Path("plan.csv"), model.num_cables());
    ASSERT_EQ(static_cast<int>(plan.size()), n);
    EXPECT_NO_THROW(cablecal::CheckSpatialPlanMatchesRobot(model, plan, Path("plan.csv")));
    EXPECT_EQ(Read("plan.csv").rfind("# cablecal " + std::string(cablecal::Version()), 0), 0u);
    const RunResult sim = RunCablecal("simulate --robot " + robot + " --plan " + Path("plan.csv") + " --out " + Path("m.csv"));
    EXPECT_EQ(sim.exit_code, 0) << sim.output;
    EXPECT_NE(sim.output.find("simulated " + std::to_string(n) + " poses of " + model.name), std::string::npos)
        << sim.output;

    // The next round (--prior): the identification of those readings, planned around.
    if (extra > 0) {
      const RunResult id = RunCablecal("identify --robot " + robot + " --measurements " + Path("m.csv") + " --out " +
                                       Path("r.yaml"));
      ASSERT_EQ(id.exit_code, 0) << id.output;
      // One start, no random sets, no robustness: the prior's path through the CLI is under test.
      const RunResult next = RunCablecal("design --robot " + robot + " --poses " + std::to_string(n) +
                                         " --starts 1 --random-sets 0 --geometry-sigma 0 --prior " + Path("r.yaml") +
                                         " --out " + Path("next.csv") + " --summary " + Path("next.yaml"));
      ASSERT_EQ(next.exit_code, 0) << next.output;
      EXPECT_NE(next.output.find("verified, counting the prior's information): "), std::string::npos) << next.output;
      // What to identify with for the predicted covariance, when the gauge holds anything.
      EXPECT_TRUE(next.output.find("; identify with --gauge hold:") != std::string::npos ||
                  next.output.find("the gauge holds nothing") != std::string::npos)
          << next.output;
      EXPECT_NE(Read("next.yaml").find("  prior: \"" + Path("r.yaml") + "\""), std::string::npos) << Read("next.yaml");
    }

    const std::string summary = Read("summary.yaml");
    for (const std::string& key : {"cablecal: {version: \"" + std::string(cablecal::Version()) + "\", commit: ",
                                   std::string("command: \"cablecal design --robot "), std::string("criterion: a\n"),
                                   "poses: " + std::to_string(n) + "\n", std::string("seed: 5\n"),
                                   std::string("random_sets: {count: 3,"), std::string("starts: {count: 2,")}) {
      EXPECT_NE(summary.find(key), std::string::npos) << key << "\n" << summary;
    }

    // The gauge-fixed unknowns and the held ones, each a list of names, none in both.
    const YAML::Node information = YAML::LoadFile(Path("summary.yaml"))["information"];
    ASSERT_TRUE(information["free"].IsSequence()) << summary;
    ASSERT_TRUE(information["held"].IsSequence()) << summary;
    EXPECT_GT(information["free"].size(), 0u);
    for (const YAML::Node& f : information["free"]) {
      for (const YAML::Node& h : information["held"]) EXPECT_NE(f.as<std::string>(), h.as<std::string>());
    }

    // The robustness it holds for, said; irma4u (no tracker survey: the default 0.01 m) holds no
    // plan for true robots within 3 cm (a cable goes slack), so it designs at the largest k that
    // does and warns.
    EXPECT_NE(summary.find("robustness:\n  geometry_sigma_m: "), std::string::npos) << summary;
    EXPECT_NE(summary.find("  holds: \"each pose holds on "), std::string::npos) << summary;
    if (extra == 0) {
      EXPECT_NE(r.output.find("cablecal: warning: robustness lowered: the plan holds for "), std::string::npos) << r.output;
      EXPECT_NE(summary.find("robustness_lowered: "), std::string::npos) << summary;
    }

    // --json: the summary and the plan on stdout, the same poses, no file needed.
    if (extra == 0) continue;
    const RunResult json = RunCablecal(args + " --json");
    ASSERT_EQ(json.exit_code, 0) << json.output;
    EXPECT_EQ(json.output.rfind("{", 0), 0u) << json.output;
    EXPECT_EQ(Count(json.output, "{\"pose\": "), n) << json.output;
    std::smatch x;
    ASSERT_TRUE(std::regex_search(json.output, x, std::regex("\\{\"pose\": 1, \"x\": ([-0-9.e+]+),"))) << json.output;
    EXPECT_EQ(std::stod(x[1]), plan[0].q(0));
  }
}

TEST_F(SpatialDesignCli, HostileInputsExitTwoOrThreeWithOneMessageAndNothingWritten) {
  const std::string robot = Irma4u();
  std::ofstream(Path("prior.yaml")) << "robot: {}\n";
  struct Case {
    std::string flags, expected;
    int exit_code;
  };
  const std::string outputs = " --out " + Path("out.csv") + " --summary " + Path("out.yaml");
  const std::vector<Case> cases = {
      {"--poses 1", "--poses: at least 2 poses are needed", 2},
      {"--poses 3 --geometry-sigma 0.6", "--geometry-sigma: must be between 0 and 0.5 m (got 0.6)", 2},
      {"--poses 3 --robust-sigmas 11", "--robust-sigmas: must be between 0 and 10 (got 11)", 2},
      {"--poses 3 --prior " + Path("prior.yaml"), Path("prior.yaml") + ": not an identification result", 2},
      {"--poses 3 --prior " + Path(""), "is a folder, not an identification result", 2},
      {"--poses 3 --plot " + Path("out.png"), "--plot: a figure of a spatial plan is not yet served", 2},
      {"--poses 501", "--poses: at most 500 poses", 2},
      {"--poses nan", "--poses: must be a whole number from 1 to 100000 (got 'nan')", 2},
      {"--poses 3.5", "--poses: must be a whole number from 1 to 100000 (got '3.5')", 2},
      {"--poses 3 --criterion b", "--criterion", 2},
      {"--poses 3 --min-spacing -1", "--min-spacing", 2},
      // Poses 50 m apart in a 2 m frame: refused before any solve (the box less its margin is
      // 2.1 x 2.3 x 1.8 m, 3.6 m across).
      {"--poses 2 --starts 1 --random-sets 0 --min-spacing 50",
       "--min-spacing: 50 m is more than any two poses can be apart: the diagonal of the frame box less its margin is 3.6 m",
       2},
      // 3.5 m apart fits the box but not the workspace: no start converges, and none is reported as a plan.
      {"--poses 2 --starts 1 --random-sets 0 --min-spacing 3.5", "solver failure: none of the 1 starts gave verified poses", 3},
  };
  for (const Case& c : cases) {
    const RunResult r = RunCablecal("design --robot " + robot + " " + c.flags + outputs);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.flags << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.flags << "\nexpected: " << c.expected << "\ngot: " << r.output;
    EXPECT_EQ(Count(r.output, "cablecal: "), 1) << c.flags << "\n" << r.output;
    EXPECT_FALSE(fs::exists(Path("out.csv"))) << c.flags;
    EXPECT_FALSE(fs::exists(Path("out.yaml"))) << c.flags;
    EXPECT_FALSE(fs::exists(Path("out.png"))) << c.flags;
  }
}

}  // namespace
