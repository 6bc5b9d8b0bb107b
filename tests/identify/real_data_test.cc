// A lab's data: repeated readings of one pose, a missing sensor, a gross outlier (named without
// a robust loss, down-weighted with one), and the per-reading residuals of the result. Every
// property is checked on the built-in robot, the asymmetric one and random robots.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "tests/support/random_robot.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

std::vector<Robot> Robots() {
  std::vector<Robot> robots = {BuiltinRobot(), LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/asymmetric.yaml")};
  Rng draw(4417);
  for (int k = 0; k < 3; ++k) robots.push_back(testing::RandomValidRobot(draw, "random" + std::to_string(k)));
  robots.push_back(testing::RandomRobotWithCables(draw, "random3", 3, false));
  return robots;
}

struct Experiment {
  Robot truth;
  std::vector<Measurement> readings;
};

// A true robot 10 mm (sigma) from nominal and n simulated poses, with the paper's noise. A
// random plan may hold a pose the true robot cannot (a slack cable at the workspace's edge):
// the next seed is then tried, as a lab would plan again.
Experiment Simulated(const Robot& nominal, int n, std::uint64_t seed, bool noise = true) {
  for (std::uint64_t attempt = 0;; ++attempt) {
    Rng rng(seed + 1000 * attempt);
    Experiment e{PerturbGeometry(nominal, 0.01, rng), {}};
    const auto plan = SampleFeasiblePoses(nominal, n, seed + 1000 * attempt + 1);
    const SimulationOptions options{noise ? NoisySensors::kBoth : NoisySensors::kNone, noise};
    try {
      e.readings = SimulateExperiment(nominal, e.truth, plan, options, rng).measurements;
      return e;
    } catch (const SolverFailure&) {
      if (attempt == 200) throw;
    }
  }
}

// "pose 7" in `text`, not followed by a digit (pose 1 is not pose 13).
bool NamesPose(const std::string& text, int id) {
  const std::string word = "pose " + std::to_string(id);
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
    const std::size_t end = at + word.size();
    if (end == text.size() || !std::isdigit(static_cast<unsigned char>(text[end]))) return true;
  }
  return false;
}

double MaxSigmasApart(const IdentifyResult& a, const GeometryVector& b, const IdentifyResult& sigmas) {
  double worst = 0.0;
  for (int k = 1; k < a.geometry.size(); ++k) {  // k = 0: a1x, held
    worst = std::max(worst, std::abs(a.geometry(k) - b(k)) / sigmas.geometry_std(k));
  }
  return worst;
}

TEST(RepeatedReadings, ShareThePoseUnknownsAndShrinkTheSpreadBySqrtOfTheirCount) {
  for (const Robot& nominal : Robots()) {
    // Three readings of each pose: the noise-free readings of one experiment, each read three
    // times with fresh noise of the paper's sigmas.
    const Experiment clean = Simulated(nominal, 12, 5, false);
    const Robot& truth = clean.truth;
    Rng rng(77);
    std::vector<Measurement> once, thrice;
    for (int copy = 0; copy < 3; ++copy) {
      for (Measurement m : clean.readings) {
        for (int i = 0; i < m.dl_m.size(); ++i) m.dl_m(i) += rng.Normal(0.0, nominal.sensors.encoder_sigma_m);
        m.at(SensorId::kLaser) += rng.Normal(0.0, nominal.sensors.laser_sigma_m());
        m.at(SensorId::kInclinometer) += rng.Normal(0.0, nominal.sensors.inclinometer_sigma_rad());
        if (copy == 0) once.push_back(m);
        thrice.push_back(m);
      }
    }
    const IdentifyResult a = Identify(nominal, once, IdentifyOptions{});
    const IdentifyResult b = Identify(nominal, thrice, IdentifyOptions{});
    ASSERT_TRUE(a.converged()) << nominal.name << ": " << a.message;
    ASSERT_TRUE(b.converged()) << nominal.name << ": " << b.message;
    EXPECT_EQ(b.poses.size(), 12u);
    EXPECT_EQ(b.readings.size(), 36u);
    EXPECT_EQ(b.poses[3].pose_id, 4);
    // Three readings of each pose: about three times the information on the geometry (the
    // same rows, at estimates a little apart), so the standard deviations shrink by about
    // sqrt(3); exactly so for the noise-free readings repeated as they are.
    std::vector<Measurement> exact = clean.readings;
    exact.insert(exact.end(), clean.readings.begin(), clean.readings.end());
    exact.insert(exact.end(), clean.readings.begin(), clean.readings.end());
    const IdentifyResult a0 = Identify(nominal, clean.readings, IdentifyOptions{});
    const IdentifyResult b0 = Identify(nominal, exact, IdentifyOptions{});
    for (int k = 1; k < a.geometry.size(); ++k) {
      EXPECT_NEAR(b.geometry_std(k) * std::sqrt(3.0) / a.geometry_std(k), 1.0, 0.25) << nominal.name << " " << k;
      EXPECT_NEAR(b0.geometry_std(k) * std::sqrt(3.0) / a0.geometry_std(k), 1.0, 1e-6) << nominal.name << " " << k;
    }
    EXPECT_LT(MaxSigmasApart(b, GeometryOf(truth), b), 4.0) << nominal.name;
  }
}

