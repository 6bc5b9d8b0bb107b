#include <gtest/gtest.h>

#include <algorithm>
#include <omp.h>

#include <filesystem>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "common/error.h"
#include "model/cable.h"
#include "experiment/plan.h"
#include "workspace/workspace.h"

namespace cablecal {
namespace {

namespace fs = std::filesystem;

TEST(WorkspaceGrid, ResultDoesNotDependOnThreadCount) {
  const Robot& robot = BuiltinRobot();
  omp_set_num_threads(1);
  const std::string one = WorkspaceCsv(robot, ComputeWorkspaceGrid(robot, 0.2), "");
  omp_set_num_threads(2);
  const std::string two = WorkspaceCsv(robot, ComputeWorkspaceGrid(robot, 0.2), "");
  EXPECT_EQ(one, two);
}

TEST(WorkspaceGrid, AreaConvergesWithStep) {
  const Robot& robot = BuiltinRobot();
  const WorkspaceGrid coarse = ComputeWorkspaceGrid(robot, 0.1);
  const WorkspaceGrid fine = ComputeWorkspaceGrid(robot, 0.05);
  EXPECT_GT(fine.num_feasible, 0);
  EXPECT_LT(fine.feasible_area_m2(), robot.frame_width_m * robot.frame_height_m);
  EXPECT_NEAR(coarse.feasible_area_m2(), fine.feasible_area_m2(), 0.05 * fine.feasible_area_m2());
  // Every infeasible point carries its reason; every feasible one an equilibrium.
  for (const WorkspacePoint& p : fine.points) {
    if (p.evaluation.feasible()) {
      EXPECT_TRUE(p.evaluation.has_equilibrium);
      EXPECT_LE(std::abs(p.evaluation.equilibrium.q(2)), robot.theta_max_rad);
      EXPECT_GE(p.evaluation.equilibrium.tensions_N.minCoeff(), robot.tension_min_N);
      EXPECT_LE(p.evaluation.equilibrium.tensions_N.maxCoeff(), robot.tension_max_N);
    }
  }
}

TEST(WorkspaceGrid, CsvHeaderAndRows) {
  const Robot& robot = BuiltinRobot();
  const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, 0.5);
  const std::string csv = WorkspaceCsv(robot, grid, "# provenance\n");
  EXPECT_EQ(csv.rfind("# provenance\nx,z,theta,t1,t2,feasible,reason\n", 0), 0u);
  EXPECT_NE(csv.find(",0,outside_frame\n"), std::string::npos);
  EXPECT_NE(csv.find(",1,feasible\n"), std::string::npos);
}

TEST(WorkspaceGrid, BadStepIsInputError) {
  EXPECT_THROW(ComputeWorkspaceGrid(BuiltinRobot(), 0.0), InputError);
  EXPECT_THROW(ComputeWorkspaceGrid(BuiltinRobot(), -0.1), InputError);
  EXPECT_THROW(ComputeWorkspaceGrid(BuiltinRobot(), 1e-6), InputError);
  // The 5.5 GB, 185 s grid (2.0e7 points) is refused before any allocation.
  EXPECT_THROW(ComputeWorkspaceGrid(BuiltinRobot(), 0.000855), InputError);
  // A step that leaves fewer than 5 points along the 2.8 m side.
  EXPECT_THROW(ComputeWorkspaceGrid(BuiltinRobot(), 0.71), InputError);
  EXPECT_NO_THROW(ComputeWorkspaceGrid(BuiltinRobot(), 0.7));
}

TEST(Sampler, SeededReproducibleAndFeasible) {
  const Robot& robot = BuiltinRobot();
  const auto a = SampleFeasiblePoses(robot, 30, 123);
  const auto b = SampleFeasiblePoses(robot, 30, 123);
  const auto c = SampleFeasiblePoses(robot, 30, 124);
  EXPECT_EQ(PosePlanCsv(a, ""), PosePlanCsv(b, ""));
  EXPECT_NE(PosePlanCsv(a, ""), PosePlanCsv(c, ""));
  const Eigen::VectorXd l0 = InitialLengths(robot);
  for (const PlanPose& p : a) {
    EXPECT_EQ(CheckFeasibility(robot, p.q, p.tensions_N), Feasibility::kFeasible);
    EXPECT_LT(EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), 1e-9);
    EXPECT_NEAR((p.lengths_m - l0 - p.length_change_m).norm(), 0.0, 1e-15);
  }
}

TEST(Sampler, UniformOverTheFeasibleRegion) {
  // Both marginals of the sample against the fine feasible grid (the sampler's target is the
  // uniform distribution over the feasible (x, z) region): two-sample Kolmogorov-Smirnov
  // statistic below its 0.1 % critical value, 1.95 sqrt((n + m) / (n m)).
  const Robot& robot = BuiltinRobot();
  const auto poses = SampleFeasiblePoses(robot, 8000, 5);
  const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, 0.02);
  for (int coord = 0; coord < 2; ++coord) {
    std::vector<double> sample, reference;
    for (const PlanPose& p : poses) sample.push_back(p.q(coord));
    for (const WorkspacePoint& w : grid.points) {
      if (w.evaluation.feasible()) reference.push_back(coord == 0 ? w.x_m : w.z_m);
    }
    std::sort(sample.begin(), sample.end());
    std::sort(reference.begin(), reference.end());
    double d = 0.0;
    for (std::size_t i = 0, j = 0; i < sample.size() && j < reference.size();) {
      const double v = std::min(sample[i], reference[j]);
      while (i < sample.size() && sample[i] <= v) ++i;
      while (j < reference.size() && reference[j] <= v) ++j;
      d = std::max(d, std::abs(static_cast<double>(i) / sample.size() - static_cast<double>(j) / reference.size()));
    }
    const double n = sample.size(), m = reference.size();
    // The grid is itself a discretisation (step 0.02 m, one column is ~0.4 % of the CDF).
    EXPECT_LT(d, 1.95 * std::sqrt((n + m) / (n * m)) + 0.005) << (coord == 0 ? "x" : "z");
  }
}

