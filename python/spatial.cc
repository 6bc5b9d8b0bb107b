// Binds the spatial robots (README, "Spatial robots"): cablecal.SpatialRobot (a `kind: spatial`
// robot file, loaded or built in, and back to YAML), cablecal.SpatialPlan,
// cablecal.SpatialMeasurements and cablecal.SpatialExperiment, and the spatial halves of
// cablecal.workspace, cablecal.sample and cablecal.simulate, which hand a SpatialRobot here.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "experiment/measurements.h"  // ReusedPoseIdWarning
#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"
#include "experiment/spatial_simulation.h"
#include "model/builtin_spatial_robots.h"
#include "model/spatial_robot.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "workspace/spatial_workspace.h"

namespace cablecal::python {
namespace {

Eigen::MatrixXd Poses(const std::vector<SpatialPose<double>>& poses) {
  Eigen::MatrixXd q(poses.size(), 6);
  for (std::size_t j = 0; j < poses.size(); ++j) q.row(j) = poses[j].transpose();
  return q;
}

Eigen::MatrixXd PlanColumn(const PySpatialPlan& p, Eigen::VectorXd SpatialPlanPose::*member) {
  Eigen::MatrixXd m(p.poses.size(), p.num_cables);
  for (std::size_t j = 0; j < p.poses.size(); ++j) m.row(j) = (p.poses[j].*member).transpose();
  return m;
}

// Degrees given as None (the default) or a number; a non-finite or non-positive one refused.
std::optional<double> OptionalDegrees(py::handle h, const std::string& name) {
  if (h.is_none()) return std::nullopt;
  return AsNumber(h, name);
}

}  // namespace

void BindSpatial(py::module_& m) {
  py::class_<SpatialRobot>(m, "SpatialRobot", "A spatial robot file's content (kind: spatial; README, \"Spatial robots\").")
      .def_static("load", [](py::handle path) { return LoadSpatialRobotFile(AsPath(path, "path")); }, py::arg("path"),
                  "Loads and validates a spatial robot YAML file (cablecal.Robot.load does too, by the file's kind).")
      .def_static("builtin", [](py::handle name) { return BuiltinSpatialRobot(AsText(name, "name")); }, py::arg("name"),
                  "A built-in spatial robot: 'cogiro', 'ipanema1' or 'irma4u' (robots/<name>.yaml).")
      .def_static("builtin_names", [] { return BuiltinSpatialRobotNames(); })
      .def_static(
          "from_dict", [](py::handle d) { return RobotFromDict(d, LoadSpatialRobotFromString); }, py::arg("d"),
          "A spatial robot from a dict in the robot file's schema (kind: spatial; the file's checks apply).")
      .def("to_dict", [](const SpatialRobot& r) { return FromYaml(YAML::Load(SpatialRobotToYaml(r))); })
      .def("to_yaml", [](const SpatialRobot& r) { return SpatialRobotToYaml(r); })
      .def_property_readonly("name", [](const SpatialRobot& r) { return r.name; })
      .def_property_readonly("num_cables", &SpatialRobot::num_cables)
      .def_property_readonly("kind", [](const SpatialRobot&) { return "spatial"; })
      .def_property_readonly("home", [](const SpatialRobot& r) { return Vector(r.home_pose()); },
                             "(6,): x, y, z (m), roll, pitch, yaw (rad) of the file's home")
      .def("__repr__", [](const SpatialRobot& r) {
        return "<cablecal.SpatialRobot '" + r.name + "', " + std::to_string(r.num_cables()) + " cables>";
      });

  py::class_<PySpatialPlan>(m, "SpatialPlan", "A spatial robot's measurement poses (sample).")
      .def_static(
          "load",
          [](py::handle robot_arg, py::handle path) {
            const SpatialRobot& robot = AsObject<SpatialRobot>(robot_arg, "robot", "SpatialRobot");
            const std::string p = AsPath(path, "path");
            PySpatialPlan plan{{}, robot.num_cables(), {}};
            plan.poses = ReadSpatialPlanCsv(p, robot.num_cables(), &plan.pose_ids);
            CheckSpatialPlanMatchesRobot(robot, plan.poses, p);
            return plan;
          },
          py::arg("robot"), py::arg("path"), "Reads a spatial pose plan CSV made for `robot`.")
      .def_property_readonly("poses", [](const PySpatialPlan& p) {
        std::vector<SpatialPose<double>> q;
        for (const SpatialPlanPose& pose : p.poses) q.push_back(pose.q);
        return Array(Poses(q));
      }, "(n, 6): x, y, z (m), roll, pitch, yaw (rad)")
      .def_property_readonly("tensions", [](const PySpatialPlan& p) { return Array(PlanColumn(p, &SpatialPlanPose::tensions_N)); },
                             "(n, m), N")
      .def_property_readonly("lengths", [](const PySpatialPlan& p) { return Array(PlanColumn(p, &SpatialPlanPose::lengths_m)); },
                             "(n, m), m")
      .def_property_readonly("length_changes",
                             [](const PySpatialPlan& p) { return Array(PlanColumn(p, &SpatialPlanPose::length_change_m)); },
                             "(n, m), m: the encoder commands from home (paid-out length changes)")
      .def("to_csv", [](const PySpatialPlan& p) { return SpatialPlanCsv(p.poses, ""); },
           "The CLI's pose plan CSV (no provenance lines).")
      .def("__len__", [](const PySpatialPlan& p) { return p.poses.size(); });

  py::class_<PySpatialMeasurements>(m, "SpatialMeasurements",
                                    "A spatial robot's readings: dl (n, m) and, per sensor the data have, its columns.")
      .def(py::init([](py::handle robot_arg, py::handle dl, py::handle sensors, py::handle pose_ids) {
             const SpatialRobot& robot = AsObject<SpatialRobot>(robot_arg, "robot", "SpatialRobot");
             return MakeSpatialMeasurements(robot, dl, sensors, pose_ids);
           }),
           py::arg("robot"), py::arg("dl"), py::arg("sensors") = py::none(), py::arg("pose_ids") = py::none(),
           "Readings from arrays: dl (n, m), m; sensors {name: (n, k)} as the `sensors` property gives them; pose_ids "
           "(default 1..n).")
      .def_static(
          "load",
          [](py::handle robot_arg, py::handle path) {
            const SpatialRobot& robot = AsObject<SpatialRobot>(robot_arg, "robot", "SpatialRobot");
            const std::string p = AsPath(path, "path");
            PySpatialMeasurements m{ReadSpatialMeasurementsCsv(p, robot.num_cables()), robot.num_cables()};
            // As the CLI reads a file: values no sensor of this robot can give (millimetres,
            // degrees) are refused here, naming the pose and column, not later in identify.
            CheckSpatialReadingsPlausible(robot, m.readings, p);
            if (const auto reused = ReusedPoseIdWarning(p, m.readings)) {  // the CLI's warning
              if (PyErr_WarnEx(PyExc_UserWarning, reused->c_str(), 1) < 0) throw py::error_already_set();
            }
            return m;
          },
          py::arg("robot"), py::arg("path"),
          "Reads a spatial measurement CSV by column name; values no sensor of `robot` can give are refused.")
      .def_property_readonly("dl", [](const PySpatialMeasurements& p) {
        Eigen::MatrixXd d(p.readings.size(), p.num_cables);
        for (std::size_t j = 0; j < p.readings.size(); ++j) d.row(j) = p.readings[j].dl_m.transpose();
        return Array(d);
      })
      .def_property_readonly("sensors", [](const PySpatialMeasurements& p) {
        py::dict out;
        if (p.readings.empty()) return out;
        for (const SpatialSensor s : kSpatialSensors) {
          if (!p.readings.front().has(s)) continue;
          const int size = SpatialSensorSize(s, p.num_cables);
          Eigen::MatrixXd v(p.readings.size(), size);
          for (std::size_t j = 0; j < p.readings.size(); ++j) v.row(j) = p.readings[j].values(s).transpose();
          out[ToString(s)] = Array(v);
        }
        return out;
      }, "{sensor name: (n, k) array} for each sensor the readings have (inclinometer: roll, pitch; laser: z; "
         "position: px, py, pz; swivel: sw1..swm; heading: yaw; load_cell: f1..fm)")
      .def_property_readonly("pose_ids", [](const PySpatialMeasurements& p) {
        std::vector<int> ids;
        for (const SpatialMeasurement& r : p.readings) ids.push_back(r.pose_id);
        return ids;
      })
      .def("to_csv", [](const PySpatialMeasurements& p) { return SpatialMeasurementsCsv(p.readings, ""); })
      .def("__len__", [](const PySpatialMeasurements& p) { return p.readings.size(); });

  py::class_<SpatialPlanSimulation>(m, "SpatialExperiment", "A simulated spatial experiment: readings, the true robot and poses.")
      .def_property_readonly("measurements", [](const SpatialPlanSimulation& s) {
        return PySpatialMeasurements{s.experiment.measurements, s.truth.num_cables()};
      })
      .def_property_readonly("truth", [](const SpatialPlanSimulation& s) { return s.truth; })
      .def_property_readonly("true_poses", [](const SpatialPlanSimulation& s) { return Array(Poses(s.experiment.true_poses)); },
                             "(n, 6): where the platform settled")
      .def_property_readonly("truth_yaml", [](const SpatialPlanSimulation& s) { return SpatialTruthYaml(s.truth, s.experiment); },
                             "the CLI's --truth-out file (no provenance lines)")
      .def_property_readonly("skipped", [](const SpatialPlanSimulation& s) {
        py::list out;
        for (const SpatialSkippedPose& k : s.experiment.skipped) out.append(py::make_tuple(k.pose_id, k.reason));
        return out;
      });
}

py::object SpatialWorkspace(const SpatialRobot& robot, double step_m, py::handle rpy_deg) {
  Eigen::Vector3d rpy_rad = robot.home_rpy_rad;
  if (!rpy_deg.is_none()) {
    const Eigen::Vector3d deg = AsMatrix(rpy_deg, "rpy_deg", 3, 1).col(0);
    try {
      rpy_rad = WorkspaceOrientation(deg);  // the CLI's --rpy-deg check
    } catch (const InputError& e) {
      const std::string what = e.what();
      Bad("rpy_deg", what.substr(std::string("--rpy-deg: ").size()));
    }
  }
  SpatialWorkspaceGrid grid;
  {
    py::gil_scoped_release release;
    grid = ComputeSpatialWorkspace(robot, rpy_rad, step_m);
  }
  const int mc = robot.num_cables();
  const long n = static_cast<long>(grid.points.size());
  Eigen::MatrixXd xyz(n, 3), rpy(n, 3), t(n, mc);
  py::array_t<bool> feasible(n);
  auto f = feasible.mutable_unchecked<1>();
  py::list reasons;
  for (long k = 0; k < n; ++k) {
    const SpatialWorkspacePoint& p = grid.points[k];
    const bool has = p.evaluation.has_equilibrium;
    xyz.row(k) = p.p_F_m.transpose();
    for (int a = 0; a < 3; ++a) rpy(k, a) = has ? p.evaluation.equilibrium.q(3 + a) : std::nan("");
    for (int i = 0; i < mc; ++i) t(k, i) = has ? p.evaluation.equilibrium.tensions_N(i) : std::nan("");
    f(k) = p.evaluation.feasible();
    reasons.append(ToString(p.evaluation.feasibility));
  }
  py::dict d;
  d["xyz"] = Array(xyz);
  d["rpy"] = Array(rpy);
  d["tensions"] = Array(t);
  d["feasible"] = feasible;
  d["reason"] = reasons;
  d["volume_m3"] = grid.feasible_volume_m3();
  d["csv"] = SpatialWorkspaceCsv(robot, grid, "");
  return d;
}

py::object SpatialSample(const SpatialRobot& robot, int n, std::uint64_t seed, py::handle yaw_range_deg) {
  const std::optional<double> yaw = OptionalDegrees(yaw_range_deg, "yaw_range_deg");
  if (yaw && !(*yaw > 0.0)) Bad("yaw_range_deg", "must be positive (degrees)");
  const double yaw_rad = yaw ? *yaw * M_PI / 180.0 : kDefaultSampleYawRange_rad;
  PySpatialPlan plan{{}, robot.num_cables(), {}};
  {
    py::gil_scoped_release release;
    plan.poses = SampleSpatialPoses(robot, n, seed, yaw_rad);
  }
  return py::cast(std::move(plan));
}

py::object SpatialSimulate(const SpatialRobot& robot, py::handle plan_arg, py::handle truth_arg, py::handle geometry_sigma,
                           NoisySensors noisy, bool encoder_noise, std::uint64_t seed, bool systematic_errors,
                           bool skip_infeasible) {
  const PySpatialPlan& plan = AsObject<PySpatialPlan>(plan_arg, "plan", "SpatialPlan");
  if (plan.num_cables != robot.num_cables()) Bad("plan", "made for a robot with another number of cables");
  std::optional<SpatialRobot> truth;
  if (!truth_arg.is_none()) truth = AsObject<SpatialRobot>(truth_arg, "truth", "SpatialRobot");
  double sigma = 0.0;
  if (!geometry_sigma.is_none()) {
    if (truth) Bad("truth", "give either truth or geometry_sigma, not both");
    sigma = AsNumber(geometry_sigma, "geometry_sigma");
    if (sigma < 0.0) Bad("geometry_sigma", "must be 0 or more (m)");
  }
  if (systematic_errors) Bad("systematic_errors", "a spatial robot file has no systematic sensor errors to add");
  SpatialSimulationOptions sim;
  sim.noisy = noisy;
  sim.encoder_noise = encoder_noise;
  sim.skip_infeasible = skip_infeasible;
  sim.pose_ids = plan.pose_ids;  // a loaded plan's pose column, as simulate numbers its readings
  CheckSpatialPlanMatchesRobot(robot, plan.poses, "plan");
  std::optional<SpatialPlanSimulation> run;
  {
    py::gil_scoped_release release;
    run = SimulateSpatialPlan(robot, truth, sigma, plan.poses, sim, seed, "plan");
  }
  if (!run->experiment.skipped.empty()) {
    const std::string w = "skipped " + std::to_string(run->experiment.skipped.size()) + " of " +
                          std::to_string(plan.poses.size()) +
                          " poses the true robot cannot hold (SpatialExperiment.skipped says why)";
    if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
  }
  return py::cast(std::move(*run));
}

}  // namespace cablecal::python