TEST(RepeatedReadings, NoiseFreeCopiesRecoverTheTruth) {
  const Robot nominal = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/asymmetric.yaml");
  Experiment e = Simulated(nominal, 10, 3, false);
  std::vector<Measurement> doubled = e.readings;
  doubled.insert(doubled.end(), e.readings.begin(), e.readings.end());
  const IdentifyResult r = Identify(nominal, doubled, IdentifyOptions{});
  ASSERT_TRUE(r.converged()) << r.message;
  for (int k = 0; k < r.geometry.size(); ++k) EXPECT_NEAR(r.geometry(k), GeometryOf(e.truth)(k), 1e-7) << k;
}

std::vector<Measurement> Without(std::vector<Measurement> readings, bool laser, bool inclinometer) {
  for (Measurement& m : readings) {  // as the CSV reader leaves them: no value read
    if (!laser) m.drop(SensorId::kLaser);
    if (!inclinometer) m.drop(SensorId::kInclinometer);
  }
  return readings;
}

TEST(MissingSensor, TwoCablesWithoutInclinometerCannotBeCalibratedAndSaySo) {
  const Experiment e = Simulated(BuiltinRobot(), 20, 9);
  try {
    Identify(BuiltinRobot(), Without(e.readings, true, false), IdentifyOptions{});
    FAIL() << "accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("no number of poses determines the geometry (the data have no 'theta' "
                                             "column (inclinometer))"),
              std::string::npos)
        << error.what();
  }
  IdentifyOptions paper;
  paper.estimator = Estimator::kPaper;
  EXPECT_THROW(Identify(BuiltinRobot(), Without(e.readings, false, true), paper), InputError);
}

// With more cables the encoders alone say more: a 4-cable robot is calibrated without its
// inclinometer, from noise-free readings exactly, and the result says which sensor is missing.
// Without the laser nothing sees height: the vertical shift of every exit point and pose is a
// null direction the message names (a tracker prior on the exits would fix it).
TEST(MissingSensor, FourCablesCalibrateWithoutInclinometerAndNameTheShiftWithoutLaser) {
  const Robot nominal = LoadRobotFile(CABLECAL_SOURCE_DIR "/robots/planar4_fully_constrained.yaml");
  const Experiment e = Simulated(nominal, 20, 13, false);
  const IdentifyResult r = Identify(nominal, Without(e.readings, true, false), IdentifyOptions{});
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_EQ(r.missing_sensors, std::vector<std::string>{"inclinometer"});
  for (int k = 0; k < r.geometry.size(); ++k) EXPECT_NEAR(r.geometry(k), GeometryOf(e.truth)(k), 1e-7) << k;
  EXPECT_NE(IdentifyResultYaml(r, "test").find("missing_sensors: [inclinometer]"), std::string::npos);
  EXPECT_TRUE(r.has_covariance);

  const IdentifyResult no_laser = Identify(nominal, Without(e.readings, false, true), IdentifyOptions{});
  EXPECT_EQ(no_laser.status, IdentifyStatus::kRankDeficient);
  EXPECT_NE(no_laser.message.find("1 direction(s) beyond the declared gauge; null directions: 0.2041 a1z + 0.2041 a2z"),
            std::string::npos)
      << no_laser.message;
  EXPECT_NE(no_laser.message.find("(the data have no 'z' column (laser))"), std::string::npos) << no_laser.message;
  IdentifyOptions prior;
  prior.gauge = Gauge::kPrior;
  const IdentifyResult with_prior = Identify(nominal, Without(e.readings, false, true), prior);
  EXPECT_TRUE(with_prior.converged()) << with_prior.message;
}

TEST(MissingSensor, CsvWithoutAColumnReadsAndWritesBack) {
  std::istringstream in("pose,dl1,dl2,z\n1,0.01,-0.02,1.5\n1,0.011,-0.02,1.5\n2,0.1,0.2,1.2\n");
  const std::vector<Measurement> m = ReadMeasurementsCsv(in, "lab.csv", 2);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[1].pose_id, 1);
  EXPECT_TRUE(m[0].has(SensorId::kLaser));
  EXPECT_FALSE(m[0].has(SensorId::kInclinometer));
  EXPECT_EQ(MeasurementsCsv(m, ""), "pose,dl1,dl2,z\n1,0.01,-0.02,1.5\n1,0.011,-0.02,1.5\n2,0.1,0.2,1.2\n");
  std::istringstream no_dl("pose,dl1,z,theta\n1,0,1,0\n");
  EXPECT_THROW(ReadMeasurementsCsv(no_dl, "lab.csv", 2), InputError);
}

