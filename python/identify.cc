// Binds the identification and what follows it: cablecal.identify and its
// cablecal.IdentifyResult, cablecal.calibrated_robot, cablecal.report (the calibration report,
// figures drawn with this interpreter), and cablecal.validate with its cablecal.Validation.

#include <optional>
#include <string>
#include <vector>

#include "common/atomic_output.h"
#include "common/error.h"
#include "identify/calibration_report.h"
#include "experiment/experiment.h"
#include "identify/identify.h"
#include "identify/validate.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "experiment/correction.h"

namespace cablecal::python {
namespace {

// The plotting scripts: CABLECAL_SCRIPTS_DIR, else share/cablecal/scripts beside the module as
// the build and an install place them (build/python/ and build/share/; lib/python3/dist-packages/
// and share/ under the prefix), as the CLI finds them beside itself.
std::string PlotScriptsDir() {
  py::module_ os = py::module_::import("os");
  py::object env = os.attr("environ").attr("get")("CABLECAL_SCRIPTS_DIR");
  if (!env.is_none()) return env.cast<std::string>();
  const std::string here = os.attr("path").attr("dirname")(py::module_::import("cablecal").attr("__file__")).cast<std::string>();
  for (const std::string& dir : {here + "/../share/cablecal/scripts", here + "/../../../share/cablecal/scripts"}) {
    if (os.attr("path").attr("isdir")(dir).cast<bool>()) return dir;
  }
  return here + "/../share/cablecal/scripts";  // named by the failure
}

// Draws a report's figures with this interpreter (it has NumPy; matplotlib is its own to have)
// by the plotting script `name`: "" or why not, as the CLI's runner says it.
std::string DrawWithPython(const std::string& name, const std::vector<std::string>& arguments) {
  const std::string script = PlotScriptsDir() + "/" + name;
  py::list command;
  command.append(py::module_::import("sys").attr("executable"));
  command.append(script);
  for (const std::string& a : arguments) command.append(a);
  py::object done = py::module_::import("subprocess")
                        .attr("run")(command, py::arg("capture_output") = true, py::arg("text") = true);
  const int status = done.attr("returncode").cast<int>();
  if (status == 0) return "";
  // Exit status 3: the script could not import matplotlib or numpy (scripts/plot_report.py).
  if (status == 3) {
    return "the figure could not be made: this interpreter (" + command[0].cast<std::string>() +
           ") has no matplotlib (or numpy): install it (pip install matplotlib, or apt-get install "
           "python3-matplotlib for Debian's /usr/bin/python3)";
  }
  std::string why = done.attr("stderr").cast<std::string>();
  while (!why.empty() && why.back() == '\n') why.pop_back();
  why = why.substr(why.rfind('\n') + 1);  // the exception's line
  return "the figure could not be made: the plotting script failed (exit status " + std::to_string(status) + "): " +
         script + (why.empty() ? "" : ": " + why);
}

// Where readings came from: the file of their first reading ("file:line"), if read from one.
std::string SourceOf(const std::vector<Measurement>& readings, const std::string& otherwise) {
  if (readings.empty() || readings.front().where.empty()) return otherwise;
  const std::string& where = readings.front().where;
  return where.substr(0, where.rfind(':'));
}

}  // namespace

// Long (~265 lines) for a reason: a binding table, each class's properties and each function's
// keywords in the order help() shows them.
void BindIdentify(py::module_& m) {
  // ---- identify
  py::class_<IdentifyResult>(m, "IdentifyResult")
      .def_property_readonly("status", [](const IdentifyResult& r) { return std::string(ToString(r.status)); })
      .def_readonly("message", &IdentifyResult::message)
      .def_readonly("iterations", &IdentifyResult::iterations)
      .def_readonly("final_cost", &IdentifyResult::final_cost)
      .def_readonly("rms_encoder_m", &IdentifyResult::rms_encoder_m)
      .def_property_readonly("rms_laser_m", [](const IdentifyResult& r) { return r.rms_sensor[static_cast<int>(SensorId::kLaser)]; })
      .def_property_readonly("rms_inclinometer_rad",
                             [](const IdentifyResult& r) { return r.rms_sensor[static_cast<int>(SensorId::kInclinometer)]; })
      .def_property_readonly("geometry_names", [](const IdentifyResult& r) {
        return GeometryNames(static_cast<int>(r.geometry.size() / 3));
      })
      .def_property_readonly("geometry", [](const IdentifyResult& r) { return Vector(r.geometry); }, "(3m,), m")
      .def_property_readonly("std", [](const IdentifyResult& r) { return Vector(r.geometry_std); }, "(3m,), m")
      .def_property_readonly("correlation", [](const IdentifyResult& r) { return Array(r.geometry_correlation); })
      .def_property_readonly("covariance", [](const IdentifyResult& r) {
        const Eigen::VectorXd& s = r.geometry_std;
        return Array(s.asDiagonal() * r.geometry_correlation * s.asDiagonal());
      }, "(3m, 3m), m^2")
      .def_property_readonly("loss", [](const IdentifyResult& r) { return ToString(r.loss); })
      .def_readonly("down_weighted", &IdentifyResult::down_weighted)
      .def_readonly("dropped_pose_ids", &IdentifyResult::dropped_pose_ids)
      .def_readonly("geometry_prior_sigma_m", &IdentifyResult::geometry_prior_sigma_m)
      .def_readonly("warnings", &IdentifyResult::warnings)
      .def_readonly("missing_sensors", &IdentifyResult::missing_sensors)
      .def_property_readonly("readings", [](const IdentifyResult& r) {
        py::list out;
        for (const ReadingFit& f : r.readings) {
          py::dict d;
          d["pose_id"] = f.pose_id;
          d["encoder_sigmas"] = Vector(f.encoder_sigmas);
          for (const SensorUnit& u : kPlanarSensors) {  // "laser_sigmas", ...
            const std::optional<double>& sigmas = f.sensor_sigmas[static_cast<int>(u.id)];
            d[(std::string(u.name) + "_sigmas").c_str()] = sigmas ? py::cast(*sigmas) : py::none();
          }
          d["encoder_weights"] = Vector(f.encoder_weights);
          for (const SensorUnit& u : kPlanarSensors) {
            d[(std::string(u.name) + "_weight").c_str()] = f.sensor_weights[static_cast<int>(u.id)];
          }
          out.append(d);
        }
        return out;
      }, "per reading: each sensor's residual (model - reading) over its sigma, and the loss's weights")
      .def_property_readonly("held", [](const IdentifyResult& r) {
        std::vector<std::string> held;
        const std::vector<std::string> names = GeometryNames(static_cast<int>(r.geometry.size()) / 3);
        for (int k = 0; k < r.geometry.size(); ++k) {
          if (IsHeld(r, k)) held.push_back(names[k]);
        }
        return held;
      }, "the geometric parameters held rather than estimated (a1x under gauge a1x): their std is 0 by construction")
      .def_property_readonly("pose_ids", [](const IdentifyResult& r) {
        std::vector<int> ids;
        for (const PoseEstimate& p : r.poses) ids.push_back(p.pose_id);
        return ids;
      }, "the poses of `poses`, one per pose id")
      .def_property_readonly("poses", [](const IdentifyResult& r) {
        Eigen::MatrixXd q(r.poses.size(), 3);
        for (std::size_t j = 0; j < r.poses.size(); ++j) q.row(j) = r.poses[j].q.transpose();
        return Array(q);
      }, "(n, 3): x, z, theta estimated")
      .def_property_readonly("pose_std", [](const IdentifyResult& r) {
        Eigen::MatrixXd q(r.poses.size(), 3);
        for (std::size_t j = 0; j < r.poses.size(); ++j) q.row(j) = r.poses[j].std_dev.transpose();
        return Array(q);
      })
      .def_property_readonly("identifiability", [](const IdentifyResult& r) {
        py::dict d;
        d["geometry_names"] = r.identifiability.geometry_names;
        d["singular_values"] = Vector(r.identifiability.singular_values);
        d["condition_number"] = r.identifiability.condition_number;
        d["weakest_pose_id"] = r.identifiability.weakest_pose_id;
        d["null_directions"] = r.identifiability.null_directions;
        return d;
      })
      .def_property_readonly("sensor_correction", [](const IdentifyResult& r) -> py::object {
        if (!r.corrected_for) return py::none();
        py::dict d;
        d["laser_offset_m"] = r.corrected_for->laser_offset_m;
        d["inclinometer_offset_rad"] = r.corrected_for->inclinometer_offset_rad;
        d["inclinometer_sec_coefficient_rad"] = r.corrected_for->inclinometer_sec_coefficient_rad;
        return d;
      }, "The systematic sensor errors the readings were corrected for before the solve, or None.")
      .def("to_yaml", [](const IdentifyResult& r) { return IdentifyResultYaml(r, CallText("identify")); },
           "The CLI's result.yaml (the command line reads python: cablecal.identify).");
  m.def(
      "identify",
      [](py::handle robot_arg, py::handle measurements_arg, py::handle estimator, py::handle gauge,
         py::handle max_iterations, py::handle loss, py::handle geometry_prior, py::handle equilibrium,
         py::handle identify, py::handle plan) -> py::object {
        if (py::isinstance<SpatialRobot>(robot_arg)) {
          return SpatialIdentify(robot_arg.cast<const SpatialRobot&>(), measurements_arg, estimator, gauge,
                                 max_iterations, loss, geometry_prior, equilibrium, identify, plan);
        }
        if (!identify.is_none()) {
          throw InputError("identify", AsText(identify, "identify"), "serves spatial robots only (a SpatialRobot)");
        }
        if (!plan.is_none()) throw InputError("plan", "", "serves spatial robots only (a SpatialRobot)");
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const PyMeasurements& measurements = AsObject<PyMeasurements>(measurements_arg, "measurements", "Measurements");
        if (measurements.num_cables != robot.num_cables()) Bad("measurements", "read for a robot with another number of cables");
        IdentifyOptions o;
        o.estimator = ParseEstimator(AsText(estimator, "estimator"));
        // None: the planar defaults (a spatial robot has its own: gauge auto, 200 iterations, statics on).
        o.gauge = ParseGauge(gauge.is_none() ? "a1x" : AsText(gauge, "gauge"));
        if (!max_iterations.is_none()) {
          o.max_iterations = static_cast<int>(AsInteger(max_iterations, "max_iterations", 1, kMaxIdentifyIterations));
        }
        o.loss = ParseLoss(AsText(loss, "loss"));
        if (!geometry_prior.is_none()) o.geometry_prior_sigma_m = AsNumber(geometry_prior, "geometry_prior");  // 0 refused
        o.equilibrium = equilibrium.is_none() ? kDefaultEquilibrium : OnOff(equilibrium, "equilibrium");
        o.source = "measurements";
        // As the CLI: a robot with systematic sensor errors has them removed before the solve.
        o.readings_as_read = true;
        IdentifyResult r;
        {
          py::gil_scoped_release release;
          r = Identify(robot, measurements.readings, o);
        }
        RequireUsableResult(r, "measurements");
        for (const std::string& w : r.warnings) {
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        }
        return py::cast(std::move(r));
      },
      py::arg("robot"), py::arg("measurements"), py::arg("estimator") = "ml", py::arg("gauge") = py::none(),
      py::arg("max_iterations") = py::none(), py::arg("loss") = "none", py::arg("geometry_prior") = py::none(),
      py::arg("equilibrium") = py::none(), py::arg("identify") = py::none(), py::arg("plan") = py::none(),
      "Identifies exit points and initial lengths (cablecal identify); InputError when the data cannot "
      "calibrate this robot, SolverError when the solve does not converge. geometry_prior: the standard "
      "deviation (m) of the nominal geometry, a prior as identify --geometry-prior (None: none). Defaults (None): "
      "gauge 'a1x', 100 iterations, equilibrium as the CLI's; for a SpatialRobot and SpatialMeasurements: gauge "
      "'auto' (or 'none', 'prior', 'hold:a1x,a1y,...,b1x,...'), 200 iterations, the statics on ('off' to leave them "
      "out), identify 'exits' ('anchors': the platform anchors b1x .. bmz too, as identify --identify anchors), "
      "plan: the SpatialPlan the readings were taken at (as identify --plan: each pose starts from its commanded "
      "pose, matched by pose id; None: from home), estimator 'ml' only, no geometry_prior; it returns a "
      "SpatialIdentifyResult.");
  m.def("calibrated_robot", [](py::handle nominal_arg, py::handle result_arg) -> py::object {
        if (py::isinstance<SpatialRobot>(nominal_arg)) {
          return SpatialCalibratedRobot(nominal_arg.cast<const SpatialRobot&>(), result_arg);
        }
        const Robot& nominal = AsObject<Robot>(nominal_arg, "nominal", "Robot");
        const IdentifyResult& r = AsObject<IdentifyResult>(result_arg, "result", "IdentifyResult");
        RequireResultOfRobot("result", r.robot_name, static_cast<int>(r.geometry.size()) / 3, nominal);
        return py::cast(WithGeometry(nominal, r.geometry));
      },
        py::arg("nominal"), py::arg("result"),
        "The nominal robot with the identified geometry (a SpatialRobot's with each cable's initial_length).");
  m.def(
      "report",
      [](py::handle nominal_arg, py::handle result_arg, py::handle directory, py::handle holdout_arg) {
        if (py::isinstance<SpatialRobot>(nominal_arg)) {
          return SpatialReport(nominal_arg.cast<const SpatialRobot&>(), result_arg, directory, holdout_arg,
                               [](const std::vector<std::string>& a) { return DrawWithPython("plot_spatial_report.py", a); });
        }
        const Robot& nominal = AsObject<Robot>(nominal_arg, "nominal", "Robot");
        const IdentifyResult& r = AsObject<IdentifyResult>(result_arg, "result", "IdentifyResult");
        RequireResultOfRobot("result", r.robot_name, static_cast<int>(r.geometry.size()) / 3, nominal);
        const std::string dir = AsPath(directory, "directory");
        OutputFolder folder("directory", dir, ReportFileNames());
        ReportSources sources{CallText("report"), "the measurements given to cablecal.identify", ""};
        std::optional<ValidationResult> validation;
        if (!holdout_arg.is_none()) {
          const PyMeasurements& holdout = AsObject<PyMeasurements>(holdout_arg, "holdout", "Measurements");
          if (holdout.num_cables != nominal.num_cables()) Bad("holdout", "read for a robot with another number of cables");
          sources.holdout = SourceOf(holdout.readings, "the held-out Measurements given to cablecal.report");
          // As identify's readings and the CLI's --holdout: corrected for the robot file's systematic errors.
          const std::vector<Measurement> readings = CorrectedReadings(nominal, holdout.readings, sources.holdout);
          py::gil_scoped_release release;
          validation = ValidateCalibration(nominal, r, readings, sources);
        }
        const std::string figure_error =
            StageReport(folder, nominal, r, IdentifyResultYaml(r, CallText("identify")),
                        validation ? &*validation : nullptr, sources,
                        [](const std::vector<std::string>& a) { return DrawWithPython("plot_report.py", a); });
        folder.Commit();
        if (!figure_error.empty()) throw FigureFailure(ReportWithoutFiguresMessage(dir, figure_error));
        return dir + "/report.md";
      },
      py::arg("nominal"), py::arg("result"), py::arg("directory"), py::arg("holdout") = py::none(),
      "Writes the calibration report of `result` into `directory` as identify --report does (report.md, its figures "
      "and data files; the folder is created if new, its parent must exist) and returns report.md's path. holdout: "
      "held-out Measurements, validated with the calibrated and the nominal robot. The figures are drawn with this "
      "interpreter's matplotlib; if they cannot be, the rest is written and FigureError raised. A SpatialRobot "
      "with its SpatialIdentifyResult (and held-out SpatialMeasurements) writes the spatial report.");

  // ---- validate
  py::class_<ValidationResult>(m, "Validation",
                               "Each robot's predictions of held-out poses against the readings (cablecal validate).")
      .def_property_readonly("pose_ids", [](const ValidationResult& r) { return r.pose_ids; }, "one per reading")
      .def_property_readonly("z_measured", [](const ValidationResult& r) -> py::object {
        if (!r.has_laser) return py::none();
        return Vector(Eigen::Map<const Eigen::VectorXd>(r.z_measured_m.data(), r.z_measured_m.size()));
      }, "(n,), m; None without a laser")
      .def_property_readonly("theta_measured", [](const ValidationResult& r) -> py::object {
        if (!r.has_inclinometer) return py::none();
        return Vector(Eigen::Map<const Eigen::VectorXd>(r.theta_measured_rad.data(), r.theta_measured_rad.size()));
      }, "(n,), rad; None without an inclinometer")
      .def_property_readonly("robots", [](const ValidationResult& r) {
        const auto errors = [](const std::vector<double>& e, bool measured) -> py::object {
          if (!measured) return py::none();
          return Vector(Eigen::Map<const Eigen::VectorXd>(e.data(), e.size()));
        };
        py::dict d;
        for (const RobotPrediction& p : r.robots) {
          Eigen::MatrixXd q(p.q.size(), 3);
          for (std::size_t j = 0; j < p.q.size(); ++j) q.row(j) = p.q[j].transpose();
          py::dict e;
          e["robot"] = p.robot;
          e["poses"] = Array(q);
          e["z_error"] = errors(p.z_error_m, r.has_laser);
          e["theta_error"] = errors(p.theta_error_rad, r.has_inclinometer);
          e["z_rms"] = p.z_m ? py::object(py::float_(p.z_m->rms)) : py::none();
          e["z_max_abs"] = p.z_m ? py::object(py::float_(p.z_m->max_abs)) : py::none();
          e["theta_rms"] = p.theta_rad ? py::object(py::float_(p.theta_rad->rms)) : py::none();
          e["theta_max_abs"] = p.theta_rad ? py::object(py::float_(p.theta_rad->max_abs)) : py::none();
          d[py::str(p.name)] = e;
        }
        return d;
      }, "'calibrated' (and 'nominal'): poses (n, 3) predicted x, z, theta; z_error, theta_error (n,) = predicted - "
         "measured; z_rms, z_max_abs (m), theta_rms, theta_max_abs (rad); None for a sensor the data lack")
      .def_property_readonly("ratio", [](const ValidationResult& r) -> py::object {
        if (r.robots.size() < 2) return py::none();
        py::dict d;
        d["z_rms"] = r.has_laser ? py::object(py::float_(ZRmsRatio(r))) : py::none();
        d["theta_rms"] = r.has_inclinometer ? py::object(py::float_(ThetaRmsRatio(r))) : py::none();
        return d;
      }, "nominal / calibrated RMS errors (> 1: the calibration helped); None without a nominal robot")
      .def_property_readonly("skipped", [](const ValidationResult& r) {
        py::list out;
        for (const SkippedReading& k : r.skipped) out.append(py::make_tuple(k.pose_id, k.reason));
        return out;
      }, "the readings left out with skip_infeasible=True: (pose id, reason) in the readings' order")
      .def_property_readonly("not_compared", [](const ValidationResult& r) { return NotCompared(r); },
                             "what the data lack, e.g. \"no 'theta' column (inclinometer)\"; empty when both compared")
      .def("to_csv", [](const ValidationResult& r) { return ValidationCsv(r, ""); },
           "The CLI's per-reading CSV (no provenance lines).")
      .def("to_yaml", [](const ValidationResult& r) { return ValidationSummaryYaml(r, CallText("validate")); },
           "The CLI's summary YAML (the command line reads python: cablecal.validate).");
  m.def(
      "validate",
      [](py::handle robot_arg, py::handle measurements_arg, py::handle nominal_arg, py::handle skip_infeasible) -> py::object {
        if (!py::isinstance<py::bool_>(skip_infeasible)) Bad("skip_infeasible", "expected True or False");
        const bool skip = skip_infeasible.cast<bool>();
        if (py::isinstance<SpatialRobot>(robot_arg)) {
          return SpatialValidatePy(robot_arg.cast<const SpatialRobot&>(), measurements_arg, nominal_arg, skip);
        }
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const PyMeasurements& measurements = AsObject<PyMeasurements>(measurements_arg, "measurements", "Measurements");
        if (measurements.num_cables != robot.num_cables()) Bad("measurements", "read for a robot with another number of cables");
        std::optional<Robot> nominal;
        if (!nominal_arg.is_none()) nominal = AsObject<Robot>(nominal_arg, "nominal", "Robot");
        const std::vector<Measurement> readings = CorrectedReadings(robot, measurements.readings, "measurements");
        ValidationResult r;
        {
          py::gil_scoped_release release;
          r = Validate(robot, nominal, readings, "measurements", skip);
        }
        if (robot.sensors.systematic.any()) r.corrected_for = robot.sensors.systematic;
        if (!r.skipped.empty()) {
          std::string ids;
          for (const SkippedReading& k : r.skipped) ids += (ids.empty() ? "" : ", ") + std::to_string(k.pose_id);
          const std::string w = "skipped " + std::to_string(r.skipped.size()) + " of " +
                                std::to_string(readings.size()) + " readings a robot cannot hold (poses " + ids +
                                "; Validation.skipped says why)";
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        }
        return py::cast(std::move(r));
      },
      py::arg("robot"), py::arg("measurements"), py::arg("nominal") = py::none(), py::arg("skip_infeasible") = false,
      "Predicts every measured pose with `robot` (and `nominal`) and compares z and theta with the readings "
      "(cablecal validate); InputError when a robot cannot hold a pose's lengths, or with skip_infeasible=True "
      "such readings are left out and listed in Validation.skipped (validate --skip-infeasible). A SpatialRobot "
      "and SpatialMeasurements give a SpatialValidation: every sensor the readings have compared.");
}

}  // namespace cablecal::python
