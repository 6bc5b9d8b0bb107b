// Spatial identification, first layer (README, "Spatial robots", "Spatial identification"):
// the geometry of a spatial robot (every exit point D_i, every initial length l_i0, and the
// zero offsets of the relative sensors) and every measured pose from the readings of any subset
// of its sensors, with the gauge chosen from the data.
//
// Unknowns, in the order of SpatialIdentifyResult::names: a1x a1y a1z ... amx amy amz (exit
// points, m), l10 ... lm0 (each cable's length at home, m: an inextensible cable's encoder
// reads dl_ij = l_i(q_j) - l_i0), then b1x b1y b1z ... bmx bmy bmz with options.anchors (the
// platform anchors b_i in the platform frame P, m; otherwise the robot file's, taken as exact),
// then sw10 ... swm0 when swivel readings are present (the
// angle about k_i, from the nominal home's pulley direction, at which encoder i reads zero,
// rad), then yaw0 when heading readings are present (the yaw at which the IMU reads zero,
// rad), then mass comx comy comz when the statics are modelled (kg; m, in P: below); and each
// measured pose's (x, y, z, roll, pitch, yaw). Repeated pose ids are repeated readings of one
// pose.
//
// Residuals: model minus reading over the sensor's sigma (robot file: the encoder sigma, each
// RangedNoise's sigma()), the models those of model/swivel.h and model/spatial_sensor_model.h.
//
// Statics (options.statics, on by default). Each pose j also has the m cable tensions t_ij (N)
// as unknowns, eliminated with its coordinates, when they carry information: load-cell
// readings are present, a cable has a stiffness, or the robot is underactuated (m < 6). Then
// - each load cell reads (t_ij - f_ij) / sigma_f;
// - each pose's equilibrium W(q_j, D) t_j + w_g(q_j, mass, c) = 0 (model/swivel.h: its wrench
//   columns through the unknown exit points, its gravity through the unknown mass and centre of
//   mass) is 6 residuals, the statics' tolerance: the force rows over
//   kEquilibriumForceSigmaRelative times the weight, the moment rows over the weight times
//   kEquilibriumMomentSigma_m;
// - the platform's mass and centre of mass c (in P) are 4 unknowns of the geometry vector
//   (names mass, comx, comy, comz, after everything else), each with a prior residual about the
//   robot file's value (model/spatial_robot.h's SpatialPlatformPriorSigma: platform.mass_sigma
//   and platform.com_sigma, by default 1 % of the mass and 5 mm). A wrong centre of mass
//   is one error shared by every pose, not an independent one per pose: as unknowns with their
//   priors, their uncertainty reaches the geometry's covariance once, as it reaches the
//   estimate (a per-pose allowance of the same size made the predicted sigmas of irma4u 1.0 to
//   1.7 times the spread of simulated experiments, bench/README.md);
// - the encoder of a cable with a stiffness reads the cable paid out, its unstretched length
//   (model/robot.h's UnstretchedLength): dl_ij = l_i(q_j) / (1 + t_ij / EA_i) - l_i0, so that
//   l_i0 is then the cable paid out at home (the unstretched length there), not its geometric
//   length.
// A robot with 7 or more inextensible cables gets no tensions without load cells (its
// equilibrium adds nothing: every tension combination it does not fix is free) and is refused
// with them (the same indeterminacy: InputError naming sensors.load_cell). Note that with
// stretching cables and no load cells the tensions take the redundant cables' information:
// each pose has m + 6 unknowns for m encoder values and 6 equilibrium rows, so encoders alone
// no longer self-calibrate an elastic robot (refused, too few values); load cells, an
// inclinometer or a laser restore it. options.statics = false leaves the statics out (cables
// taken as inextensible, load cells unused): the first layer's model, for comparison.
//
// Free anchors (options.anchors, `--identify anchors`): every residual that reads an anchor
// (encoders, swivel encoders, the equilibrium's moment arms) takes it from the geometry vector
// instead of the robot file, through the same model functions. The anchors add null
// directions: a rigid motion of the anchors in P, undone by every pose, changes no length (6
// more: 3 translations, 3 rotations). A position tracker sees the anchors' translation (its
// target is a point of P, not an anchor), an inclinometer their rotations about P's x and y
// and, through the platform's tilt at the poses, about P's z; the equilibrium (centre of mass
// from the robot file) their horizontal offset from it. The platform's position along its own
// z is seen by the laser only through the tilt (second order): weakly.
//
// Gauge (SpatialGaugeAnalysis): the Jacobian of every whitened residual at the nominal
// geometry and the starting poses, each pose's columns eliminated by an orthogonal projection
// (so that nothing is squared), then an SVD of the reduced geometry Jacobian: singular values
// below kSpatialNullThreshold of the largest are null directions (no reading sees them),
// those below kSpatialWeakThreshold weakly observable. The default gauge holds, at their
// nominal values, the coordinates chosen by a column-pivoted QR of the transposed null basis
// restricted to the holdable rows (the first k pivots for k null directions: the coordinates
// the null directions move most independently), exit coordinates first: each pivot is the
// exit coordinate the remaining null directions move most, and an anchor coordinate (with
// options.anchors) only when they move no exit coordinate any more (the remaining directions
// are motions of the anchors in P alone). So a frame is defined by its exits, as without free
// anchors, and the platform frame by the fewest anchor coordinates that pin what no reading
// sees of it.
// A weakly seen direction that is nearly a rigid motion of the frame (SpatialDirection::
// nearly_rigid) is held by the default gauge too, one more pivot each: no pose set sees it much
// better (only the pulley radii and the swivel axes' tilts do), and estimating it leaves
// Levenberg-Marquardt crawling along it (cogiro with one swivel axis tilted 1 to 70 degrees,
// encoders, inclinometer and laser: not converged in 3000 iterations, 5 with it held). Its
// hold is a choice of frame as the null directions' are: the fit is the same to its tiny
// singular value. --gauge hold: without it estimates it.
// Solver: Levenberg-Marquardt with the poses eliminated (our block-arrow iterations without a robust
// loss, Ceres DENSE_SCHUR with one), from each pose's own start at the nominal geometry. Ours
// falls back to a QR step where the normal equations fail and refits the poses at each
// candidate once a step was mispredicted near the fit (identify/spatial_identify.cc,
// SolveBlockArrow: barely determined problems converge instead of crawling).
// Depends on model/ (header-only parts and the robot), Ceres and experiment/spatial_measurements.h.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"  // SpatialPlanPose (a plain struct: header only)
#include "identify/identify.h"  // RobustLoss
#include "model/kind.h"
#include "model/spatial_robot.h"

