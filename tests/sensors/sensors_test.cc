// The sensors stage: the bench fit recovers a known error model with honest standard errors,
// its block pastes into a robot file, and the identification's correction removes what
// simulate --systematic-errors adds.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/random.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "model/sensor_model.h"
#include "sensors/sensors.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A bench's truth: the systematic error, and the accuracy and repeatability as 3-sigma ranges
// (the accuracy drawn once per reference value, the repeatability once per reading: the
// estimator's model, README "Sensor error models").
struct BenchTruth {
  SystematicSensorErrors systematic;
  double accuracy = 0.0, repeatability = 0.0;
};

std::vector<BenchReading> MakeBench(BenchSensor sensor, const BenchTruth& truth, const std::vector<double>& references,
                                    int repeats, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<BenchReading> out;
  for (const double reference : references) {
    const double accuracy_error = rng.Normal(0.0, truth.accuracy / 3.0);
    const double read = sensor == BenchSensor::kLaser ? LaserReading(truth.systematic, reference)
                                                      : InclinometerReading(truth.systematic, reference);
    for (int k = 0; k < repeats; ++k) {
      out.push_back({reference, read + accuracy_error + rng.Normal(0.0, truth.repeatability / 3.0), ""});
    }
  }
  return out;
}

// -60 to 60 degrees every 4 (31 references): the paper's inclinometer range.
std::vector<double> AngleReferences() {
  std::vector<double> r;
  for (int deg = -60; deg <= 60; deg += 4) r.push_back(deg * kDeg);
  return r;
}
// 0.2 to 2.9 m every 0.1 m (28 references): the paper's laser range.
std::vector<double> DistanceReferences() {
  std::vector<double> r;
  for (int k = 2; k <= 29; ++k) r.push_back(0.1 * k);
  return r;
}

BenchTruth PaperInclinometer() {
  BenchTruth t;
  t.systematic.inclinometer_offset_rad = 0.02 * kDeg;
  t.systematic.inclinometer_sec_coefficient_rad = -0.24 * kDeg;
  t.accuracy = 0.1 * kDeg;
  t.repeatability = 0.05 * kDeg;
  return t;
}
BenchTruth PaperLaser() {
  BenchTruth t;
  t.systematic.laser_offset_m = 0.004;
  t.accuracy = 0.006;
  t.repeatability = 0.0015;
  return t;
}

TEST(BenchFit, InclinometerRecoversTheModelWithinItsStandardErrors) {
  const BenchTruth truth = PaperInclinometer();
  const InclinometerFit f = FitInclinometer(MakeBench(BenchSensor::kInclinometer, truth, AngleReferences(), 10, 7), "b");
  EXPECT_EQ(f.bench.readings, 310);
  EXPECT_EQ(f.bench.references, 31);
  EXPECT_EQ(f.bench.repeated_references, 31);
  EXPECT_NEAR(f.offset_rad, truth.systematic.inclinometer_offset_rad, 3.0 * f.offset_se_rad);
  EXPECT_NEAR(f.sec_coefficient_rad, truth.systematic.inclinometer_sec_coefficient_rad, 3.0 * f.sec_coefficient_se_rad);
  // The standard errors are what 31 references at 0.1 degree (3 sigma) allow: a few
  // thousandths of a degree, not tenths.
  EXPECT_LT(f.offset_se_rad, 0.02 * kDeg);
  EXPECT_LT(f.sec_coefficient_se_rad, 0.05 * kDeg);
  // 279 degrees of freedom for the repeatability, 29 for the accuracy.
  EXPECT_NEAR(f.repeatability_rad / truth.repeatability, 1.0, 0.15);
  EXPECT_NEAR(f.accuracy_rad / truth.accuracy, 1.0, 0.4);
}

