// What identify writes for a spatial robot, at the library's level: the calibrated robot (its
// initial lengths are where the encoders read zero for every stage that reads the file) and
// result.yaml / its JSON, on an identification of noise-free readings of a random robot.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "common/random.h"
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "identify/spatial_identify.h"
#include "identify/spatial_report.h"
#include "tests/support/random_spatial_robot.h"

namespace cablecal {
namespace {

struct Identified {
  SpatialRobot nominal, truth;
  SpatialIdentifyOptions options;
  SpatialIdentifyResult result;
};

// A random 7-cable robot with stiff cables, an inclinometer, a laser and load cells, 0.1 mm off
// its file; 15 noise-free readings.
Identified IdentifyRandomRobot() {
  Rng rng(41);
  Identified out;
  out.nominal = testing::RandomSpatialRobot(rng, "random", 7);
  out.nominal.sensors.inclinometer_rad = RangedNoise{0.002, 0.0};
  out.nominal.sensors.laser_m = RangedNoise{0.003, 0.0};
  out.nominal.sensors.load_cell_N = RangedNoise{3.0, 0.0};
  for (SpatialCable& c : out.nominal.cables) c.stiffness_N = c.stiffness_N.value_or(2e6);
  const std::vector<SpatialPlanPose> plan = SampleSpatialPoses(out.nominal, 15, 3, 0.3);
  SpatialSimulationOptions sim;
  sim.noisy = NoisySensors::kNone;
  sim.encoder_noise = false;
  sim.skip_infeasible = true;
  const SpatialPlanSimulation run = SimulateSpatialPlan(out.nominal, std::nullopt, 1e-4, plan, sim, 3, "plan");
  out.truth = run.truth;
  out.result = IdentifySpatial(out.nominal, run.experiment.measurements, out.options);
  return out;
}

TEST(SpatialReport, CalibratedRobotCarriesTheIdentifiedZeroOfTheEncoders) {
  const Identified id = IdentifyRandomRobot();
  ASSERT_TRUE(id.result.converged()) << id.result.message;
  const SpatialRobot calibrated = CalibratedSpatialRobot(id.nominal, id.result);
  const int m = id.nominal.num_cables();
  for (int i = 0; i < m; ++i) {
    EXPECT_EQ(calibrated.cables[i].p_F_exit_m, id.result.geometry.segment<3>(3 * i));
    ASSERT_TRUE(calibrated.cables[i].initial_length_m);
    // Noise-free readings: the truth's zero (the nominal home's commands), to the solver's tolerance.
    EXPECT_NEAR(*calibrated.cables[i].initial_length_m, *id.truth.cables[i].initial_length_m, 1e-6) << i;
  }
  // Every stage that reads the file takes its encoders' zero from it: the plan's home lengths and
  // the identification's start.
  const Eigen::VectorXd l0 = id.result.geometry.segment(3 * m, m);
  EXPECT_EQ(SpatialHome(calibrated).paid_out_m, l0);
  EXPECT_EQ(NominalSpatialGeometry(calibrated, false, false).segment(3 * m, m), l0);
  // Back through the file, bit for bit.
  const SpatialRobot back = LoadSpatialRobotFromString(SpatialRobotToYaml(calibrated), "calibrated");
  for (int i = 0; i < m; ++i) EXPECT_EQ(back.cables[i].initial_length_m, calibrated.cables[i].initial_length_m);
}

TEST(SpatialReport, ResultYamlAndJsonHoldTheSameResult) {
  const Identified id = IdentifyRandomRobot();
  ASSERT_TRUE(id.result.converged()) << id.result.message;
  const YAML::Node yaml = YAML::Load(SpatialIdentifyResultYaml(id.nominal, id.options, id.result, "cmd"));
  const YAML::Node json = YAML::Load(SpatialIdentifyResultJson(id.nominal, id.options, id.result, "cmd"));
  for (const YAML::Node* doc : {&yaml, &json}) {
    const YAML::Node& d = *doc;
    EXPECT_EQ(d["status"].as<std::string>(), "converged");
    EXPECT_EQ(d["command"].as<std::string>(), "cmd");
    ASSERT_EQ(d["parameters"].size(), id.result.names.size());
    for (std::size_t k = 0; k < id.result.names.size(); ++k) {
      const YAML::Node p = d["parameters"][id.result.names[k]];
      EXPECT_EQ(p["value"].as<double>(), id.result.geometry(k));
      EXPECT_EQ(p["std"].as<double>(), id.result.sigma(k));
      EXPECT_EQ(static_cast<bool>(p["held"]), std::count(id.result.held.begin(), id.result.held.end(),
                                                         id.result.names[k]) == 1);
    }
    EXPECT_EQ(d["held"].size(), id.result.held.size());
    EXPECT_EQ(d["null_directions"].size(), id.result.null_directions.size());
    ASSERT_EQ(d["poses"].size(), id.result.poses.size());
    EXPECT_EQ(d["poses"][0]["yaw"].as<double>(), id.result.poses[0](5));
    EXPECT_EQ(d["poses"][0]["tensions_N"].size(), 7u);
    EXPECT_EQ(d["readings"].size(), id.result.fits.size());
    EXPECT_EQ(d["covariance"][3][5].as<double>(), id.result.covariance(3, 5));
    EXPECT_EQ(d["worst_reading"]["sigmas"].as<double>(), id.result.worst_residual);
    // Encoders, inclinometer, laser, load cells: their RMS in their units, noise-free ~0.
    EXPECT_LT(d["residual_rms"]["encoder_m"].as<double>(), 1e-8);
    EXPECT_TRUE(d["residual_rms"]["load_cell_N"]);
  }
}

}  // namespace
}  // namespace cablecal
