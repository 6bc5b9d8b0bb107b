// montecarlo for spatial robots: the same study as the planar one (montecarlo.h: cells of pose
// count n and pose-set design, a fresh true robot and sensor noise per trial, the errors of
// the identified geometry, failed trials counted by cause, shares and their assembly), with a
// spatial robot's trial: its true robot, sampler or grid, simulation and identification.
//
// The gauge: a spatial robot's sensors leave some rigid motions of the frame unseen, and the
// identification holds the exit coordinates that fix them (identify/spatial_identify.h). The
// study chooses them once, from noise-free readings of the nominal robot at n_min sampled
// poses, and every trial's identification holds those; each trial's true robot is drawn with
// them at their nominal values (the frame's definition, as the planar study keeps a1x), so that
// identified minus true is an error and not a choice of frame. Its platform's mass and centre
// of mass are drawn from the robot file's priors on them (PerturbSpatialPlatform), from a
// stream of their own, unless SpatialMonteCarloOptions::exact_platform.
//
// Depends on montecarlo.h (the study's machinery), experiment/ (sample, grid, simulation) and
// identify/spatial_identify.h.
#pragma once

#include <vector>

#include "experiment/spatial_plan.h"
#include "identify/spatial_identify.h"
#include "model/spatial_robot.h"
#include "montecarlo/montecarlo.h"

namespace cablecal {

// Each trial's identification iteration cap (identify's default: 200).
constexpr int kSpatialTrialMaxIterations = 2000;

struct SpatialMonteCarloOptions {
  // pose_counts, designs (random, a criterion's design, grid:2x2x2, grid:3x3x3), trials, sensors (which get noise),
  // geometry_sigma_m (every exit coordinate but the held ones), loss, seed, progress,
  // interrupted. The planar-only ones (estimator, gauge, geometry prior, equilibrium, com
  // error, outliers) must stay at their defaults.
  MonteCarloOptions study;
  double yaw_range_rad = kDefaultSampleYawRange_rad;  // of the random sets (sample)
  bool statics = true;  // of every trial's identification (SpatialIdentifyOptions::statics)
  // false, with study.sensors = NoisySensors::kNone: noise-free readings, so that the errors
  // are what the identification itself leaves (a check of the study, not a lab's experiment).
  bool encoder_noise = true;
  // Each trial skips the poses its true robot cannot hold within its limits (what a lab does:
  // simulate --skip-infeasible) and identifies from the rest; their x errors are NaN (left out
  // of the statistics), TrialOutcome::skipped_poses counts them. Off: such a trial fails
  // (cause "simulation"), as planar.
  bool skip_infeasible = false;
  // The lab plans every pose set (random, designed, grid) inside the file's limits narrowed by
  // these margins: tension bounds [tension.min + margin, tension.max - margin], the frame margin
  // plus plan_margin_m, the tilt limit less plan_tilt_margin_rad; and commands those plans'
  // lengths, so that where the true robot settles (its tensions, its pose) keeps room for what
  // the unknown true geometry changes (a stiff redundant robot's tensions move by EA/L times the
  // length errors; a designed pose sits on the limits). The true robot's limits stay the file's.
  // 0: plans on the file's limits. PlanningRobot says what the lab plans with.
  double plan_tension_margin_N = 0.0;
  double plan_margin_m = 0.0;
  double plan_tilt_margin_rad = 0.0;
  // 0: every trial's random set is a fresh sample. P > 0: P feasible poses are sampled once per
  // study (its own seed stream) and each trial's random set is n of them drawn without
  // replacement (its own stream): for robots whose sampler is slow (underactuated equilibria).
  int random_pool = 0;
  // Each trial's true platform: false, its mass and centre of mass drawn from the robot file's
  // priors (PerturbSpatialPlatform: what a lab's platform is, the file's values known to
  // mass_sigma and com_sigma); true, the file's values exactly (montecarlo --exact-platform: a
  // study of the exits and the noise alone).
  bool exact_platform = false;
  // Ipopt's iteration cap per start of the criterion designs (SpatialDesignOptions::max_iterations).
  int design_max_iterations = 3000;
  // The exit coordinates every trial holds (the gauge), empty: the default gauge's choice on
  // noise-free readings at the fewest poses. A study split into runs (reproduce: the grids in a
  // run of their own) gives every run the first run's, so that their errors compare even where a
  // weakly seen direction, held by the default gauge, is seen above the threshold at other
  // poses (cogiro, encoders alone: at 16 random poses and not at the 27 of the grid).
  std::vector<std::string> held;
};

// The robot the lab plans and commands with (and identifies against): the nominal one with its
// limits narrowed by the options' plan margins. The true robot of every trial is drawn around
// `nominal` itself (its limits). When the identification leaves the statics out (options.statics
// false: cables taken as inextensible), the criterion designs are made on that model (the
// planning robot without stiffness) and each pose is then planned on the planning robot, whose
// commands include the stretch the lab expects.
// InputError naming the flag (--tension-margin, --frame-margin, --tilt-margin-deg) of a negative
// margin or one that leaves no limits.
SpatialRobot PlanningRobot(const SpatialRobot& nominal, const SpatialMonteCarloOptions& options);

// The InputErrors of RunSpatialMonteCarlo: the study's own (ValidateStudyOptions), a
// planar-only option, a grid with a pose count other than its side^3, a tension margin that
// leaves no bounds, a pool smaller than the largest pose count, and pose counts the robot's
// sensors cannot identify the geometry from (naming what is missing).
void ValidateSpatialMonteCarloOptions(const SpatialRobot& nominal, const SpatialMonteCarloOptions& options);

// One designed set of the study: a grid (GridSpatialPoses) or a criterion's design
// (design/spatial_design.h: the study's design_starts, its own seed stream, robust for true
// exits within 3 x the study's geometry_sigma_m (not with statics off); if no start holds, 4 times as many starts, and
// then the largest robustness that gives a set, said on stderr);
// empty, said on stderr, when none can be made. `planning`: PlanningRobot's.
std::vector<SpatialPlanPose> MakeSpatialDesignedSet(const SpatialRobot& planning, const SpatialMonteCarloOptions& options,
                                                    const DesignedSetKey& key);

// The study (montecarlo.h's cells, files and statistics). Each trial's errors: the identified
// minus the true exit coordinates and initial lengths (SpatialGeometryNames' a1x ... lm0; the
// true l_i0 is the cable paid out at home, what the controller commands there), then every
// pose's x. Failure causes as planar: sampling, simulation (the true robot cannot hold a pose
// within its limits), identification (not converged, rank deficient, or refused).
MonteCarloResult RunSpatialMonteCarlo(const SpatialRobot& nominal, const SpatialMonteCarloOptions& options);

}  // namespace cablecal
