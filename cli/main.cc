// cablecal: plan, identify and predict the calibration of cable-driven parallel robots.
// Parses the command line (CLI11) and maps every failure to a documented exit code:
// 0 success, 1 internal error, 2 bad input (file, flag, value), 3 solver failure.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "common/error.h"
#include "common/version.h"

namespace {

using cablecal::cli::Context;

void AddRobotOption(CLI::App* app, std::string* path) {
  app->add_option("--robot", *path, "robot YAML file (default: the built-in wang2022 robot)")
      ->check(CLI::ExistingFile);
}

}  // namespace

int main(int argc, char** argv) {
  Context ctx;
  // argv[0] is recorded as "cablecal" so that outputs do not depend on where it was built.
  std::vector<std::string> args(argv, argv + argc);
  args[0] = "cablecal";
  ctx.command_line = cablecal::CommandLine(args);

  CLI::App app{"cablecal: plan, identify and predict the calibration of cable-driven parallel robots"};
  app.set_version_flag("--version", std::string("cablecal ") + cablecal::Version() + " (commit " +
                                        cablecal::GitCommit() + ")");
  app.require_subcommand(1);

  cablecal::cli::WorkspaceOptions ws;
  CLI::App* ws_cmd = app.add_subcommand("workspace", "grid the feasible cable-tension workspace to CSV (and PNG)");
  AddRobotOption(ws_cmd, &ws.robot_path);
  ws_cmd->add_option("--step", ws.step_m, "grid spacing in m")->capture_default_str()->check(CLI::PositiveNumber);
  ws_cmd->add_option("--out", ws.out_path, "workspace CSV (x,z,theta,t1,t2,feasible,reason)")->required();
  ws_cmd->add_option("--plot", ws.plot_path, "PNG of the feasible region, tensions and exit points");

  cablecal::cli::SampleOptions sample;
  CLI::App* sample_cmd = app.add_subcommand("sample", "draw random feasible poses as a pose plan CSV");
  AddRobotOption(sample_cmd, &sample.robot_path);
  sample_cmd->add_option("--poses", sample.poses, "number of poses")->required()->check(CLI::PositiveNumber);
  sample_cmd->add_option("--seed", sample.seed, "random seed")->capture_default_str();
  sample_cmd->add_option("--out", sample.out_path, "pose plan CSV")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "cablecal: error: %s\nRun with --help for usage.\n", e.what());
    return cablecal::kExitBadInput;
  }

  try {
    if (ws_cmd->parsed()) return cablecal::cli::RunWorkspace(ctx, ws);
    if (sample_cmd->parsed()) return cablecal::cli::RunSample(ctx, sample);
  } catch (const cablecal::InputError& e) {
    std::fprintf(stderr, "cablecal: error: %s\n", e.what());
    return cablecal::kExitBadInput;
  } catch (const cablecal::SolverFailure& e) {
    std::fprintf(stderr, "cablecal: solver failure: %s\n", e.what());
    return cablecal::kExitSolverFailed;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cablecal: internal error: %s\n", e.what());
    return cablecal::kExitInternal;
  }
  return cablecal::kExitInternal;
}
