#include "experiment/spatial_plan.h"

#include <algorithm>
#include <fstream>
#include <limits>
#include <set>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/parallel.h"
#include "common/random.h"
#include "experiment/plan.h"  // kMaxPlanPoses
#include "model/forward_statics.h"
#include "model/swivel.h"
#include "workspace/spatial_workspace.h"

namespace cablecal {

SpatialHomeReference SpatialHome(const SpatialRobot& robot) {
  const SpatialPoseEvaluation e = EvaluateSpatialHome(robot);
  if (!e.has_equilibrium) {
    throw SolverFailure("the home pose of " + robot.name + " is no equilibrium (" + ToString(e.feasibility) +
                        "): the encoders have no zero");
  }
  SpatialHomeReference home;
  home.equilibrium = e.equilibrium;
  home.paid_out_m = PaidOutLengths(robot, e.equilibrium);
  // A calibrated robot file knows where its encoders read zero better than its nominal home.
  for (int i = 0; i < robot.num_cables(); ++i) {
    if (robot.cables[i].initial_length_m) home.paid_out_m(i) = *robot.cables[i].initial_length_m;
  }
  return home;
}

SpatialPlanPose MakeSpatialPlanPose(const SpatialRobot& robot, const SpatialEquilibrium& equilibrium,
                                    const SpatialHomeReference& home) {
  SpatialPlanPose p;
  p.q = equilibrium.q;
  p.tensions_N = equilibrium.tensions_N;
  p.lengths_m = CableLengths<double>(robot, equilibrium.q);
  p.length_change_m = CommandedUnstretchedLengths(robot, p.lengths_m, p.tensions_N) - home.paid_out_m;
  return p;
}

std::vector<SpatialPlanPose> SampleSpatialPoses(const SpatialRobot& robot, int n, std::uint64_t seed,
                                                double yaw_range_rad) {
  if (n < 1) throw InputError("--poses", "", "must be at least 1 (got " + std::to_string(n) + ")");
  if (!(yaw_range_rad > 0.0 && yaw_range_rad <= M_PI)) {
    throw InputError("--yaw-range-deg", "", "must be in (0, 180] degrees (got " +
                                                FormatDouble(yaw_range_rad * 180.0 / M_PI) + ")");
  }
  const SpatialHomeReference home = SpatialHome(robot);
  const SpatialPose<double> q_home = robot.home_pose();
  const std::vector<int> controlled = ControlledCoordinates(robot);
  SpatialPose<double> lo, hi;
  lo << robot.p_F_frame_min_m.array() + robot.margin_m, -robot.tilt_max_rad, -robot.tilt_max_rad,
      q_home(5) - yaw_range_rad;
  hi << robot.p_F_frame_max_m.array() - robot.margin_m, robot.tilt_max_rad, robot.tilt_max_rad,
      q_home(5) + yaw_range_rad;
  // As the planar sample's with a free orientation: the orientation is drawn too.
  const long max_draws = 10L * (10000L + 1000L * n);
  // Candidates are drawn in order, evaluated a batch at a time in parallel and kept in draw
  // order up to the n-th feasible one: the batch's size changes only how many evaluations past
  // it are wasted, never the plan. It follows the acceptance rate so far (an underactuated
  // robot's evaluation solves for its equilibrium: milliseconds).
#ifdef _OPENMP
  const long threads = omp_get_max_threads();
#else
  const long threads = 1;
#endif
  Rng rng(seed);
  std::vector<SpatialPlanPose> plan;
  std::vector<SpatialPose<double>> candidates;
  std::vector<SpatialPoseEvaluation> evaluations;
  long draws = 0;
  while (static_cast<int>(plan.size()) < n) {
    const double rate = (plan.size() + 1.0) / (draws + 1.0);
    const long wanted = static_cast<long>(std::ceil(1.2 * (n - plan.size()) / std::min(1.0, rate)));
    const int batch = static_cast<int>(std::clamp(wanted, 2 * threads, 1024L));
    candidates.resize(batch);
    evaluations.resize(batch);
    if (draws >= max_draws) {
      throw SolverFailure("found only " + std::to_string(plan.size()) + " feasible poses of " + robot.name + " in " +
                          std::to_string(max_draws) + " random draws: the feasible workspace is empty or tiny");
    }
    for (SpatialPose<double>& q : candidates) {
      SpatialPose<double> draw;
      for (int k = 0; k < 6; ++k) draw(k) = rng.Uniform(lo(k), hi(k));
      q = q_home;  // the uncontrolled coordinates' first guess
      for (const int k : controlled) q(k) = draw(k);
    }
    ParallelFor(batch, 4, [&](long k) {
      evaluations[k] = EvaluateSpatialPose(robot, candidates[k], SpatialEvaluationDepth::kVerdict);
    });
    for (int k = 0; k < batch && static_cast<int>(plan.size()) < n && draws < max_draws; ++k, ++draws) {
      if (evaluations[k].feasible()) plan.push_back(MakeSpatialPlanPose(robot, evaluations[k].equilibrium, home));
    }
  }
  return plan;
}

std::vector<SpatialPlanPose> GridSpatialPoses(const SpatialRobot& robot, int side) {
  if (side < 2 || side > 4) {
    throw InputError("--designs", "", "a grid's side must be 2, 3 or 4 (got " + std::to_string(side) + ")");
  }
  const SpatialHomeReference home = SpatialHome(robot);
  const SpatialWorkspaceGrid grid = ComputeSpatialWorkspace(robot, robot.home_rpy_rad, DefaultSpatialStep(robot));
  std::vector<int> feasible;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int k = 0; k < static_cast<int>(grid.points.size()); ++k) {
    if (!grid.points[k].evaluation.feasible()) continue;
    feasible.push_back(k);
    lo = lo.cwiseMin(grid.points[k].p_F_m);
    hi = hi.cwiseMax(grid.points[k].p_F_m);
  }
  const int n = side * side * side;
  if (static_cast<int>(feasible.size()) < n) {
    throw SolverFailure("the workspace of " + robot.name + " at home's orientation has " +
                        std::to_string(feasible.size()) + " feasible points on its " + FormatDouble(grid.step_m) +
                        " m grid, fewer than the " + std::to_string(n) + " poses of a " + std::to_string(side) + "x" +
                        std::to_string(side) + "x" + std::to_string(side) + " grid");
  }
  std::vector<bool> taken(grid.points.size(), false);
  std::vector<SpatialPlanPose> plan;
  for (int iz = 0; iz < side; ++iz) {
    for (int iy = 0; iy < side; ++iy) {
      for (int ix = 0; ix < side; ++ix) {
        const Eigen::Vector3d fraction((ix + 0.5) / side, (iy + 0.5) / side, (iz + 0.5) / side);
        const Eigen::Vector3d centre = lo + fraction.cwiseProduct(hi - lo);
        int best = -1;
        double best_distance = std::numeric_limits<double>::infinity();
        for (const int k : feasible) {
          const double d = (grid.points[k].p_F_m - centre).squaredNorm();
          if (!taken[k] && d < best_distance) {
            best = k;
            best_distance = d;
          }
        }
        taken[best] = true;
        plan.push_back(MakeSpatialPlanPose(robot, grid.points[best].evaluation.equilibrium, home));
      }
    }
  }
  return plan;
}