// The issue's case: one laser reading 0.3 m off (or one inclinometer reading 5 degrees off)
// among 20 poses. Least squares absorbs it at a pose of high leverage; the fit is refused
// naming that pose and sensor. With --loss cauchy the estimate is nearly the one without that
// pose's bad reading: within 1 sigma of least squares on the data without the pose (Cauchy's
// loss still pulls with c^2 / r, 0.7 sigma for the 143 sigma reading at scale 10, and at a
// pose of high leverage that moves the estimate by as much: 0.64 sigma on the built-in robot),
// and within 3 sigma of the truth.
TEST(Outlier, NamedWithoutALossAndRejectedByCauchy) {
  int robots_checked = 0;
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 20, 21);
    const IdentifyResult clean = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(clean.converged()) << nominal.name << ": " << clean.message;
    for (const int sensor : {0, 1}) {
      const int bad = 7;
      std::vector<Measurement> readings = e.readings;
      if (sensor == 0) readings[bad - 1].at(SensorId::kLaser) += 0.3;
      if (sensor == 1) readings[bad - 1].at(SensorId::kInclinometer) += 5.0 * M_PI / 180.0;
      std::vector<Measurement> dropped = e.readings;
      dropped.erase(dropped.begin() + (bad - 1));
      const IdentifyResult reference = Identify(nominal, dropped, IdentifyOptions{});
      ASSERT_TRUE(reference.converged()) << nominal.name;

      const IdentifyResult plain = Identify(nominal, readings, IdentifyOptions{});
      const std::string label = nominal.name + (sensor == 0 ? " laser" : " inclinometer");
      if (plain.converged()) {
        // Absorbed entirely (a 5 degree error along a pose's free swing): then harmless.
        EXPECT_LT(MaxSigmasApart(plain, reference.geometry, reference), 2.0) << label;
        continue;
      }
      ++robots_checked;
      EXPECT_EQ(plain.status, IdentifyStatus::kPoorFit) << label;
      EXPECT_NE(plain.message.find("pose 7 does not fit the others"), std::string::npos) << label << ": " << plain.message;
      EXPECT_NE(plain.message.find("--loss"), std::string::npos) << plain.message;

      IdentifyOptions cauchy;
      cauchy.loss = ParseLoss("cauchy");
      const IdentifyResult robust = Identify(nominal, readings, cauchy);
      ASSERT_TRUE(robust.converged()) << label << ": " << robust.message;
      EXPECT_LT(MaxSigmasApart(robust, reference.geometry, reference), 1.0) << label;
      EXPECT_LT(MaxSigmasApart(robust, GeometryOf(e.truth), robust), 3.0) << label;
      ASSERT_FALSE(robust.down_weighted.empty()) << label;
      EXPECT_EQ(robust.down_weighted[0].rfind("pose 7: ", 0), 0u) << robust.down_weighted[0];
      // The bad reading's residual in result.yaml: its error over its sensor's sigma.
      const ReadingFit& fit = robust.readings[bad - 1];
      const double expected = sensor == 0 ? 0.3 / nominal.sensors.laser_sigma_m()
                                          : 5.0 * M_PI / 180.0 / nominal.sensors.inclinometer_sigma_rad();
      const double got = std::max(std::abs(*fit.sensor_sigmas[0]), std::abs(*fit.sensor_sigmas[1]));
      EXPECT_GT(got, 0.5 * expected) << label;
    }
  }
  EXPECT_GE(robots_checked, 4);  // the laser case on most robots at least
}

// A reading no robot near nominal can give can keep least squares from converging at all (a
// new user's lab file: 20 simulated poses of a 2-cable robot with exit points at different
// heights, and one reading near the top beam with lengths off by decimetres). The failure
// names the pose without which the others converge, and a reading whose start has no valid
// cable length is named as such.
TEST(BadReading, NonConvergenceNamesThePoseWithoutWhichTheOthersConverge) {
  const Robot lab = LoadRobotFromString(R"(# my lab's 2-cable robot
name: lab2
gravity: 9.81
frame: {width: 3.5, height: 2.2}
platform:
  mass: 1.8
  com: [0.07, -0.05]
  anchors: [[-0.18, 0.02], [0.21, -0.01]]
cables:
  - {exit: [0.0, 2.1], pulley_radius: 0.015, side: left}
  - {exit: [3.5, 1.85], pulley_radius: 0.03, side: right}
tension: {min: 1.5, max: 90.0}
limits: {theta_max_deg: 50, laser_range: 2.5, margin: 0.05}
home: [1.7, 1.0]
sensors:
  laser: {accuracy: 0.005, repeatability: 0.001}
  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}
  encoder: {sigma: 0.00005}
  tracker: {sigma: 0.0004}
)", "lab2.yaml");
  std::istringstream csv(R"(pose,dl1,dl2,z,theta
1,0.9223284783826285,-0.8174991047039589,1.022184525974094,0.26822239044637797
2,0.8257412580555318,0.27950090985553594,0.19431971614685686,-0.03524523564569064
3,0.7180318868927174,0.397143794721187,0.18395805503734916,-0.11789197074240852
4,0.6131988445070441,-1.146737165004435,1.7562395943019828,0.05425980492110881
5,0.571563301456309,-0.5398642381390014,1.014097315733242,0.0788337144095426
6,0.06328252171821842,0.1341097850533794,0.8550796064601801,-0.16940825762493328
7,1.2061227168739381,-1.4954334860851797,1.518569845737025,0.522293190413107
8,0.06688278689492677,0.6753036644287485,0.48628435258177444,-0.38126307046655256
9,1.1623155933271059,-1.5754362818956582,1.6333479824268615,0.3903674891944335
10,1.2394451198346872,-0.6919065420219228,0.750474659960771,0.5078051022216011
11,-0.17694912340091187,0.9316699510544063,0.5542294191793149,-0.5416811357134939
12,-0.17970317271187472,0.9774602827219491,0.5352575641989544,-0.5678262067142991
13,-1.514486277385106,1.1094311359882696,1.774036768583337,-0.45645975459353
14,1.39723969092433,-0.0299764839810318,0.13332082978499568,0.4190074095096229
15,0.7471067597633347,-0.2950347977274943,0.6785530301479216,0.10060823231392013
16,1.5744894021734224,-0.5659846347537613,0.5256735664036594,0.8356903655297168
17,-0.9855864594004535,1.1506297898539433,1.1968923605968318,-0.7180201821297313
18,0.4276103800128968,-0.30074102154070964,0.9107003050723724,0.0006466768086870291
19,0.975972850528423,-0.739641616322592,0.9199998964243862,0.2969123440795088
20,0.5818235513079525,-0.8223840556943925,1.2937967632321516,0.1008207940734021
21,-1.855,1.21,2.08,0.0
)");
  const std::vector<Measurement> readings = ReadMeasurementsCsv(csv, "lab2_meas.csv", 2);
  const IdentifyResult r = Identify(lab, readings, IdentifyOptions{});
  ASSERT_EQ(r.status, IdentifyStatus::kNotConverged) << r.message;
  EXPECT_NE(r.message.find("only without pose 21 do the other poses converge, and against their fit its readings are off by "), std::string::npos)
      << r.message;
  EXPECT_EQ(r.message.find("--max-iterations"), std::string::npos) << "raising the limit would not help: " << r.message;
  const std::vector<Measurement> clean(readings.begin(), readings.end() - 1);
  EXPECT_TRUE(Identify(lab, clean, IdentifyOptions{}).converged());
}