namespace cablecal {

// A singular value of the reduced Jacobian below this fraction of the largest is a null
// direction: rounding in the whitened Jacobian (entries of order 1 / sigma, exact to ~1e-15
// relative) stays six orders below it, while a direction seen through a pulley radius of a
// millimetre on a 10 m frame is still above it.
constexpr double kSpatialNullThreshold = 1e-9;
// Below this fraction (and above the null threshold) a direction is reported as weakly
// observable: its sigma is 1e4 times that of the best-seen direction or more.
constexpr double kSpatialWeakThreshold = 1e-4;
// A weakly seen direction whose exit part is within this fraction (of its norm) of a rigid
// motion of the frame's exits is "nearly" that motion (SpatialDirection::nearly_rigid).
constexpr double kSpatialNearlyRigid = 0.05;

// The equilibrium rows' sigma, the statics' tolerance once the mass and the centre of mass are
// unknowns: the force rows this fraction of the weight, the moment rows the weight times this
// arm (0.1 mm). Small enough that the priors above, not the rows, carry what the statics do not
// know: on irma4u, whose simulated statics are exact, the predicted sigmas are then within 3.5 %
// of the spread (1e-3 made them 20 % conservative, 3e-4 6 %). Its cost: the nearly hard
// constraint takes a 30-pose cogiro identification 35 Levenberg-Marquardt iterations (11 at
// 3e-4, 6 at 1e-3); at 3e-4 a random 6-cable robot's 27-pose design reached Ipopt's iteration
// cap and a robust design on another held only to 0.85 of the requested robustness (both
// converge at 1e-4; bench/README.md, irma4u). Pulley friction, the cables' own weight and
// anything else the model leaves out must fit in it: where they do not, the equilibrium rows'
// residuals (SpatialReadingFit::equilibrium, result.yaml) say so.
constexpr double kEquilibriumForceSigmaRelative = 1e-4;
constexpr double kEquilibriumMomentSigma_m = 1e-4;

// Plausibility (SpatialIdentifyResult::warnings): an identified exit point farther than this
// outside the frame box (pulleys sit on the frame; half a metre is beyond any bracket), and an
// initial length off its nominal by more than the frame box's diagonal (no cable can be).
constexpr double kPlausibleExitOutsideFrame_m = 0.5;

enum class SpatialGaugeKind {
  kAuto,   // hold the exit (then anchor) coordinates the pivoted QR picks (the default)
  kHold,   // hold the user's exit (and anchor) coordinates; refused when they leave a null direction
  kNone,   // hold nothing: covariance by the pseudo-inverse, the null directions reported
  kPrior,  // the robot file's tracker sigma on every exit coordinate, about its nominal value
};
struct SpatialGauge {
  SpatialGaugeKind kind = SpatialGaugeKind::kAuto;
  std::vector<std::string> held;  // kHold: exit-coordinate names, a1x ..., and anchor ones, b1x ...
};
// "auto", "none", "prior", "hold:a1x,a2y,...". InputError naming --gauge.
SpatialGauge ParseSpatialGauge(const std::string& text);
std::string ToString(const SpatialGauge& gauge);

// Where a pose's search starts when the lab knows what it commanded there (identify --plan: a
// row of the plan CSV that made the experiment): the commanded pose, an equilibrium of the
// nominal robot, and the nominal tensions that hold it there.
struct SpatialPoseStart {
  SpatialPose<double> q = SpatialPose<double>::Zero();  // x y z (m), roll pitch yaw (rad), in F
  Eigen::VectorXd tensions_N;  // one per cable; empty: those nearest holding the nominal platform at q
};

// A plan's rows as starts, by pose id: `pose_ids` the plan file's pose column
// (ReadSpatialPlanCsv), empty for 1..n in plan order (as simulate numbers a plan's readings
// without one).
inline std::map<int, SpatialPoseStart> PoseStartsFromPlan(const std::vector<SpatialPlanPose>& plan,
                                                          const std::vector<int>& pose_ids = {}) {
  std::map<int, SpatialPoseStart> starts;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    starts[pose_ids.empty() ? static_cast<int>(k + 1) : pose_ids[k]] = {plan[k].q, plan[k].tensions_N};
  }
  return starts;
}

