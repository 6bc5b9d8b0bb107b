// Binds the experiment: cablecal.Plan (measurement poses), cablecal.Measurements (readings, from
// arrays or a CSV), cablecal.sample (random feasible poses), and cablecal.simulate with the
// cablecal.Experiment it returns (the readings of a plan on a true robot).

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/format.h"
#include "experiment/experiment.h"
#include "model/robot.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "workspace/workspace.h"

namespace cablecal::python {
namespace {

Eigen::MatrixXd PlanColumn(const PyPlan& p, Eigen::VectorXd PlanPose::*member) {
  Eigen::MatrixXd m(p.poses.size(), p.num_cables);
  for (std::size_t j = 0; j < p.poses.size(); ++j) {
    const Eigen::VectorXd& v = p.poses[j].*member;
    for (int i = 0; i < p.num_cables; ++i) m(j, i) = i < v.size() ? v(i) : std::nan("");
  }
  return m;
}

PyMeasurements MakeMeasurements(const Robot& robot, py::handle dl, py::handle z, py::handle theta, py::handle pose_ids) {
  const Eigen::MatrixXd dl_m = AsMatrix(dl, "dl", -1, robot.num_cables());
  const long n = dl_m.rows();
  // None: no such sensor (the CSV without that column).
  const Eigen::MatrixXd z_m = z.is_none() ? Eigen::MatrixXd() : AsMatrix(z, "z", n, 1);
  const Eigen::MatrixXd theta_rad = theta.is_none() ? Eigen::MatrixXd() : AsMatrix(theta, "theta", n, 1);
  PyMeasurements out{{}, robot.num_cables()};
  std::vector<long long> ids;
  if (pose_ids.is_none()) {
    for (long j = 0; j < n; ++j) ids.push_back(j + 1);
  } else {
    if (!py::isinstance<py::sequence>(pose_ids) && !py::isinstance<py::array>(pose_ids)) {
      Bad("pose_ids", "expected a sequence of integers");
    }
    for (const auto& e : pose_ids) ids.push_back(AsInteger(e, "pose_ids", 1, 1LL << 30));
    if (static_cast<long>(ids.size()) != n) Bad("pose_ids", "one id per row of dl");
  }
  for (long j = 0; j < n; ++j) {
    Measurement m;
    m.pose_id = static_cast<int>(ids[j]);
    m.dl_m = dl_m.row(j).transpose();
    if (!z.is_none()) m.set(SensorId::kLaser, z_m(j, 0));
    if (!theta.is_none()) m.set(SensorId::kInclinometer, theta_rad(j, 0));
    out.readings.push_back(m);
  }
  return out;
}

}  // namespace

// Long (~160 lines) for a reason: a binding table, as BindIdentify.
void BindExperiment(py::module_& m) {
  // ---- Pose plans
  py::class_<PyPlan>(m, "Plan", "Measurement poses: a pose plan (sample, design).")
      .def_static(
          "load",
          [](py::handle robot_arg, py::handle path) {
            const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
            const std::string p = AsPath(path, "path");
            PyPlan plan{ReadPosePlanCsv(p, robot.num_cables()), robot.num_cables()};
            CheckPlanMatchesRobot(robot, plan.poses, p);
            return plan;
          },
          py::arg("robot"), py::arg("path"), "Reads a pose plan CSV made for `robot`.")
      .def_property_readonly("poses", [](const PyPlan& p) {
        Eigen::MatrixXd q(p.poses.size(), 3);
        for (std::size_t j = 0; j < p.poses.size(); ++j) q.row(j) = p.poses[j].q.transpose();
        return Array(q);
      }, "(n, 3): x (m), z (m), theta (rad)")
      .def_property_readonly("tensions", [](const PyPlan& p) { return Array(PlanColumn(p, &PlanPose::tensions_N)); },
                             "(n, m), N")
      .def_property_readonly("lengths", [](const PyPlan& p) { return Array(PlanColumn(p, &PlanPose::lengths_m)); },
                             "(n, m), m")
      .def_property_readonly("length_changes",
                             [](const PyPlan& p) { return Array(PlanColumn(p, &PlanPose::length_change_m)); },
                             "(n, m), m: the encoder commands from home")
      .def("to_csv", [](const PyPlan& p) { return PosePlanCsv(p.poses, ""); }, "The CLI's pose plan CSV (no provenance lines).")
      .def("__len__", [](const PyPlan& p) { return p.poses.size(); });

  // ---- Measurements
  py::class_<PyMeasurements>(m, "Measurements",
                             "Readings: dl (n, m), z (n,) or None (no laser), theta (n,) or None (no inclinometer); "
                             "pose_ids may repeat (repeated readings of one pose).")
      .def(py::init([](py::handle robot_arg, py::handle dl, py::handle z, py::handle theta, py::handle pose_ids) {
             const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
             return MakeMeasurements(robot, dl, z, theta, pose_ids);
           }),
           py::arg("robot"), py::arg("dl"), py::arg("z") = py::none(), py::arg("theta") = py::none(),
           py::arg("pose_ids") = py::none())
      .def_static(
          "load",
          [](py::handle robot_arg, py::handle path, py::handle delimiter) {
            const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
            std::vector<std::string> ignored, warnings;
            PyMeasurements m{ReadMeasurementsCsv(AsPath(path, "path"), robot.num_cables(),
                                                 ParseDelimiter(AsText(delimiter, "delimiter")),
                                                 [&](const std::vector<std::string>& names) { ignored = names; },
                                                 [&](const std::string& w) { warnings.push_back(w); }),
                             robot.num_cables()};
            if (!ignored.empty()) warnings.insert(warnings.begin(), "ignoring columns " + QuotedList(ignored));
            for (const std::string& w : warnings) {
              if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
            }
            return m;
          },
          py::arg("robot"), py::arg("path"), py::arg("delimiter") = ",",
          "Reads a measurement CSV by column name (other columns ignored, with a warning).")
      .def_property_readonly("dl", [](const PyMeasurements& p) {
        Eigen::MatrixXd d(p.readings.size(), p.num_cables);
        for (std::size_t j = 0; j < p.readings.size(); ++j) d.row(j) = p.readings[j].dl_m.transpose();
        return Array(d);
      })
      .def_property_readonly("z", [](const PyMeasurements& p) -> py::object {
        if (p.readings.empty() || !p.readings.front().has(SensorId::kLaser)) return py::none();
        Eigen::VectorXd v(p.readings.size());
        for (std::size_t j = 0; j < p.readings.size(); ++j) v(j) = p.readings[j].value(SensorId::kLaser);
        return Vector(v);
      }, "(n,) laser heights, m; None without a laser")
      .def_property_readonly("theta", [](const PyMeasurements& p) -> py::object {
        if (p.readings.empty() || !p.readings.front().has(SensorId::kInclinometer)) return py::none();
        Eigen::VectorXd v(p.readings.size());
        for (std::size_t j = 0; j < p.readings.size(); ++j) v(j) = p.readings[j].value(SensorId::kInclinometer);
        return Vector(v);
      }, "(n,) inclinometer angles, rad; None without an inclinometer")
      .def_property_readonly("pose_ids", [](const PyMeasurements& p) {
        std::vector<int> ids;
        for (const Measurement& r : p.readings) ids.push_back(r.pose_id);
        return ids;
      })
      .def("to_csv", [](const PyMeasurements& p) { return MeasurementsCsv(p.readings, ""); })
      .def("__len__", [](const PyMeasurements& p) { return p.readings.size(); });

  // ---- sample
  m.def(
      "sample",
      [](py::handle robot_arg, py::handle n, py::handle seed, py::handle yaw_range_deg) -> py::object {
        const int count = static_cast<int>(AsInteger(n, "n", 1, kMaxPlanPoses));
        const std::uint64_t s = AsSeed(seed);
        if (py::isinstance<SpatialRobot>(robot_arg)) {
          return SpatialSample(robot_arg.cast<const SpatialRobot&>(), count, s, yaw_range_deg);
        }
        if (!yaw_range_deg.is_none()) Bad("yaw_range_deg", "serves spatial robots only (a cablecal.SpatialRobot)");
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        PyPlan plan{{}, robot.num_cables()};
        {
          py::gil_scoped_release release;
          plan.poses = SampleFeasiblePoses(robot, count, s);
        }
        return py::cast(std::move(plan));
      },
      py::arg("robot"), py::arg("n"), py::arg("seed") = 1, py::arg("yaw_range_deg") = py::none(),
      "n uniform random feasible poses (cablecal sample): a Plan, or a SpatialPlan for a SpatialRobot (yaw within "
      "home's +- yaw_range_deg, default 30).");

  // ---- simulate
  py::class_<PlanSimulation>(m, "Experiment", "A simulated experiment: measurements, the true robot and poses.")
      .def_property_readonly("measurements", [](const PlanSimulation& s) {
        return PyMeasurements{s.experiment.measurements, s.truth.num_cables()};
      })
      .def_property_readonly("truth", [](const PlanSimulation& s) { return WithGeometry(s.truth, GeometryOf(s.truth)); })
      .def_property_readonly("true_poses", [](const PlanSimulation& s) {
        Eigen::MatrixXd q(s.experiment.true_poses.size(), 3);
        for (std::size_t j = 0; j < s.experiment.true_poses.size(); ++j) q.row(j) = s.experiment.true_poses[j].transpose();
        return Array(q);
      })
      .def_property_readonly("skipped", [](const PlanSimulation& s) {
        py::list out;
        for (const SkippedPose& k : s.experiment.skipped) out.append(py::make_tuple(k.pose_id, k.reason));
        return out;
      }, "the plan's poses skipped with skip_infeasible=True: (pose id, reason), in plan order");
  m.def(
      "simulate",
      [](py::handle robot_arg, py::handle plan_arg, py::handle truth_arg, py::handle geometry_sigma,
         py::handle sensors, py::handle encoder_noise, py::handle seed, py::handle systematic_errors,
         py::handle skip_infeasible) -> py::object {
        if (py::isinstance<SpatialRobot>(robot_arg)) {
          for (const auto& [flag, name] : {std::pair<py::handle, const char*>{encoder_noise, "encoder_noise"},
                                           {systematic_errors, "systematic_errors"},
                                           {skip_infeasible, "skip_infeasible"}}) {
            if (!py::isinstance<py::bool_>(flag)) Bad(name, "expected True or False");
          }
          return SpatialSimulate(robot_arg.cast<const SpatialRobot&>(), plan_arg, truth_arg, geometry_sigma,
                                 ParseNoisySensors(AsText(sensors, "sensors")), encoder_noise.cast<bool>(), AsSeed(seed),
                                 systematic_errors.cast<bool>(), skip_infeasible.cast<bool>());
        }
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const PyPlan& plan = AsObject<PyPlan>(plan_arg, "plan", "Plan");
        std::optional<Robot> truth;
        if (!truth_arg.is_none()) truth = AsObject<Robot>(truth_arg, "truth", "Robot");
        if (plan.num_cables != robot.num_cables()) Bad("plan", "made for a robot with another number of cables");
        double sigma = 0.0;
        if (!geometry_sigma.is_none()) {
          if (truth) Bad("truth", "give either truth or geometry_sigma, not both");
          sigma = AsNumber(geometry_sigma, "geometry_sigma");
          if (sigma < 0.0) Bad("geometry_sigma", "must be 0 or more (m)");
        }
        if (!py::isinstance<py::bool_>(encoder_noise)) Bad("encoder_noise", "expected True or False");
        SimulationOptions sim{ParseNoisySensors(AsText(sensors, "sensors")), encoder_noise.cast<bool>(), true};
        if (!py::isinstance<py::bool_>(systematic_errors)) Bad("systematic_errors", "expected True or False");
        sim.systematic_errors = systematic_errors.cast<bool>();
        if (!py::isinstance<py::bool_>(skip_infeasible)) Bad("skip_infeasible", "expected True or False");
        sim.skip_infeasible = skip_infeasible.cast<bool>();
        if (sim.systematic_errors && !robot.sensors.systematic.any()) {
          Bad("systematic_errors", "the robot " + robot.name +
                                       " has no systematic sensor errors to add (its sensors block has no laser offset, "
                                       "inclinometer offset_deg or sec_coefficient_deg; fit_sensors makes them)");
        }
        const std::uint64_t s = AsSeed(seed);
        CheckPlanMatchesRobot(robot, plan.poses, "plan");
        std::optional<PlanSimulation> run;
        {
          py::gil_scoped_release release;
          run = SimulatePlan(robot, truth, sigma, plan.poses, sim, s, "plan");
        }
        if (!run->experiment.skipped.empty()) {
          std::string ids;
          for (const SkippedPose& k : run->experiment.skipped) ids += (ids.empty() ? "" : ", ") + std::to_string(k.pose_id);
          const std::string w = "skipped " + std::to_string(run->experiment.skipped.size()) + " of " +
                                std::to_string(plan.poses.size()) + " poses the true robot cannot hold (" + ids +
                                "; Experiment.skipped says why)";
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        }
        return py::cast(std::move(*run));
      },
      py::arg("robot"), py::arg("plan"), py::arg("truth") = py::none(), py::arg("geometry_sigma") = py::none(),
      py::arg("sensors") = "both", py::arg("encoder_noise") = true, py::arg("seed") = 1,
      py::arg("systematic_errors") = false, py::arg("skip_infeasible") = false,
      "The sensors' readings of a plan on a true robot (cablecal simulate); systematic_errors=True also adds the "
      "robot's systematic laser and inclinometer errors (simulate --systematic-errors); skip_infeasible=True skips "
      "the poses the true robot cannot hold (Experiment.skipped) instead of raising InputError at the first "
      "(simulate --skip-infeasible).");
}

}  // namespace cablecal::python