namespace {

std::vector<std::string> PlanHeader(int m) {
  std::vector<std::string> header = {"pose"};
  for (const char* name : SpatialKind::kPoseNames) header.push_back(name);
  for (const char* prefix : {"t", "l", "dl"}) {
    for (int i = 1; i <= m; ++i) header.push_back(prefix + std::to_string(i));
  }
  return header;
}

}  // namespace

std::string SpatialPlanCsv(const std::vector<SpatialPlanPose>& plan, const std::string& provenance) {
  const int m = plan.empty() ? 0 : static_cast<int>(plan.front().lengths_m.size());
  std::string out = provenance + JoinCsv(PlanHeader(m)) + "\n";
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const SpatialPlanPose& p = plan[j];
    out += std::to_string(j + 1);
    for (int k = 0; k < 6; ++k) out += "," + FormatDouble(p.q(k));
    for (const Eigen::VectorXd* v : {&p.tensions_N, &p.lengths_m, &p.length_change_m}) {
      for (int i = 0; i < m; ++i) out += "," + FormatDouble((*v)(i));
    }
    out += "\n";
  }
  return out;
}

std::vector<SpatialPlanPose> ReadSpatialPlanCsv(const std::string& path, int num_cables, std::vector<int>* pose_ids) {
  std::ifstream in = OpenCsvFile(path);
  return ReadSpatialPlanCsv(in, path, num_cables, pose_ids);
}