// At the fewest poses that determine the geometry (5 for 2 cables, 4 for 3), leaving one out
// leaves the rest unable to check it: clean data must not be refused as a pose that does not
// fit the others (a new user's 2-cable robot at 5 poses was, at 25 sigma, from the fit's
// curvature). Such small random sets often determine the geometry barely: that is a warning.
TEST(Outlier, CleanDataAtTheFewestPosesAreNotBlamedOnAPose) {
  int fits = 0, undetermined = 0, not_converged = 0;
  for (const Robot& nominal : Robots()) {
    const int fewest = nominal.num_cables() == 2 ? 5 : 4;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      // One pose more for the second half: there the fit without one pose can converge where
      // the whole set's does not, and that pose must still not be blamed for it.
      const Experiment e = Simulated(nominal, fewest + (seed > 10 ? 1 : 0), 500 + seed);
      const IdentifyResult r = Identify(nominal, e.readings, IdentifyOptions{});
      EXPECT_EQ(r.message.find("does not fit the others"), std::string::npos)
          << nominal.name << " seed " << seed << ": " << r.message;
      // Nor, where Levenberg-Marquardt is lost, blamed on the pose without which it is not.
      EXPECT_EQ(r.message.find("the other poses converge"), std::string::npos)
          << nominal.name << " seed " << seed << ": " << r.message;
      not_converged += r.status == IdentifyStatus::kNotConverged;
      fits += r.converged();
      // A geometry they hardly determine (sigmas beyond 0.1 m) is said to be one.
      if (r.converged() && r.geometry_std.maxCoeff() > 0.1) {
        ++undetermined;
        const bool said = std::any_of(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
          return w.find("hardly determine the geometry") != std::string::npos;
        });
        EXPECT_TRUE(said) << nominal.name << " seed " << seed << ": max sigma " << r.geometry_std.maxCoeff() << " m";
      }
    }
  }
  EXPECT_GE(undetermined, 10);   // 25 of the 69 fits: the warning is exercised
  EXPECT_GE(not_converged, 5);   // 15 of the 120: the diagnosis of a lost fit is exercised
  // The check runs on the fits that converge: 69 of these 120 (random sets this small often
  // leave the geometry undetermined or Levenberg-Marquardt lost, with 1 cm geometry errors).
  EXPECT_GE(fits, 40);
}

// Under gauge prior, exit points 10 mm off nominal against a tracker sigma of 0.5 mm strain
// every pose: a refusal then says it may be the prior, not only a pose.
TEST(BadReading, ARefusalUnderGaugePriorMentionsThePrior) {
  int refused = 0;
  for (const Robot& nominal : Robots()) {
    if (!nominal.sensors.tracker_sigma_m) continue;
    const Experiment e = Simulated(nominal, 20, 31);
    IdentifyOptions prior;
    prior.gauge = Gauge::kPrior;
    const IdentifyResult r = Identify(nominal, e.readings, prior);
    if (r.status != IdentifyStatus::kPoorFit) continue;
    ++refused;
    EXPECT_NE(r.message.find("tracker prior that disagrees"), std::string::npos) << nominal.name << ": " << r.message;
    const IdentifyResult a1x = Identify(nominal, e.readings, IdentifyOptions{});
    EXPECT_EQ(a1x.message.find("tracker prior"), std::string::npos) << a1x.message;
  }
  EXPECT_GE(refused, 2);
}

// A bad laser reading at the pose that decides most of the geometry (the weakest pose) is
// absorbed by least squares: every residual stays small. Checked against the other poses'
// fit it stands out, and the fit is refused naming it.
TEST(Outlier, AbsorbedAtTheWeakestPoseIsStillNamed) {
  int refused = 0;
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 30, 57);
    const IdentifyResult clean = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(clean.converged()) << nominal.name << ": " << clean.message;
    const int weakest = clean.identifiability.weakest_pose_id;
    std::vector<Measurement> readings = e.readings;
    readings[weakest - 1].at(SensorId::kLaser) += 0.3;
    const IdentifyResult r = Identify(nominal, readings, IdentifyOptions{});
    EXPECT_EQ(r.status, IdentifyStatus::kPoorFit) << nominal.name << ": converged, geometry off by "
                                                  << MaxSigmasApart(r, GeometryOf(e.truth), clean) << " sigma";
    refused += r.status == IdentifyStatus::kPoorFit;
    EXPECT_NE(r.message.find("pose " + std::to_string(weakest) + " does not fit the others"), std::string::npos)
        << nominal.name << ": " << r.message;
  }
  EXPECT_EQ(refused, static_cast<int>(Robots().size()));
}