struct SpatialIdentifyOptions {
  SpatialGauge gauge;
  // By pose id. A pose with a start here begins from it; the others from home, fitted first
  // to their readings without the statics, then with them (PoseStarts in spatial_identify.cc).
  // The true robot settles within its geometry's errors of the commanded pose, so from 6 cables
  // on no per-pose fit is needed (below 6 the commanded start is fitted and competes with one
  // from home). A start whose misfit stands out among those of the poses started alike
  // (another pose's plan row, a wrong basin) is fitted and competes with one from home.
  std::map<int, SpatialPoseStart> pose_starts;
  // A fit from pose_starts that did not converge or misfits is solved again from the starts
  // without them (a plan of other poses). Off in the Monte Carlo, whose plans are its readings'
  // own: there a misfit is the model's (encoders alone on stretching cables), and the second
  // solve was a quarter of the spatial study's CPU time, for the same failures.
  bool retry_without_plan = true;
  // The cables paid out at the nominal robot's home equilibrium (SpatialHome's paid_out_m), the
  // initial lengths' start; empty: solved for from the robot (NominalSpatialGeometry). The Monte
  // Carlo solves it once per study and passes it: a home equilibrium per trial was 0.9 ms of a
  // cogiro trial's 5.6.
  Eigen::VectorXd home_paid_out_m;
  RobustLoss loss;  // on each whitened sensor value (an encoder, roll, px, ...) on its own
  int max_iterations = 200;
  bool statics = true;  // the tensions, load cells, equilibrium and stretch (file comment)
  bool anchors = false;  // --identify anchors: every platform anchor b_i an unknown too (file comment)
  // Each reading value's leverage (SpatialReadingFit::leverage) and the warning for values no
  // other reading checks. Off in the Monte Carlo, which reads neither; computed with no robust
  // loss only (a loss reweights the rows: the leverages would be the weighted fit's).
  bool reading_leverage = true;
  // Refuse an estimate no robot of this file can have (SpatialPlausibilityWarnings: an exit
  // point off the frame box, an initial length off by more than its diagonal) as poor_fit, as
  // the planar identification does. Off in the Monte Carlo: there a wild estimate from a poor
  // pose set is a result to count, not a sign of wrong data.
  bool check_plausible_geometry = true;
};

// A converged fit whose readings' whitened residuals have an RMS above this (over the sensors'
// values, not the equilibrium's rows; with a robust loss, over the values within
// kOutlierSigmas) is poor_fit: that is not noise, but readings of another robot, in other
// units, or a wrong minimum (the planar identification's factor).
constexpr double kSpatialPoorFitFactor = 10.0;