TEST(BenchFit, LaserRecoversTheOffsetWithinItsStandardError) {
  const BenchTruth truth = PaperLaser();
  const LaserFit f = FitLaser(MakeBench(BenchSensor::kLaser, truth, DistanceReferences(), 8, 3), "b");
  EXPECT_EQ(f.bench.readings, 224);
  EXPECT_NEAR(f.offset_m, 0.004, 3.0 * f.offset_se_m);
  EXPECT_LT(f.offset_se_m, 0.001);
  EXPECT_NEAR(f.repeatability_m / truth.repeatability, 1.0, 0.15);
  EXPECT_NEAR(f.accuracy_m / truth.accuracy, 1.0, 0.4);
}

// Over 400 benches the errors in units of their standard error spread as Student's t with
// references - coefficients degrees of freedom (standard deviation sqrt(nu / (nu - 2))), and
// the squared ranges average to the true ones (their estimators are unbiased for the variances).
TEST(BenchFit, StandardErrorsAreHonestAndRangesUnbiasedOverManyBenches) {
  constexpr int kBenches = 400;
  const BenchTruth incl = PaperInclinometer(), laser = PaperLaser();
  double z_offset = 0, z_sec = 0, z_laser = 0, acc2 = 0, rep2 = 0, lacc2 = 0, lrep2 = 0;
  for (int s = 0; s < kBenches; ++s) {
    const InclinometerFit f =
        FitInclinometer(MakeBench(BenchSensor::kInclinometer, incl, AngleReferences(), 4, 1000 + s), "b");
    z_offset += std::pow((f.offset_rad - incl.systematic.inclinometer_offset_rad) / f.offset_se_rad, 2);
    z_sec += std::pow((f.sec_coefficient_rad - incl.systematic.inclinometer_sec_coefficient_rad) / f.sec_coefficient_se_rad, 2);
    acc2 += std::pow(f.accuracy_rad, 2);
    rep2 += std::pow(f.repeatability_rad, 2);
    const LaserFit l = FitLaser(MakeBench(BenchSensor::kLaser, laser, DistanceReferences(), 4, 5000 + s), "b");
    z_laser += std::pow((l.offset_m - 0.004) / l.offset_se_m, 2);
    lacc2 += std::pow(l.accuracy_m, 2);
    lrep2 += std::pow(l.repeatability_m, 2);
  }
  const auto t_std = [](double nu) { return std::sqrt(nu / (nu - 2.0)); };
  // The sample standard deviation of 400 draws is within about 7 % (two of its standard errors).
  EXPECT_NEAR(std::sqrt(z_offset / kBenches) / t_std(29), 1.0, 0.12);
  EXPECT_NEAR(std::sqrt(z_sec / kBenches) / t_std(29), 1.0, 0.12);
  EXPECT_NEAR(std::sqrt(z_laser / kBenches) / t_std(27), 1.0, 0.12);
  // The accuracy's variance is a difference of two estimates floored at zero: a few percent.
  EXPECT_NEAR(acc2 / kBenches / std::pow(incl.accuracy, 2), 1.0, 0.08);
  EXPECT_NEAR(rep2 / kBenches / std::pow(incl.repeatability, 2), 1.0, 0.03);
  EXPECT_NEAR(lacc2 / kBenches / std::pow(laser.accuracy, 2), 1.0, 0.08);
  EXPECT_NEAR(lrep2 / kBenches / std::pow(laser.repeatability, 2), 1.0, 0.03);
}