// result.yaml's detectable_sigmas say how large one wrong reading must be before the other
// poses show it: twice that at a pose's laser refuses the fit, half of it passes.
TEST(Diagnostics, AReadingTwiceItsDetectableSizeIsRefusedHalfOfItPasses) {
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 30, 61);
    const IdentifyResult clean = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(clean.converged()) << nominal.name;
    const int k = 4;
    const int laser_row = nominal.num_cables();
    const double detectable = clean.readings[k].min_detectable_sigmas(laser_row);
    ASSERT_TRUE(std::isfinite(detectable) && detectable < 50.0) << nominal.name << ": " << detectable;
    for (const double factor : {2.0, 0.5}) {
      std::vector<Measurement> readings = e.readings;
      readings[k].at(SensorId::kLaser) += factor * detectable * nominal.sensors.laser_sigma_m();
      const IdentifyResult r = Identify(nominal, readings, IdentifyOptions{});
      EXPECT_EQ(r.converged(), factor < 1.0) << nominal.name << " x" << factor << ": " << r.message;
    }
  }
}

TEST(Outlier, HuberEitherHoldsOrWarns) {
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 20, 21);
    std::vector<Measurement> readings = e.readings;
    readings[6].at(SensorId::kLaser) += 0.3;
    std::vector<Measurement> dropped = e.readings;
    dropped.erase(dropped.begin() + 6);
    const IdentifyResult reference = Identify(nominal, dropped, IdentifyOptions{});
    IdentifyOptions huber;
    huber.loss = ParseLoss("huber");
    const IdentifyResult r = Identify(nominal, readings, huber);
    ASSERT_TRUE(r.converged()) << nominal.name << ": " << r.message;
    if (!r.dropped_pose_ids.empty()) {  // strayed: the fit without the bad pose is returned
      EXPECT_LT(MaxSigmasApart(r, reference.geometry, reference), 1e-3) << nominal.name;
      continue;
    }
    if (MaxSigmasApart(r, reference.geometry, r) > 2.0) {
      ASSERT_FALSE(r.warnings.empty()) << nominal.name << ": Huber strayed without a warning";
      // It names the parameter furthest from that fit (or one within 10 % of it: the warning
      // compares with the fit without the poses it found, this test with the fit without pose 7).
      const std::vector<std::string> names = GeometryNames(nominal.num_cables());
      const std::string& w = r.warnings.front();
      const std::size_t at = w.find("estimate of ");
      ASSERT_NE(at, std::string::npos) << w;
      const std::string named = w.substr(at + 12, w.find(' ', at + 12) - (at + 12));
      int k = 0;
      while (k < static_cast<int>(names.size()) && names[k] != named) ++k;
      ASSERT_LT(k, static_cast<int>(names.size())) << w;
      const double named_sigmas = std::abs(r.geometry(k) - reference.geometry(k)) / r.geometry_std(k);
      EXPECT_GE(named_sigmas, 0.9 * MaxSigmasApart(r, reference.geometry, r)) << nominal.name << ": " << w;
    }
  }
}

// A robust fit the tool itself knows is wrong must not be returned (issue's case: a 2-cable
// robot of a new user's, 30 poses, one laser reading +0.3 m at pose 7 or 4; Cauchy returned l20
// 28 sigma from the truth while its own warning put it 29.9 sigma from the fit without pose
// 7). On robots drawn for this test (none tuned on), Cauchy and Huber each return an estimate
// within 3 sigma of the truth and within 2 sigma of the fit without the bad pose; where the
// robust estimate strayed, the bad pose is named as dropped and the fit without it returned.
TEST(Outlier, ARobustFitFarFromTheFitWithoutTheNamedPosesIsNotReturned) {
  Rng draw(777);
  int dropped = 0, found = 0, cases = 0;
  for (int k = 0; k < 12; ++k) {
    const Robot nominal = testing::RandomValidRobot(draw, "r" + std::to_string(k));
    const Experiment e = Simulated(nominal, 30, 100 + k);
    for (const int bad : {7, 4}) {
      std::vector<Measurement> readings = e.readings;
      readings[bad - 1].at(SensorId::kLaser) += 0.3;
      std::vector<Measurement> without = e.readings;
      without.erase(without.begin() + (bad - 1));
      const IdentifyResult reference = Identify(nominal, without, IdentifyOptions{});
      ASSERT_TRUE(reference.converged()) << nominal.name << ": " << reference.message;
      // Whether least squares found the bad pose: where it absorbed the reading unseen (a pose
      // of high leverage, far beyond the linear check's reach), the robust loss sees nothing
      // either and its estimate is least squares' (README, "Bad readings").
      const IdentifyResult ls = Identify(nominal, readings, IdentifyOptions{});
      const bool named = !ls.converged() && NamesPose(ls.message, bad);
      found += named;
      for (const char* loss : {"cauchy", "huber"}) {
        IdentifyOptions o;
        o.loss = ParseLoss(loss);
        const IdentifyResult r = Identify(nominal, readings, o);
        const std::string label = nominal.name + " pose " + std::to_string(bad) + " " + loss;
        ASSERT_TRUE(r.converged()) << label << ": " << r.message;
        ++cases;
        EXPECT_EQ(r.readings.size(), readings.size()) << label;
        if (!named) continue;
        EXPECT_LT(MaxSigmasApart(r, reference.geometry, reference), 2.0) << label;
        // No more than 2 sigma further from the truth than the fit without the bad pose.
        EXPECT_LT(MaxSigmasApart(r, GeometryOf(e.truth), reference),
                  MaxSigmasApart(reference, GeometryOf(e.truth), reference) + 2.0) << label;
        if (!r.dropped_pose_ids.empty()) {
          ++dropped;
          EXPECT_EQ(r.dropped_pose_ids, std::vector<int>{bad}) << label;
          EXPECT_LT(MaxSigmasApart(r, reference.geometry, reference), 1e-3) << label;
          ASSERT_FALSE(r.warnings.empty()) << label;
          EXPECT_NE(r.warnings.front().find("pose " + std::to_string(bad) + " dropped"), std::string::npos)
              << r.warnings.front();
          // The dropped pose's readings are still reported, against the returned geometry.
          EXPECT_GT(std::abs(*r.readings[bad - 1].sensor_sigmas[0]), kOutlierSigmas) << label;
          EXPECT_EQ(r.readings[bad - 1].sensor_weights[0], 0.0) << label;
          ASSERT_EQ(r.poses.size(), readings.size()) << label;  // every pose's estimate, the dropped one's too
          EXPECT_EQ(r.poses[bad - 1].pose_id, bad) << label;
          EXPECT_NE(IdentifyResultYaml(r, "test").find("dropped_poses: [" + std::to_string(bad) + "]"),
                    std::string::npos);
        }
      }
    }
  }
  EXPECT_EQ(cases, 48);
  EXPECT_GE(found, 18);   // measured: least squares names the bad pose in 21 of the 24 experiments
  EXPECT_GE(dropped, 3);  // measured: 4 (the case is exercised)
}