// A pose estimated farther than this from its commanded pose (SpatialIdentifyOptions::
// pose_starts) is named in a warning: a geometry off by centimetres moves the platform by about
// as much, a plan row of another pose by decimetres or more.
constexpr double kSpatialPlanFarFromPose_m = 0.05;

// `--identify`: "exits" (the exit points and initial lengths: the default) or "anchors" (the
// platform anchors too). InputError naming --identify otherwise.
bool ParseSpatialIdentify(const std::string& text);
const char* SpatialIdentifyName(bool anchors);

// One direction of the geometry the readings do not see (or see weakly): unit vector over
// the geometry unknowns (names order), the relative singular value, and in words.
struct SpatialDirection {
  Eigen::VectorXd geometry;
  double relative_singular_value = 0.0;
  std::string description;  // "a translation along x", "a rotation about z", ...
  // A weakly seen direction whose exit part is within kNearlyRigid of a rigid motion of the
  // frame (a turn about z that one tilted swivel axis barely sees): the default gauge holds it.
  bool nearly_rigid = false;
};

// Each value's leverage h in [0, 1] (the diagonal of the whitened fit's hat matrix, the pose
// unknowns and the free geometry together): how much of a change in the reading the fitted
// value follows (h = d model / d reading). A value with h near 1 is checked by no other reading:
// its residual shows only sqrt(1 - h) of an error in it, and the rest moves the estimate. Over
// every value (the equilibrium's rows and the priors' included) the leverages sum to the
// number of unknowns the values determine.
struct SpatialReadingLeverage {
  Eigen::VectorXd encoders;  // per cable
  std::array<Eigen::VectorXd, kNumSpatialSensors> sensors;  // as SpatialReadingFit::sensors
  Eigen::VectorXd equilibrium;
};

// How one reading fits at the estimate: each value's whitened residual (model - reading) / sigma.
struct SpatialReadingFit {
  int pose_id = 0;
  std::string where;
  Eigen::VectorXd encoders;  // per cable
  std::array<Eigen::VectorXd, kNumSpatialSensors> sensors;  // empty where not read (load cells: or not modelled)
  // The pose's 6 equilibrium residuals (force, moment), on the pose's first reading when the
  // statics are modelled; empty otherwise.
  Eigen::VectorXd equilibrium;
  // Empty unless computed (a converged fit, SpatialIdentifyOptions::reading_leverage, no loss);
  // NaN for a pose whose own readings do not determine it.
  SpatialReadingLeverage leverage;
};

// A value at or above this leverage is checked by no other reading (its residual shows at most
// 10 % of an error in it): named in a warning of a fit with redundancy.
constexpr double kUncheckedLeverage = 0.99;  // the warning says 0.99

enum class SpatialIdentifyStatus {
  kConverged,
  kNotConverged,   // the solver stopped without meeting its tolerances: not a result
  kRankDeficient,  // at the estimate a direction beyond the gauge is unseen: not a result
  kPoorFit,        // converged, but the readings do not fit (kSpatialPoorFitFactor) or the
                   // geometry is implausible (check_plausible_geometry): not a result
};
const char* ToString(SpatialIdentifyStatus s);

struct SpatialIdentifyResult {
  SpatialIdentifyStatus status = SpatialIdentifyStatus::kNotConverged;
  std::string message;  // why, when not converged
  std::vector<std::string> names;
  Eigen::VectorXd geometry;  // by names; the last iterate when not converged (not a result)
  std::vector<int> pose_ids;  // one per distinct pose id, in order of first appearance
  std::vector<SpatialPose<double>> poses;
  // Where the kept fit started. Below 6 cables each pose starts from home; a fit from there
  // that did not converge or misfits its readings (whitened RMS above 2) is tried again from
  // staged starts (the pose from the readings without the statics first), and the lower cost
  // kept with its starts and `iterations`.
  std::vector<SpatialPose<double>> starting_poses;
  std::vector<Eigen::VectorXd> tensions_N;  // per pose when the statics are modelled, else empty
  double final_cost = 0.0;  // 1/2 sum of squared whitened residuals (before the loss)
  int iterations = 0;
  std::vector<SpatialReadingFit> fits;  // one per reading
  std::vector<std::string> held;        // the held exit (and anchor) coordinates
  std::vector<SpatialDirection> null_directions;  // before holding anything
  std::vector<SpatialDirection> weak_directions;
  // Covariance of the geometry (names order) with the gauge held: held rows and columns zero;
  // gauge none: the pseudo-inverse (the null directions have no variance). Empty when not
  // converged.
  Eigen::MatrixXd covariance;
  Eigen::VectorXd sigma;
  std::vector<std::string> unused_sensors;  // read but not modelled ("load_cell" with statics off)
  // The largest whitened residual (before the loss), its pose and sensor ("encoder 3",
  // "inclinometer roll", "load_cell f2", "equilibrium moment x", ...).
  double worst_residual = 0.0;
  int worst_pose_id = 0;
  std::string worst_sensor, worst_where;
  // A result to read with care: an exit point more than kPlausibleExitOutsideFrame_m outside
  // the frame box, an initial length off its nominal by more than the frame's diagonal, the
  // worst reading beyond kOutlierSigmas.
  std::vector<std::string> warnings;
  // The RMS of the readings' whitened residuals (kSpatialPoorFitFactor's), 0 until computed.
  double whitened_rms = 0.0;
  // The priors' rows' leverages summed (the platform's, the tracker's with --gauge prior): with
  // the readings' (SpatialReadingFit::leverage) they make the unknowns' count. 0 without.
  double prior_leverage = 0.0;
  bool converged() const { return status == SpatialIdentifyStatus::kConverged; }
};