std::vector<SpatialPlanPose> ReadSpatialPlanCsv(std::istream& in, const std::string& path, int num_cables,
                                                std::vector<int>* pose_ids) {
  if (pose_ids) pose_ids->clear();
  const std::vector<std::string> header = PlanHeader(num_cables);
  std::vector<SpatialPlanPose> plan;
  std::set<int> ids;
  ForEachCsvRow(in, path, header, [&](const CsvRow& row) {
    if (static_cast<int>(plan.size()) >= kMaxPlanPoses) {
      throw InputError(row.Where(), "", "more than " + std::to_string(kMaxPlanPoses) + " poses");
    }
    const int id = row.PositiveInt(0);
    if (!ids.insert(id).second) throw InputError(row.Where(), "column 'pose'", "duplicate pose id " + std::to_string(id));
    if (pose_ids) pose_ids->push_back(id);
    SpatialPlanPose p;
    for (int k = 0; k < 6; ++k) p.q(k) = row.Number(1 + k);
    Eigen::VectorXd* columns[3] = {&p.tensions_N, &p.lengths_m, &p.length_change_m};
    for (int c = 0; c < 3; ++c) {
      columns[c]->resize(num_cables);
      for (int i = 0; i < num_cables; ++i) (*columns[c])(i) = row.Number(7 + c * num_cables + i);
    }
    plan.push_back(p);
  });
  return plan;
}

void CheckSpatialPlanMatchesRobot(const SpatialRobot& robot, const std::vector<SpatialPlanPose>& plan,
                                  const std::string& source) {
  constexpr double kLengthTol_m = 1e-6;  // files hold shortest round-trip doubles: far below
  const double weight_N = robot.platform_mass_kg * robot.gravity_mps2;
  const SpatialHomeReference home = SpatialHome(robot);
  for (std::size_t j = 0; j < plan.size(); ++j) {
    const SpatialPlanPose& p = plan[j];
    const std::string where = source + ": pose " + std::to_string(j + 1);
    // The reference point first: a pose outside the frame is named by its own column rather
    // than by the cable lengths that follow from it.
    for (int a = 0; a < 3; ++a) {
      const double lo = robot.p_F_frame_min_m(a), hi = robot.p_F_frame_max_m(a);
      if (!(p.q(a) >= lo && p.q(a) <= hi)) {
        throw InputError(where, std::string("column '") + SpatialKind::kPoseNames[a] + "'",
                         FormatDouble(p.q(a)) + " m is outside the frame [" + FormatDouble(lo) + ", " +
                             FormatDouble(hi) + "] m of " + robot.name + ": a plan for another robot?");
      }
    }
    for (int a = 3; a < 6; ++a) {
      if (!(std::abs(p.q(a)) <= 2.0 * M_PI)) {
        throw InputError(where, std::string("column '") + SpatialKind::kPoseNames[a] + "'",
                         FormatDouble(p.q(a)) + " rad is more than a turn (degrees? angles are in radians)");
      }
    }
    if (!(TiltAngle(p.q) <= robot.tilt_max_rad + 1e-12)) {
      throw InputError(where, "columns 'roll,pitch'",
                       "the platform is tilted " + Rounded(TiltAngle(p.q) * 180.0 / M_PI, 6) +
                           " degrees, beyond limits.tilt_max_deg " + Rounded(robot.tilt_max_rad * 180.0 / M_PI, 6) +
                           " of " + robot.name + ": a plan for another robot?");
    }
    const Eigen::VectorXd l = CableLengths<double>(robot, p.q);
    const Eigen::VectorXd paid_out = CommandedUnstretchedLengths(robot, l, p.tensions_N);
    for (int i = 0; i < robot.num_cables(); ++i) {
      const std::string c = std::to_string(i + 1);
      RequirePlanLength(where, robot.name, i, l(i), p.lengths_m(i), kLengthTol_m);
      const double dl = paid_out(i) - home.paid_out_m(i);
      if (!(std::abs(dl - p.length_change_m(i)) <= kLengthTol_m)) {
        throw InputError(where, "column 'dl" + c + "'",
                         FormatDouble(p.length_change_m(i)) + " m is not the change of cable " + c +
                             "'s paid-out length from home (" + FormatDouble(dl) + " m) of " + robot.name);
      }
    }
    RequirePlanEquilibrium(where, robot.name, p.tensions_N,
                           EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), weight_N,
                           "x,y,z,roll,pitch,yaw");
  }
}

}  // namespace cablecal