// A 0.3 m laser error at one of 30 poses could leave least squares lost within the default 100
// iterations (exit 3, no pose named) while 2000 iterations found and named it: within the
// default budget the result names the pose, whether it is refused or not converged.
TEST(BadReading, AGrossLaserErrorIsNamedWithinTheDefaultIterations) {
  Rng draw(5150);
  int refused = 0, lost = 0, cases = 0;
  for (int k = 0; k < 4; ++k) {
    const Robot nominal = testing::RandomValidRobot(draw, "gross" + std::to_string(k));
    const Experiment e = Simulated(nominal, 30, 1300 + k);
    for (int bad = 1; bad <= 30; bad += 4) {
      std::vector<Measurement> readings = e.readings;
      readings[bad - 1].at(SensorId::kLaser) += 0.3;
      const IdentifyResult r = Identify(nominal, readings, IdentifyOptions{});
      const std::string label = nominal.name + " pose " + std::to_string(bad);
      ++cases;
      if (r.converged()) continue;  // absorbed unseen at a pose of high leverage: counted below
      refused += r.status == IdentifyStatus::kPoorFit;
      lost += r.status == IdentifyStatus::kNotConverged;
      EXPECT_TRUE(NamesPose(r.message, bad)) << label << ": " << r.message;
    }
  }
  EXPECT_EQ(cases, 32);
  EXPECT_GE(lost, 1);              // the issue's case is exercised
  EXPECT_GE(refused + lost, 28);   // measured: 30 of 32 found; 2 absorbed unseen (README, "Bad readings")
}

// A new user's 5 poses copied under 30 pose ids fitted exactly (residual RMS 1e-15) and
// returned a geometry 172 mm off with no word: copies and residuals far below the sensors'
// noise are both said. Clean experiments (noisy readings) say neither.
TEST(Diagnostics, CopiedReadingsAndResidualsBelowTheNoiseAreFlagged) {
  const auto has = [](const IdentifyResult& r, const std::string& text) {
    return std::any_of(r.warnings.begin(), r.warnings.end(),
                       [&](const std::string& w) { return w.find(text) != std::string::npos; });
  };
  int flagged = 0;
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 30, 808);
    const IdentifyResult clean = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(clean.converged()) << nominal.name << ": " << clean.message;
    EXPECT_FALSE(has(clean, "identical in every value")) << nominal.name;
    EXPECT_FALSE(has(clean, "far below the sensors' noise")) << nominal.name;

    std::vector<Measurement> copies;
    for (int id = 1; id <= 30; ++id) {
      Measurement m = e.readings[(id - 1) % 5];
      m.pose_id = id;
      copies.push_back(m);
    }
    const IdentifyResult r = Identify(nominal, copies, IdentifyOptions{});
    if (!r.converged()) continue;  // refused is fine too: nothing wrong was returned quietly
    ++flagged;
    EXPECT_TRUE(has(r, "25 readings are identical in every value to another pose's (pose 6 = pose 1"))
        << nominal.name << ": " << (r.warnings.empty() ? "" : r.warnings.front());
    EXPECT_TRUE(has(r, "far below the sensors' noise")) << nominal.name;
  }
  EXPECT_GE(flagged, 3);
}