// The gauge analysis alone (IdentifySpatial runs it first): the null and weak directions of
// the readings at the nominal geometry and the starting poses, and what the gauge holds.
// InputError as IdentifySpatial.
struct SpatialGaugeAnalysis {
  std::vector<std::string> names;
  std::vector<SpatialDirection> null_directions;
  std::vector<SpatialDirection> weak_directions;
  std::vector<int> held;  // indices into names
  // Reading values left over once every unknown is counted (the geometry less what the gauge
  // holds, each pose's coordinates and tensions): 0 is an exactly determined fit, which fits
  // any readings, noise and gross errors alike (IdentifySpatial warns).
  int redundancy = -1;
};
SpatialGaugeAnalysis AnalyzeSpatialGauge(const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                                         const SpatialIdentifyOptions& options);

// Identifies the geometry and the poses (file comment). InputError (exit 2 in the CLI), naming
// what is missing, when: no readings; a reading's cable count differs from the robot's; a
// reading has a sensor the robot file lacks (no sigma); the readings have fewer values than
// the unknowns (every geometry coordinate but the rigid motions of the frame that no reading
// sees and the gauge holds, as design's MinSpatialDesignPoses counts; each pose's coordinates
// and tensions); a pose is not determined by its own readings; a null direction moves no exit
// (or, with free anchors, anchor) coordinate (holding them cannot fix it); `hold:` names
// something other than an exit or free anchor coordinate or leaves a null direction (named in
// words); `prior` without a tracker sigma, or with free anchors that a null direction moves
// alone (the prior is on the exits only);
// load cells on more than 6 inextensible cables (sensors.load_cell), stiffness on some cables
// with more than 6 without (cables[i].stiffness), the statics on a weightless platform.
// A solver that did not converge is a status, never a result.
SpatialIdentifyResult IdentifySpatial(const SpatialRobot& nominal, const std::vector<SpatialMeasurement>& readings,
                                      const SpatialIdentifyOptions& options);

// The plausibility warnings of a geometry (names order; only its exits and lengths are read):
// an exit point more than kPlausibleExitOutsideFrame_m outside nominal's frame box, an
// initial length off its nominal value (NominalSpatialGeometry) by more than the box's
// diagonal. Each names the unknown and the amount.
std::vector<std::string> SpatialPlausibilityWarnings(const SpatialRobot& nominal, const Eigen::VectorXd& geometry);

// The nominal geometry vector (names order): exits, the cables paid out at the home equilibrium
// (unstretched: as SpatialHome's paid_out_m; a cable's initial_length where the file gives one), the file's anchors (when anchors), zero swivel
// offsets (when swivel), the home yaw (when heading), the file's mass and centre of mass (when
// platform: the statics modelled).
// home_paid_out_m: those lengths when the caller has them (SpatialIdentifyOptions), else solved for.
Eigen::VectorXd NominalSpatialGeometry(const SpatialRobot& nominal, bool swivel, bool heading, bool anchors = false,
                                       bool platform = false, const Eigen::VectorXd* home_paid_out_m = nullptr);
std::vector<std::string> SpatialGeometryNames(int num_cables, bool swivel, bool heading, bool anchors = false,
                                              bool platform = false);
// The mass and centre-of-mass unknowns' names, in order (the last four of the geometry vector
// when the statics are modelled; their priors SpatialPlatformPriorSigma, model/spatial_robot.h).
inline constexpr const char* kSpatialPlatformNames[4] = {"mass", "comx", "comy", "comz"};

}  // namespace cablecal
