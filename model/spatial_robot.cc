// A planar robot as a spatial one (model/spatial_robot.h, PlanarAsSpatial).
#include "model/spatial_robot.h"

#include "model/statics.h"

namespace cablecal {

SpatialRobot PlanarAsSpatial(const Robot& planar) {
  const auto in_plane = [](const Eigen::Vector2d& xz) { return Eigen::Vector3d(xz.x(), 0.0, xz.y()); };
  SpatialRobot s;
  s.name = planar.name;
  s.source = planar.source;
  s.gravity_mps2 = planar.gravity_mps2;
  s.p_F_frame_min_m = Eigen::Vector3d(0.0, -0.5 * kPlanarAsSpatialDepth_m, 0.0);
  s.p_F_frame_max_m = Eigen::Vector3d(planar.frame_width_m, 0.5 * kPlanarAsSpatialDepth_m, planar.frame_height_m);
  s.platform_mass_kg = planar.platform_mass_kg;
  s.p_P_com_m = in_plane(planar.p_P_com_m);
  for (const Cable& c : planar.cables) {
    SpatialCable sc;
    // The planar exit A_i is where the cable, running along the post, first touches the
    // pulley: the swivel pulley's D_i, with the cable arriving up (over) or down (under).
    sc.p_F_exit_m = in_plane(c.p_F_exit_m);
    sc.k_F_swivel_axis = Eigen::Vector3d(0.0, 0.0, WrapSign(c.wrap));
    sc.pulley_radius_m = c.pulley_radius_m;
    sc.p_P_anchor_m = in_plane(c.p_P_anchor_m);
    s.cables.push_back(sc);
  }
  s.tension_min_N = planar.tension_min_N;
  s.tension_max_N = planar.tension_max_N;
  s.tilt_max_rad = planar.theta_max_rad;
  s.margin_m = planar.margin_m;
  s.p_F_home_m = in_plane(planar.p_F_home_m);
  // With 2 cables the home equilibrium decides theta; with more the file gives it.
  const double home_theta_rad =
      planar.theta_is_free() ? planar.home_theta_rad : EvaluateHome(planar).equilibrium.q(2);
  s.home_rpy_rad = Eigen::Vector3d(0.0, -home_theta_rad, 0.0);
  SpatialSensors& sensors = s.sensors;
  sensors.encoder_sigma_m = planar.sensors.encoder_sigma_m;
  sensors.laser_m = RangedNoise{planar.sensors.laser_accuracy_m, planar.sensors.laser_repeatability_m};
  sensors.inclinometer_rad =
      RangedNoise{planar.sensors.inclinometer_accuracy_rad, planar.sensors.inclinometer_repeatability_rad};
  sensors.tracker_sigma_m = planar.sensors.tracker_sigma_m;
  return s;
}

}  // namespace cablecal