// --geometry-prior: what the lab knew before measuring (every parameter to 10 mm) is never
// lost. A new user's 3-cable robot calibrated at sigmas of 13-33 mm, worse than the 10 mm known
// before. With the prior every sigma is at most the prior's, the estimate stays within 4 sigma
// of a true robot drawn from it, the data may be fewer than the unknowns, and the result says
// which parameters the data add little to, exactly when their sigma stays above 0.7 x the prior's.
TEST(GeometryPrior, NeverLessInformedThanThePriorAndSaysWhenTheDataAddLittle) {
  constexpr double kPrior_m = 0.01;
  std::vector<Robot> robots = Robots();
  Rng draw(2418);
  for (int k = 0; k < 3; ++k) robots.push_back(testing::RandomRobotWithCables(draw, "prior3_" + std::to_string(k), 3, false));
  int said = 0, runs = 0;
  for (const Robot& nominal : robots) {
    for (const int n : {3, 5, 30}) {
      Experiment e;
      try {
        e = Simulated(nominal, n, 900 + n);
      } catch (const SolverFailure&) {
        continue;  // this robot holds no random plan of n poses 1 cm off nominal: not this test's concern
      }
      IdentifyOptions o;
      o.geometry_prior_sigma_m = kPrior_m;
      const IdentifyResult r = Identify(nominal, e.readings, o);
      const std::string label = nominal.name + " n=" + std::to_string(n);
      if (!r.converged()) continue;  // 3 poses may leave Levenberg-Marquardt lost: not a result
      ++runs;
      ASSERT_TRUE(r.has_covariance) << label;
      bool little = false;
      for (int k = 1; k < r.geometry.size(); ++k) {
        EXPECT_LE(r.geometry_std(k), kPrior_m * (1.0 + 1e-9)) << label << " " << k;
        little = little || r.geometry_std(k) > kDataAddLittle * kPrior_m;
      }
      const bool warned = std::any_of(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
        return w.find("the data add little to the geometry prior") != std::string::npos;
      });
      EXPECT_EQ(warned, little) << label;
      said += warned;
      EXPECT_LT(MaxSigmasApart(r, GeometryOf(e.truth), r), 4.0) << label;
      EXPECT_NE(IdentifyResultYaml(r, "test").find("geometry_prior_sigma_m: 0.01"), std::string::npos);
    }
  }
  EXPECT_GE(runs, 15);
  EXPECT_GE(said, 5);  // the few-pose runs leave parameters near the prior
  IdentifyOptions paper;
  paper.estimator = Estimator::kPaper;
  paper.geometry_prior_sigma_m = kPrior_m;
  EXPECT_THROW(Identify(BuiltinRobot(), Simulated(BuiltinRobot(), 10, 1).readings, paper), InputError);
  // The tracker's prior is in sigmas too: with the paper estimator it outweighed every reading
  // (a new user's trial: the exits came back as the file's, 24 sigma from the truth).
  IdentifyOptions paper_tracker;
  paper_tracker.estimator = Estimator::kPaper;
  paper_tracker.gauge = Gauge::kPrior;
  try {
    Identify(BuiltinRobot(), Simulated(BuiltinRobot(), 10, 1).readings, paper_tracker);
    ADD_FAILURE() << "the paper estimator ran with the tracker prior";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--gauge prior"), std::string::npos) << e.what();
  }
  for (const double bad : {2.0, 0.0, -0.01}) {  // 0 is refused, not taken for "no prior"
    IdentifyOptions o;
    o.geometry_prior_sigma_m = bad;
    EXPECT_THROW(Identify(BuiltinRobot(), Simulated(BuiltinRobot(), 10, 1).readings, o), InputError) << bad;
  }
}

// A new user's 2-cable robot (exits at different heights, offset centre of mass) and 19
// simulated poses, from the hostile trial: with a 0.3 m laser error at pose 17, --loss cauchy
// dropped pose 17 *and* clean pose 1 ("112 sigma": the leave-out refit, warm-started from the
// fit that absorbed the bad reading, stayed in its basin); at pose 7, least squares needed 106
// iterations and --loss cauchy exited 3 at the default 100. Now only the bad pose is named, and
// the robust fit starts from the fit without it.
TEST(Outlier, ANewUsersRobotDropsOnlyTheBadPoseAndRecoversFromALostLeastSquares) {
  const Robot lab = LoadRobotFromString(R"(name: lab2
gravity: 9.81
frame: {width: 3.2, height: 2.4}
platform:
  mass: 2.0
  com: [0.04, -0.05]
  anchors: [[-0.2, 0.0], [0.2, 0.0]]
cables:
  - {exit: [0.0, 2.3], pulley_radius: 0.025, side: left}
  - {exit: [3.2, 2.1], pulley_radius: 0.03, side: right}
tension: {min: 1.0, max: 100.0}
limits: {theta_max_deg: 50, laser_range: 2.5, margin: 0.05}
home: [1.6, 1.1]
sensors:
  laser: {accuracy: 0.006, repeatability: 0.0015}
  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}
  encoder: {sigma: 0.00005}
  tracker: {sigma: 0.0005}
)", "lab2.yaml");
  std::istringstream csv(R"(pose,dl1,dl2,z,theta
1,0.8316669636906912,-1.5878966689939509,1.9910588979171375,0.24794599771999867
2,0.1275798388854935,1.163923114517005,0.34723556727137583,-0.7404811335193696
3,0.17229549808946135,1.301073934420775,0.26614692276840973,-0.8221429535035965
4,1.31119867172046,0.002524790452884699,0.3573736578054489,0.5819056349283848
5,-0.2016720617634418,0.49670783330981816,0.9203480675488699,-0.41453941939380407
6,-0.0563052741986198,0.12270286373329407,1.0397500505101487,-0.22005327329220406
7,0.9344795462976405,-0.3719590471354871,0.7982263764958438,0.4026208601770404
8,0.4925484640530052,0.625800089682427,0.33438985126343634,-0.28043049469318143
9,0.2148245014085493,0.791791016366607,0.44219005664091343,-0.4741738488012916
10,-0.012673473418056202,0.3433972502643019,0.8594257031661994,-0.3028226283061555
11,-0.49856830207876246,0.19125425824612388,1.383770541900474,-0.2863393982697144
12,0.3898921191261627,-0.5656944232476944,1.2628436568916734,0.08903165133945373
13,-1.3348325114269763,0.9043387661314115,1.7560170720878248,-0.7071012628438129
14,0.7620019028908839,-1.268759702028093,1.6885814543606705,0.34833095045242934
15,-0.15138162085056125,0.37745560638977577,0.9522144007458899,-0.3457572386415863
16,1.217056730741595,-0.059965731333303005,0.4341090243162081,0.5237178896741544
17,-1.2184353735385136,0.8076539479868288,1.6877455770266858,-0.6241269205216171
19,0.5174010681950822,0.4356639936437297,0.4348335020613473,-0.17528267218374374
20,-0.37774473361695843,-0.37085782845508425,1.8979231628024116,-0.08910951685137186
)");
  const std::vector<Measurement> clean = ReadMeasurementsCsv(csv, "lab2.csv", 2);
  int lost_least_squares = 0;
  for (std::size_t bad = 0; bad < clean.size(); ++bad) {
    std::vector<Measurement> readings = clean;
    readings[bad].at(SensorId::kLaser) += 0.3;
    std::vector<Measurement> without = clean;
    without.erase(without.begin() + static_cast<long>(bad));
    const IdentifyResult reference = Identify(lab, without, IdentifyOptions{});
    ASSERT_TRUE(reference.converged()) << reference.message;
    const IdentifyResult ls = Identify(lab, readings, IdentifyOptions{});
    lost_least_squares += ls.status == IdentifyStatus::kNotConverged;
    if (ls.converged()) continue;  // absorbed unseen: nothing for the robust fit to start from
    IdentifyOptions cauchy;
    cauchy.loss = ParseLoss("cauchy");
    const IdentifyResult r = Identify(lab, readings, cauchy);
    const std::string label = "pose " + std::to_string(clean[bad].pose_id);
    ASSERT_TRUE(r.converged()) << label << ": " << r.message;
    EXPECT_LT(MaxSigmasApart(r, reference.geometry, reference), 2.0) << label << " LS: " << ls.message;
    for (const int id : r.dropped_pose_ids) EXPECT_EQ(id, clean[bad].pose_id) << label;
  }
  EXPECT_GE(lost_least_squares, 3);  // measured: 5 of the 19 (the recovery is exercised)
}

