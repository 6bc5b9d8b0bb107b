// The information a spatial experiment gives about the robot's geometry (README, "Spatial
// robots", "Experiment design"): what the spatial identification (identify/spatial_identify.h)
// would estimate from readings at the given poses with the robot file's sensors, before any
// reading is taken.
//
// For each pose j the whitened Jacobian J_j = [J_q | J_g] of the noise-free readings: the
// rows the identification has (each encoder, each sensor the robot file has, and when the
// identification models the statics the pose's 6 equilibrium rows and its load cells), the
// columns its unknowns: the pose's 6 coordinates and (statics modelled) its m tensions, then
// the geometry in SpatialIdentifyResult::names order. The rows are the models of
// model/swivel.h and model/spatial_sensor_model.h differentiated by Jets, one cable at a time.
// The pose's own unknowns are eliminated (the Schur complement, as an orthogonal projection:
// M_j = J_g^T (I - J_q J_q^+) J_g), and the information of the unknowns the gauge leaves free
// (the identification's default gauge, the exit coordinates AnalyzeSpatialGauge holds for these
// sensors) is sum_j M_j plus the priors: the platform's mass and centre of mass when the statics
// are modelled (the last 4 free unknowns, SpatialPlatformPriorSigma), else an earlier
// identification's (design --prior). The design's S is that of the geometry alone: the mass and
// centre of mass, nuisances to a design, eliminated in turn (a Schur complement), so that S^-1
// is the covariance the identification predicts for the geometry at the same poses when the
// robot is the nominal one.
//
// The design criteria on S and their exact gradients with respect to every pose's coordinates
// and tensions: second derivatives of the readings by nested Jets (identify/nested_jet.h).
// Depends on identify/ (the gauge, the equilibrium sigmas), experiment/ (noise-free readings
// for the gauge analysis) and model/.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "design/design.h"  // Criterion
#include "experiment/spatial_plan.h"
#include "model/spatial_robot.h"