std::string FitError(BenchSensor sensor, const std::vector<BenchReading>& readings) {
  try {
    if (sensor == BenchSensor::kLaser) {
      FitLaser(readings, "bench.csv");
    } else {
      FitInclinometer(readings, "bench.csv");
    }
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchFit, BenchesThatCannotDetermineTheModelAreRefused) {
  const auto incl = BenchSensor::kInclinometer;
  EXPECT_EQ(FitError(incl, {{0.1, 0.1, ""}}),
            "bench.csv: 1 reading of 1 reference value: the offset, the sec coefficient and the accuracy need readings "
            "at 3 or more different reference values");
  EXPECT_NE(FitError(incl, {{0.0, 0.0, ""}, {0.0, 0.001, ""}, {0.5, 0.5, ""}, {0.5, 0.501, ""}}).find("at 3 or more"),
            std::string::npos);
  EXPECT_NE(FitError(incl, {{0.0, 0.0, ""}, {0.3, 0.3, ""}, {0.5, 0.5, ""}}).find("no reference value was read more than once"),
            std::string::npos);
  EXPECT_NE(FitError(incl, {{-0.5, -0.5, ""}, {0.5, 0.5, ""}, {0.5, 0.501, ""}}).find("every reference has the same |theta|"),
            std::string::npos);
  EXPECT_NE(FitError(BenchSensor::kLaser, {{1.0, 1.0, ""}, {1.0, 1.001, ""}}).find("at 2 or more different"),
            std::string::npos);
  EXPECT_EQ(FitError(BenchSensor::kLaser, {{1.0, 1.0, ""}, {1.0, 1.001, ""}, {2.0, 2.0, ""}}), "");
}

std::string RepeatError(BenchSensor sensor, const std::vector<BenchReading>& readings) {
  try {
    CheckReadingsAgainstTheirReference(sensor, readings);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// One reading 40 sigma of the repeatability from its reference's other readings: least squares
// takes it in whole and the fitted repeatability grows several times, so the check refuses it
// by its place and column; clean benches of the paper's size pass, and so does a bench too small
// to judge (fewer than kBenchOutlierMinDegrees degrees of freedom).
TEST(BenchFit, AReadingFarFromItsReferencesOthersIsRefused) {
  for (const BenchSensor sensor : {BenchSensor::kLaser, BenchSensor::kInclinometer}) {
    const bool laser = sensor == BenchSensor::kLaser;
    const BenchTruth truth = laser ? PaperLaser() : PaperInclinometer();
    const std::vector<double> references = laser ? DistanceReferences() : AngleReferences();
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      EXPECT_EQ(RepeatError(sensor, MakeBench(sensor, truth, references, 4, seed)), "") << seed;
    }
    std::vector<BenchReading> bench = MakeBench(sensor, truth, references, 4, 7);
    for (std::size_t k = 0; k < bench.size(); ++k) bench[k].where = "bench.csv:" + std::to_string(k + 2);
    const double clean = laser ? FitLaser(bench, "b").repeatability_m : FitInclinometer(bench, "b").repeatability_rad;
    bench[9].reading += 40.0 * truth.repeatability / 3.0;
    const double inflated = laser ? FitLaser(bench, "b").repeatability_m : FitInclinometer(bench, "b").repeatability_rad;
    EXPECT_GT(inflated / clean, 3.0);  // what the check prevents
    const std::string message = RepeatError(sensor, bench);
    const std::string column = laser ? "reading_m" : "reading_rad";
    EXPECT_TRUE(std::regex_search(message, std::regex("^bench\\.csv:11: column '" + column +
                                                      "': \\S+ (m|rad) is ([2-4][0-9])[0-9.]* sigma from the other "
                                                      "readings of its reference .* check it, or drop that row$")))
        << message;
    // Too few repeats to judge a reading by the others: not refused.
    const std::vector<BenchReading> small(bench.begin(), bench.begin() + 8);
    EXPECT_EQ(RepeatError(sensor, small), "");
  }
}

std::string ReadError(BenchSensor sensor, const std::string& csv) {
  std::istringstream in(csv);
  try {
    ReadBenchCsv(sensor, in, "bench.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchCsv, ReadByColumnNameWithOthersIgnored) {
  std::istringstream in("# a lab's log\ntime;reading_rad;reference_rad\n10:00;0.0012;0\n10:01;0.5242;0.5236\n");
  std::vector<std::string> ignored;
  const std::vector<BenchReading> r = ReadBenchCsv(BenchSensor::kInclinometer, in, "b.csv", ';',
                                                   [&](const std::vector<std::string>& names) { ignored = names; });
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1].reference, 0.5236);
  EXPECT_EQ(r[1].reading, 0.5242);
  EXPECT_EQ(r[1].where, "b.csv:4");
  EXPECT_EQ(ignored, std::vector<std::string>{"time"});
}

TEST(BenchCsv, HostileCellsAreRefusedWithLineAndColumn) {
  const auto incl = BenchSensor::kInclinometer, laser = BenchSensor::kLaser;
  const std::string ih = "reference_rad,reading_rad\n", lh = "reference_m,reading_m\n";
  const struct {
    BenchSensor sensor;
    std::string csv, expected;
  } cases[] = {
      {incl, ih + "0,0\n0.1,abc\n", "^bench\\.csv:3: column 'reading_rad': must be a finite number \\(got 'abc'\\)"},
      {incl, ih + "nan,0\n", "^bench\\.csv:2: column 'reference_rad': must be a finite number \\(got 'nan'\\)"},
      {incl, ih + "0,0\n1.5708,1.5708\n", "^bench\\.csv:3: column 'reference_rad': 1\\.5708 rad is at or beyond \\+-90 degrees"},
      {incl, ih + "45,45.1\n", "bench\\.csv:2: column 'reference_rad': 45 rad .* \\(degrees\\? angles are in radians\\)"},
      {incl, ih + "0.5,0.7\n", "bench\\.csv:2: column 'reading_rad': differs from the reference by 0\\.1999.* rad, more than 10 degrees"},
      {laser, lh + "1.0,1.001\n-0.5,-0.5\n", "^bench\\.csv:3: column 'reference_m': -0\\.5 m is negative"},
      {laser, lh + "1.0,-0.001\n", "^bench\\.csv:2: column 'reading_m': -0\\.001 m is negative"},
      {laser, lh + "1500,1501\n", "bench\\.csv:2: column 'reference_m': 1500 m is more than 100 m: millimetres\\?"},
      {laser, "reference_m,reading\n1,1\n", "^bench\\.csv:1: header: no column 'reading_m'"},
      {laser, lh, "^bench\\.csv: has a header but no data rows"},
      {laser, lh + "1,1,1\n", "^bench\\.csv:2: expected 2 cells"},
  };
  for (const auto& c : cases) {
    const std::string message = ReadError(c.sensor, c.csv);
    EXPECT_TRUE(std::regex_search(message, std::regex(c.expected))) << c.csv << "\n" << message;
  }
}

// The fitted block replaces a robot file's sensors block as it is and reads back the fit.
TEST(BenchFit, TheBlockPastesIntoARobotFile) {
  SensorsFit fit;
  fit.inclinometer = FitInclinometer(MakeBench(BenchSensor::kInclinometer, PaperInclinometer(), AngleReferences(), 5, 1),
                                     "incl.csv");
  const std::string yaml = SensorsFitYaml(BuiltinRobot(), fit, "cablecal sensors fit --inclinometer incl.csv");
  EXPECT_EQ(yaml.rfind("# cablecal ", 0), 0u) << yaml;
  EXPECT_NE(yaml.find("\n# command: cablecal sensors fit --inclinometer incl.csv\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("laser, encoder and tracker\n# entries are those of wang2022"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("\n#   e = offset + k (sec theta - 1): offset "), std::string::npos) << yaml;
  const std::size_t block = yaml.find("\nsensors:\n");
  ASSERT_NE(block, std::string::npos) << yaml;
  std::string robot = BuiltinRobotYaml();
  robot = robot.substr(0, robot.find("sensors:\n")) + yaml.substr(block + 1);
  const Robot r = LoadRobotFromString(robot, "pasted.yaml");
  EXPECT_NEAR(r.sensors.systematic.inclinometer_offset_rad, fit.inclinometer->offset_rad, 1e-14);
  EXPECT_NEAR(r.sensors.systematic.inclinometer_sec_coefficient_rad, fit.inclinometer->sec_coefficient_rad, 1e-14);
  EXPECT_NEAR(r.sensors.inclinometer_accuracy_rad, fit.inclinometer->accuracy_rad, 1e-14);
  EXPECT_NEAR(r.sensors.inclinometer_repeatability_rad, fit.inclinometer->repeatability_rad, 1e-14);
  EXPECT_EQ(r.sensors.laser_accuracy_m, BuiltinRobot().sensors.laser_accuracy_m);
  EXPECT_EQ(r.sensors.systematic.laser_offset_m, 0.0);
  EXPECT_EQ(r.sensors.encoder_sigma_m, BuiltinRobot().sensors.encoder_sigma_m);
  // The bench reached 60 degrees, the robot's range: nothing extrapolated.
  EXPECT_TRUE(FitWarnings(BuiltinRobot(), fit).empty());
  std::vector<double> narrow;
  for (int deg = -30; deg <= 30; deg += 5) narrow.push_back(deg * kDeg);
  fit.inclinometer = FitInclinometer(MakeBench(BenchSensor::kInclinometer, PaperInclinometer(), narrow, 5, 1), "incl.csv");
  ASSERT_EQ(FitWarnings(BuiltinRobot(), fit).size(), 1u);
  EXPECT_NE(FitWarnings(BuiltinRobot(), fit)[0].find("the sec term is extrapolated"), std::string::npos);
}

TEST(BenchFit, AFitNoRobotFileWouldHoldIsRefused) {
  BenchTruth truth = PaperLaser();
  truth.systematic.laser_offset_m = 0.15;  // beyond kMaxLaserOffset_m: a unit slip on the bench
  SensorsFit fit;
  fit.laser = FitLaser(MakeBench(BenchSensor::kLaser, truth, DistanceReferences(), 3, 2), "laser.csv");
  try {
    FittedSensors(BuiltinRobot(), fit);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("laser.csv: the fitted sensors.laser.offset would be refused by the robot file"),
              std::string::npos)
        << e.what();
  }
}

// ---- simulate --systematic-errors and identify's correction ----------------------------

Robot WithSystematicErrors() {
  Robot r = BuiltinRobot();
  r.sensors.systematic.laser_offset_m = 0.02;  // a laser mounted 2 cm off its zero
  r.sensors.systematic.inclinometer_offset_rad = 0.05 * kDeg;
  r.sensors.systematic.inclinometer_sec_coefficient_rad = 0.5 * kDeg;
  return r;
}

TEST(SystematicErrors, OffTheSimulationIsTheSameBitForBit) {
  const Robot plain = BuiltinRobot(), with = WithSystematicErrors();
  const std::vector<PlanPose> plan = SampleFeasiblePoses(plain, 12, 3);
  SimulationOptions off;
  const std::string reference = MeasurementsCsv(SimulatePlan(plain, {}, 0.01, plan, off, 4, "p").experiment.measurements, "");
  EXPECT_EQ(MeasurementsCsv(SimulatePlan(with, {}, 0.01, plan, off, 4, "p").experiment.measurements, ""), reference);
  SimulationOptions on;
  on.systematic_errors = true;
  EXPECT_EQ(MeasurementsCsv(SimulatePlan(plain, {}, 0.01, plan, on, 4, "p").experiment.measurements, ""), reference)
      << "zero terms add nothing";
  // On, each reading is off by the model's error at the true pose, the noise draws unchanged.
  const PlanSimulation a = SimulatePlan(plain, {}, 0.01, plan, off, 4, "p");
  const PlanSimulation b = SimulatePlan(with, {}, 0.01, plan, on, 4, "p");
  for (std::size_t j = 0; j < plan.size(); ++j) {
    EXPECT_NEAR(b.experiment.measurements[j].value(SensorId::kLaser) - a.experiment.measurements[j].value(SensorId::kLaser), 0.02, 1e-15);
    EXPECT_NEAR(b.experiment.measurements[j].value(SensorId::kInclinometer) - a.experiment.measurements[j].value(SensorId::kInclinometer),
                InclinometerError(with.sensors.systematic, a.experiment.true_poses[j](2)), 1e-15);
  }
}

// With the correction the identification is as good as if the sensors had no systematic error
// (the same noise draws give the same estimate to a hundredth of its standard deviation);
// without it the exit heights are biased by the laser's offset, several standard deviations.
TEST(SystematicErrors, CorrectedReadingsIdentifyAsWellAsCleanOnesAndRawOnesAreBiased) {
  const Robot with = WithSystematicErrors();
  // Poses well inside the inclinometer's range: a true robot 1 cm off nominal holds them all.
  std::vector<PlanPose> plan;
  for (const PlanPose& p : SampleFeasiblePoses(with, 40, 9)) {
    if (std::abs(p.q(2)) < 50.0 * kDeg && plan.size() < 30) plan.push_back(p);
  }
  ASSERT_EQ(plan.size(), 30u);
  SimulationOptions clean_options, systematic_options;
  clean_options.require_feasible = systematic_options.require_feasible = true;  // as simulate
  systematic_options.systematic_errors = true;
  const std::vector<std::string> names = GeometryNames(2);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const PlanSimulation clean = SimulatePlan(with, {}, 0.01, plan, clean_options, seed, "p");
    const PlanSimulation sys = SimulatePlan(with, {}, 0.01, plan, systematic_options, seed, "p");
    const GeometryVector truth = GeometryOf(sys.truth);
    const IdentifyResult reference = Identify(with, clean.experiment.measurements, IdentifyOptions{});
    const IdentifyResult corrected =
        Identify(with, CorrectedReadings(with, sys.experiment.measurements, "p"), IdentifyOptions{});
    const IdentifyResult raw = Identify(with, sys.experiment.measurements, IdentifyOptions{});
    ASSERT_TRUE(reference.converged() && corrected.converged()) << reference.message << corrected.message;
    for (int k = 1; k < 6; ++k) {
      const double sd = reference.geometry_std(k);
      EXPECT_LT(std::abs(corrected.geometry(k) - reference.geometry(k)), 0.01 * sd) << names[k] << " seed " << seed;
      EXPECT_LT(std::abs(corrected.geometry(k) - truth(k)), 4.0 * sd) << names[k] << " seed " << seed;
    }
    ASSERT_TRUE(raw.converged()) << "seed " << seed << ": " << ToString(raw.status) << " " << raw.message;
    // Each pose's angle as well (the inclinometer's correction): as from clean readings to a
    // twentieth of its standard deviation; as read, off by the inclinometer's error there.
    for (std::size_t j = 0; j < plan.size(); ++j) {
      const double sd = reference.poses[j].std_dev(2);
      EXPECT_NEAR(corrected.poses[j].q(2), reference.poses[j].q(2), 0.05 * sd) << "pose " << j + 1 << " seed " << seed;
      EXPECT_NEAR(raw.poses[j].q(2) - reference.poses[j].q(2),
                  InclinometerError(with.sensors.systematic, sys.experiment.true_poses[j](2)), 0.1 * sd)
          << "pose " << j + 1 << " seed " << seed;
    }
    // The laser's offset moves the frame's z origin: both exit heights by the offset, many
    // standard deviations on every seed; the other parameters hardly move.
    for (const int k : {1, 3}) {
      const double bias = raw.geometry(k) - reference.geometry(k);
      EXPECT_NEAR(bias, with.sensors.systematic.laser_offset_m, 0.05 * with.sensors.systematic.laser_offset_m)
          << names[k] << " seed " << seed;
      EXPECT_GT(bias / reference.geometry_std(k), 2.5) << names[k] << " seed " << seed;
    }
  }
}

TEST(SystematicErrors, ARefusedCorrectedReadingSaysItWasCorrected) {
  const Robot with = WithSystematicErrors();
  Measurement m;
  m.pose_id = 1;
  m.where = "m.csv:3";
  m.dl_m = Eigen::VectorXd::Zero(2);
  m.set(SensorId::kLaser, 2.0);
  m.set(SensorId::kInclinometer, 1.3);  // 74 degrees: beyond the 60-degree range
  try {
    CorrectedReadings(with, {m}, "m.csv");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.csv:3: column 'theta': "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(the reading corrected for the systematic sensor errors of wang2022)"),
              std::string::npos)
        << e.what();
  }
  // Without systematic terms the readings come back as read.
  m.set(SensorId::kInclinometer, 0.3);
  EXPECT_EQ(CorrectedReadings(BuiltinRobot(), {m}, "m.csv")[0].value(SensorId::kInclinometer), 0.3);
}

}  // namespace
}  // namespace cablecal