// Without outliers the robust losses are least squares to within 0.1 sigma (their defaults
// keep 99.95 % of its efficiency), and nothing is down-weighted.
TEST(RobustLoss, CleanDataGiveTheLeastSquaresEstimate) {
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 20, 33);
    const IdentifyResult ls = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(ls.converged()) << nominal.name << ": " << ls.message;
    for (const char* loss : {"huber", "cauchy"}) {
      IdentifyOptions o;
      o.loss = ParseLoss(loss);
      const IdentifyResult r = Identify(nominal, e.readings, o);
      ASSERT_TRUE(r.converged()) << nominal.name << " " << loss << ": " << r.message;
      EXPECT_LT(MaxSigmasApart(r, ls.geometry, ls), 0.1) << nominal.name << " " << loss;
      EXPECT_TRUE(r.down_weighted.empty()) << nominal.name;
      EXPECT_TRUE(r.warnings.empty()) << nominal.name;
    }
  }
}

TEST(RobustLoss, ParsesKindAndScaleAndRefusesTheRest) {
  EXPECT_EQ(ParseLoss("huber").scale_sigmas, kDefaultHuberScaleSigmas);
  EXPECT_EQ(ParseLoss("cauchy:2.5").scale_sigmas, 2.5);
  EXPECT_EQ(ParseLoss("none").kind, LossKind::kNone);
  EXPECT_EQ(ToString(ParseLoss("cauchy")), "cauchy:10");
  for (const char* bad : {"tukey", "huber:", "huber:0", "huber:-1", "huber:x", "none:2", "", "cauchy:1e-20", "huber:0.4"}) {
    EXPECT_THROW(ParseLoss(bad), InputError) << bad;
  }
  EXPECT_DOUBLE_EQ(LossWeight(ParseLoss("huber:3"), 6.0), 0.5);
  EXPECT_DOUBLE_EQ(LossWeight(ParseLoss("cauchy:3"), 3.0), 0.5);
  IdentifyOptions paper;
  paper.estimator = Estimator::kPaper;
  paper.loss = ParseLoss("huber");
  EXPECT_THROW(Identify(BuiltinRobot(), Simulated(BuiltinRobot(), 10, 1).readings, paper), InputError);
}

// result.yaml's per-reading residuals: on clean data their mean square is below 1 (the fit
// takes some of the noise: 1 - unknowns / readings) and above half of it.
TEST(Diagnostics, WhitenedResidualsPerReadingHaveTheNoiseScale) {
  for (const Robot& nominal : Robots()) {
    const Experiment e = Simulated(nominal, 40, 45);
    const IdentifyResult r = Identify(nominal, e.readings, IdentifyOptions{});
    ASSERT_TRUE(r.converged()) << nominal.name;
    double sum = 0.0;
    int count = 0;
    for (const ReadingFit& f : r.readings) {
      sum += f.encoder_sigmas.squaredNorm() + *f.sensor_sigmas[0] * *f.sensor_sigmas[0] +
             *f.sensor_sigmas[1] * *f.sensor_sigmas[1];
      count += static_cast<int>(f.encoder_sigmas.size()) + 2;
    }
    const int unknowns = 3 * 40 + 3 * nominal.num_cables() - 1;
    EXPECT_NEAR(sum / count, 1.0 - static_cast<double>(unknowns) / count, 0.25) << nominal.name;
    EXPECT_NE(IdentifyResultYaml(r, "test").find("readings:  # per reading (data row)"), std::string::npos);
  }
}

}  // namespace
}  // namespace cablecal