TEST(Sampler, EmptyWorkspaceFailsClearly) {
  Robot robot = BuiltinRobot();
  robot.tension_max_N = 5.0;
  robot.cables[0].initial_length_m = 3.0;  // so that no home equilibrium is needed
  robot.cables[1].initial_length_m = 3.0;
  EXPECT_THROW(SampleFeasiblePoses(robot, 5, 1), SolverFailure);
  EXPECT_THROW(SampleFeasiblePoses(BuiltinRobot(), 0, 1), InputError);
}

TEST(PosePlan, CsvRoundTrip) {
  const Robot& robot = BuiltinRobot();
  const auto plan = SampleFeasiblePoses(robot, 7, 99);
  const testing_support::TempDir tmp;
  const fs::path path = tmp.Path("plan.csv");
  std::ofstream(path) << PosePlanCsv(plan, "# comment\n");
  const auto back = ReadPosePlanCsv(path.string(), 2);
  ASSERT_EQ(back.size(), plan.size());
  for (std::size_t j = 0; j < plan.size(); ++j) {
    EXPECT_EQ(back[j].q, plan[j].q);  // shortest round-trip formatting: exact
    EXPECT_EQ(back[j].length_change_m, plan[j].length_change_m);
  }
  std::ofstream(path) << "pose,x,z,theta,t1,t2,l1,l2,dl1,dl2\n1,1,1,0,1,1,1,1,0,0\n1,1,1,0,1,1,1,1,0,0\n";
  try {
    ReadPosePlanCsv(path.string(), 2);
    FAIL() << "duplicate accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ":3: column 'pose': duplicate pose id 1");
  }
}

// With 3 or more cables the sampler draws the orientation too: every pose is feasible with
// the model, the plan's lengths and tensions are the model's, and the orientations spread over
// the feasible band instead of sitting at one angle.
TEST(ManyCableWorkspace, SamplerDrawsFeasibleOrientations) {
  for (const char* file : {"planar3_suspended.yaml", "planar4_fully_constrained.yaml"}) {
    const Robot robot = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/" + file);
    const std::vector<PlanPose> plan = SampleFeasiblePoses(robot, 60, 4);
    ASSERT_EQ(plan.size(), 60u);
    double theta_lo = 1e9, theta_hi = -1e9;
    for (const PlanPose& p : plan) {
      EXPECT_TRUE(EvaluatePose(robot, p.q).feasible()) << file << " " << p.q.transpose();
      EXPECT_LT(EquilibriumResidual<double>(robot, p.q, p.tensions_N).norm(), 1e-9 * robot.platform_mass_kg * 9.81);
      theta_lo = std::min(theta_lo, p.q(2));
      theta_hi = std::max(theta_hi, p.q(2));
    }
    EXPECT_GT(theta_hi - theta_lo, 10.0 * M_PI / 180.0) << file;
    EXPECT_NO_THROW(CheckPlanMatchesRobot(robot, plan, file));
    // Same seed, same plan.
    EXPECT_EQ(PosePlanCsv(SampleFeasiblePoses(robot, 60, 4), ""), PosePlanCsv(plan, ""));
  }
}

// The grid reports, per (x, z), the band of feasible orientations; the pose it reports lies
// inside that band and is feasible, and points outside the frame have no band.
TEST(ManyCableWorkspace, GridReportsTheFeasibleBand) {
  const Robot robot = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/planar3_suspended.yaml");
  const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, 0.1);
  ASSERT_GT(grid.num_feasible, 20);
  for (const WorkspacePoint& p : grid.points) {
    if (!p.evaluation.feasible()) {
      EXPECT_TRUE(std::isnan(p.theta_min_rad));
      continue;
    }
    EXPECT_LE(p.theta_min_rad, p.evaluation.equilibrium.q(2));
    EXPECT_GE(p.theta_max_rad, p.evaluation.equilibrium.q(2));
    EXPECT_TRUE(EvaluatePose(robot, p.evaluation.equilibrium.q).feasible());
    // Just beyond the band's ends the scan found nothing feasible (a band, not scattered points).
    // The band's ends are feasible orientations themselves.
    EXPECT_TRUE(EvaluatePose(robot, Eigen::Vector3d(p.x_m, p.z_m, p.theta_min_rad)).feasible());
    EXPECT_TRUE(EvaluatePose(robot, Eigen::Vector3d(p.x_m, p.z_m, p.theta_max_rad)).feasible());
    const Eigen::Vector3d below(p.x_m, p.z_m, p.theta_min_rad - kThetaScanStep_rad);
    if (std::abs(below(2)) <= robot.theta_max_rad) {
      EXPECT_FALSE(EvaluatePose(robot, below).feasible());
    }
  }
  const std::string csv = WorkspaceCsv(robot, grid, "");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "x,z,theta,t1,t2,t3,feasible,reason,theta_min,theta_max");
}

// Every point of a many-cable grid is a theta scan: the cap on the grid is lower, named by --step.
TEST(ManyCableWorkspace, FineGridIsRefusedNamingTheStep) {
  const Robot robot = LoadRobotFile(std::string(CABLECAL_SOURCE_DIR) + "/robots/planar3_suspended.yaml");
  try {
    ComputeWorkspaceGrid(robot, 0.01);  // 301 x 201 points
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--step: 0.01 m makes a grid of more than 40,000 points"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(ComputeWorkspaceGrid(robot, 0.05));  // 61 x 41 points
}

}  // namespace
}  // namespace cablecal