namespace cablecal {

// What the identification estimates from the robot file's sensors.
struct SpatialInformationLayout {
  int num_cables = 0;
  bool tensions = false;  // each pose's m tensions are unknowns (statics modelled)
  bool swivel = false;    // sw10 .. swm0 among the geometry
  bool heading = false;   // yaw0 among the geometry
  bool load_cells = false;
  // mass, comx, comy, comz among the unknowns, the last 4 of names and of free (the statics
  // modelled: tensions); eliminated from S.
  bool platform = false;
  std::vector<std::string> names;  // the geometry unknowns (SpatialGeometryNames)
  std::vector<int> held;           // the default gauge: indices into names
  std::vector<int> free;           // the others, in names order: S's rows and columns
  // The weakly seen directions nearly a rigid motion of the frame that `held` holds besides the
  // null directions (SpatialDirection::nearly_rigid), in words: none of the sensors see them
  // much at any pose, and the identification's default gauge holds them too.
  std::vector<std::string> weakly_seen_held;
  // The directions the gauge fixes (geometry_size x k, columns unit vectors over `names`): the
  // null directions, then the weakly seen ones above.
  Eigen::MatrixXd gauge_directions;
  int null_directions = 0;  // the first columns of gauge_directions
  // Information an earlier identification gathered (design --prior), free x free in `free`'s
  // order, added to every S (SpatialInformation, SpatialDesignObjective) in place of the
  // platform's prior (which the earlier identification's covariance holds); empty: none.
  Eigen::MatrixXd prior_information;
  int local() const { return 6 + (tensions ? num_cables : 0); }
  int geometry_size() const { return static_cast<int>(names.size()); }
  // S's size: the free unknowns but the platform's.
  int information_size() const { return static_cast<int>(free.size()) - (platform ? 4 : 0); }
  // Those unknowns, indices into names (free less the platform's).
  std::vector<int> information_unknowns() const { return {free.begin(), free.begin() + information_size()}; }
};

// The layout for the robot file's sensors without a gauge (held empty, every unknown free).
SpatialInformationLayout SpatialSensorLayout(const SpatialRobot& robot);
// The reading values one pose gives (its Jacobian's rows).
int SpatialValuesPerPose(const SpatialRobot& robot, const SpatialInformationLayout& layout);

// The layout for the robot file's sensors, the gauge that AnalyzeSpatialGauge chooses from
// noise-free readings at `reference` (simulated on the nominal robot). The null directions of
// these sensors are rigid motions of the frame, the same whatever the poses, so that a
// reference set of random feasible poses gives the gauge of any set (the weakly seen ones it
// holds are seen only through the pulley radii and the axes' tilts, at any poses). InputError as the
// identification's (a sensor set that cannot calibrate, too few values for the unknowns).
SpatialInformationLayout SpatialDesignLayout(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& reference);

// Calibrating in rounds with a result that held coordinates: the design holds the same ones (its
// information is then of the same unknowns), which must fix the layout's null directions
// (InputError naming `path`, key held, and what they leave free otherwise). The weakly seen
// directions stay in weakly_seen_held only where the result's coordinates fix them too.
void HoldAsThePrior(SpatialInformationLayout* layout, const std::vector<std::string>& held, const std::string& path);

// Calibrating in rounds (design --prior): the information an earlier identification's result
// (ReadSpatialIdentifiedGeometry) gives about `layout`'s free unknowns, given its held ones: the
// inverse of the result's covariance over the coordinates it did not hold, restricted to
// layout.free (the information of the free unknowns with the held ones known); the layout must
// hold what the result held (HoldAsThePrior first). InputError naming `path` and the key when
// the result estimates other unknowns (another sensor set) or its covariance is not positive
// definite.
Eigen::MatrixXd SpatialPriorInformation(const SpatialInformationLayout& layout, const std::vector<std::string>& names,
                                        const std::vector<std::string>& held, const Eigen::MatrixXd& covariance,
                                        const std::string& path);

// The whitened Jacobian of one pose's noise-free readings, rows as the file comment, columns
// local() then the geometry.
Eigen::MatrixXd SpatialPoseJacobian(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                    const SpatialPose<double>& q, const Eigen::VectorXd& tensions_N);

// S (information_size() square, in free's order: 1/unit^2 of each unknown, m for exits and
// lengths, rad for offsets), the priors included and the platform's unknowns eliminated:
// SpatialGeometryInformation of SpatialFullInformation.
Eigen::MatrixXd SpatialInformation(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                   const std::vector<SpatialPlanPose>& poses);
// The information of every free unknown (free x free: the platform's too, the last 4), the
// priors included: the layout's prior_information if any, else the platform's prior.
Eigen::MatrixXd SpatialFullInformation(const SpatialRobot& robot, const SpatialInformationLayout& layout,
                                       const std::vector<SpatialPlanPose>& poses);
// The geometry's information from the free unknowns' (F, free x free): the platform's
// unknowns eliminated (the Schur complement on F's last 4 rows and columns) when the layout has
// them, else F.
Eigen::MatrixXd SpatialGeometryInformation(const SpatialInformationLayout& layout, const Eigen::MatrixXd& full);

// The four criteria of S (design.h's CriteriaValues: the condition number here is that of the
// whitened reduced Jacobian, sqrt(lambda_max / lambda_min) of S; A's trace mixes m^2 and rad^2
// when the geometry has offsets). Infinite / zero as appropriate when S is singular.
CriteriaValues SpatialCriteria(const Eigen::MatrixXd& information);

// What the design minimises: log kappa (condition), -log det S (d), log trace S^-1 (a),
// -log lambda_min (e); for condition and e a smooth surrogate of sharpness `power` (> 0), the
// exact value for power 0 (S with the layout's prior information). +inf where S is singular. `gradient`, if given, receives the
// derivative with respect to every pose's (x, y, z, roll, pitch, yaw, t1..tm), 6 + m per pose.
double SpatialDesignObjective(const SpatialRobot& robot, const SpatialInformationLayout& layout, Criterion criterion,
                              const std::vector<SpatialPlanPose>& poses, Eigen::VectorXd* gradient,
                              double power = 0.0);

}  // namespace cablecal
