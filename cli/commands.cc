#include "cli/commands.h"

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/version.h"
#include "model/statics.h"
#include "workspace/workspace.h"

namespace cablecal::cli {

Robot LoadRobotOption(const std::string& robot_path) {
  return robot_path.empty() ? BuiltinRobot() : LoadRobotFile(robot_path);
}

void RunPlotScript(const std::string& script, const std::vector<std::string>& args) {
  const char* scripts_env = std::getenv("CABLECAL_SCRIPTS_DIR");
  const std::string scripts_dir = scripts_env ? scripts_env : CABLECAL_SCRIPTS_DIR;
  const char* python_env = std::getenv("CABLECAL_PYTHON");
  // Debian's python3-matplotlib is installed for /usr/bin/python3, which may not be the
  // python3 first on PATH (pyenv, conda).
  std::string python = python_env ? python_env
                                  : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  std::vector<std::string> argv = {python, scripts_dir + "/" + script};
  argv.insert(argv.end(), args.begin(), args.end());
  const std::string command = CommandLine(argv);
  const int status = std::system(command.c_str());
  if (status != 0) {
    throw SolverFailure("plotting failed (exit status " +
                        std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : status) + "): " + command);
  }
}

int RunWorkspace(const Context& ctx, const WorkspaceOptions& options) {
  const Robot robot = LoadRobotOption(options.robot_path);
  const WorkspaceGrid grid = ComputeWorkspaceGrid(robot, options.step_m);
  AtomicOutput output;
  const std::string temp_csv =
      output.WriteText(options.out_path, WorkspaceCsv(robot, grid, ProvenanceComment(ctx.command_line)));
  if (!options.plot_path.empty()) {
    // The script reads the CSV's temporary: final files appear only when both succeeded.
    std::vector<std::string> args = {temp_csv, output.Add(options.plot_path)};
    args.push_back("--frame=" + FormatDouble(robot.frame_width_m) + "," + FormatDouble(robot.frame_height_m));
    for (const Cable& c : robot.cables) {
      args.push_back("--exit=" + FormatDouble(c.p_F_exit_m.x()) + "," + FormatDouble(c.p_F_exit_m.y()));
    }
    args.push_back("--home=" + FormatDouble(robot.p_F_home_m.x()) + "," + FormatDouble(robot.p_F_home_m.y()));
    args.push_back("--title=" + robot.name);
    RunPlotScript("plot_workspace.py", args);
  }
  output.Commit();
  std::printf("workspace of %s: %d of %zu grid points feasible (step %s m), area ~ %s m^2\n", robot.name.c_str(),
              grid.num_feasible, grid.points.size(), FormatDouble(options.step_m).c_str(),
              FormatDouble(grid.feasible_area_m2()).c_str());
  return kExitOk;
}

int RunSample(const Context& ctx, const SampleOptions& options) {
  const Robot robot = LoadRobotOption(options.robot_path);
  const std::vector<PlanPose> plan = SampleFeasiblePoses(robot, options.poses, options.seed);
  AtomicOutput output;
  output.WriteText(options.out_path, PosePlanCsv(plan, ProvenanceComment(ctx.command_line)));
  output.Commit();
  std::printf("wrote %zu random feasible poses of %s (seed %llu) to %s\n", plan.size(), robot.name.c_str(),
              options.seed, options.out_path.c_str());
  return kExitOk;
}

}  // namespace cablecal::cli
