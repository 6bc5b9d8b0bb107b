// The spatial identification's bench problem (bench_identify's BM_SpatialIdentify*, and
// time_spatial_identify, beside bench/scipy_spatial_identify.py): cogiro (8 cables) with an
// inclinometer (sigma 1 mrad: RangedNoise{0.003, 0}, a 3-sigma range) and a vertical laser (0.1 mm) added, taken as inextensible (the
// spatial simulation refuses an 8-cable robot without stiffness: its commanded lengths could
// not all hold), exits perturbed by 1 cm (seed 7); n poses within +-1.5 m in x and y, +-0.9 m
// in z, +-0.1 rad of home (those with a valid cable geometry), each read by the model's lengths
// and sensor values on the true robot plus the sensors' noise (encoder sigma from the file).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/random.h"
#include "experiment/spatial_measurements.h"
#include "model/spatial_robot.h"
#include "model/swivel.h"

namespace cablecal::bench {

inline SpatialRobot SpatialBenchRobot(const std::string& source_dir) {
  SpatialRobot nominal = LoadSpatialRobotFile(source_dir + "/robots/cogiro.yaml");
  for (SpatialCable& c : nominal.cables) c.stiffness_N.reset();
  nominal.sensors.inclinometer_rad = RangedNoise{0.003, 0.0};
  nominal.sensors.laser_m = RangedNoise{0.0003, 0.0};
  return nominal;
}

inline std::vector<SpatialMeasurement> SpatialBenchReadings(const SpatialRobot& nominal, int n) {
  Rng rng(7);
  SpatialRobot truth = nominal;
  for (SpatialCable& c : truth.cables) {
    for (int a = 0; a < 3; ++a) c.p_F_exit_m(a) += rng.Normal(0.0, 0.01);
  }
  const Eigen::VectorXd l0 = CableLengths<double>(truth, nominal.home_pose());
  std::vector<SpatialMeasurement> readings;
  while (static_cast<int>(readings.size()) < n) {
    SpatialPose<double> q = nominal.home_pose();
    for (int a = 0; a < 2; ++a) q(a) += rng.Uniform(-1.5, 1.5);
    q(2) += rng.Uniform(-0.9, 0.9);
    for (int a = 3; a < 6; ++a) q(a) += rng.Uniform(-0.1, 0.1);
    if (!CableGeometryAt(truth, q).valid()) continue;
    SpatialMeasurement r;
    r.pose_id = static_cast<int>(readings.size()) + 1;
    r.dl_m = CableLengths<double>(truth, q) - l0;
    for (int i = 0; i < r.dl_m.size(); ++i) r.dl_m(i) += rng.Normal(0.0, nominal.sensors.encoder_sigma_m);
    const double s_inc = nominal.sensors.inclinometer_rad->sigma(), s_las = nominal.sensors.laser_m->sigma();
    r.values(SpatialSensor::kInclinometer) =
        Eigen::Vector2d(q(3) + rng.Normal(0.0, s_inc), q(4) + rng.Normal(0.0, s_inc));
    r.values(SpatialSensor::kLaser) =
        Eigen::VectorXd::Constant(1, q(2) - nominal.p_F_frame_min_m.z() + rng.Normal(0.0, s_las));
    readings.push_back(r);
  }
  return readings;
}

}  // namespace cablecal::bench
