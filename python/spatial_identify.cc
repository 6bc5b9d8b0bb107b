// Binds the identification and validation of spatial robots (README, "Spatial robots"):
// cablecal.SpatialIdentifyResult and cablecal.SpatialValidation, the spatial halves of
// cablecal.identify, cablecal.calibrated_robot and cablecal.validate (python/identify.cc hands a
// SpatialRobot here), and SpatialMeasurements built from arrays.
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/json.h"
#include "common/atomic_output.h"
#include "identify/spatial_calibration_report.h"
#include "identify/spatial_identify.h"
#include "identify/spatial_report.h"
#include "identify/spatial_validate.h"
#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"
#include "model/spatial_robot.h"
#include "python/bindings.h"
#include "python/converters.h"

namespace cablecal::python {
namespace {

// A result with what its YAML needs: the nominal robot and the options it was identified with.
struct PySpatialIdentifyResult {
  SpatialRobot nominal;
  SpatialIdentifyOptions options;
  SpatialIdentifyResult result;
};

py::list Directions(const std::vector<SpatialDirection>& directions, bool weak = false) {
  py::list out;
  for (const SpatialDirection& d : directions) {
    py::dict e;
    e["description"] = d.description;
    e["relative_singular_value"] = d.relative_singular_value;
    if (weak) e["nearly_rigid"] = d.nearly_rigid;
    e["vector"] = Vector(d.geometry);
    out.append(e);
  }
  return out;
}

Eigen::MatrixXd Poses(const std::vector<SpatialPose<double>>& poses) {
  Eigen::MatrixXd q(poses.size(), 6);
  for (std::size_t j = 0; j < poses.size(); ++j) q.row(j) = poses[j].transpose();
  return q;
}

}  // namespace

PySpatialMeasurements MakeSpatialMeasurements(const SpatialRobot& robot, py::handle dl, py::handle sensors,
                                              py::handle pose_ids) {
  const int m = robot.num_cables();
  const Eigen::MatrixXd dl_m = AsMatrix(dl, "dl", -1, m);
  const long n = dl_m.rows();
  std::array<Eigen::MatrixXd, kNumSpatialSensors> values;
  if (!sensors.is_none()) {
    if (!py::isinstance<py::dict>(sensors)) Bad("sensors", "expected a dict {sensor name: (n, k) array}");
    for (const auto& [key, value] : sensors.cast<py::dict>()) {
      const std::string name = AsText(key, "sensors");
      bool known = false;
      for (const SpatialSensor s : kSpatialSensors) {
        if (name != ToString(s)) continue;
        values[static_cast<int>(s)] = AsMatrix(value, "sensors['" + name + "']", n, SpatialSensorSize(s, m));
        known = true;
      }
      if (!known) {
        Bad("sensors", "'" + name + "' is no spatial sensor (inclinometer, laser, position, swivel, heading, load_cell)");
      }
    }
  }
  std::vector<long long> ids;
  if (pose_ids.is_none()) {
    for (long j = 0; j < n; ++j) ids.push_back(j + 1);
  } else {
    for (const auto& e : pose_ids) ids.push_back(AsInteger(e, "pose_ids", 1, 1LL << 30));
    if (static_cast<long>(ids.size()) != n) Bad("pose_ids", "one id per row of dl");
  }
  PySpatialMeasurements out{{}, m};
  for (long j = 0; j < n; ++j) {
    SpatialMeasurement r;
    r.pose_id = static_cast<int>(ids[j]);
    r.dl_m = dl_m.row(j).transpose();
    for (int s = 0; s < kNumSpatialSensors; ++s) {
      if (values[s].size() > 0) r.sensor_values[s] = values[s].row(j).transpose();
    }
    out.readings.push_back(r);
  }
  return out;
}

py::object SpatialIdentify(const SpatialRobot& robot, py::handle measurements_arg, py::handle estimator,
                           py::handle gauge, py::handle max_iterations, py::handle loss, py::handle geometry_prior,
                           py::handle equilibrium, py::handle identify, py::handle plan_arg) {
  const PySpatialMeasurements& measurements =
      AsObject<PySpatialMeasurements>(measurements_arg, "measurements", "SpatialMeasurements");
  if (measurements.num_cables != robot.num_cables()) Bad("measurements", "read for a robot with another number of cables");
  if (AsText(estimator, "estimator") == "paper") {
    throw InputError("estimator", "", "'paper' serves planar robots only: a spatial robot is identified with 'ml'");
  }
  if (AsText(estimator, "estimator") != "ml") ParseEstimator(AsText(estimator, "estimator"));  // its message
  if (!geometry_prior.is_none()) {
    throw InputError("geometry_prior", "", "serves planar robots only; for a spatial robot gauge='prior' puts the "
                                           "robot file's tracker sigma on every exit coordinate");
  }
  PySpatialIdentifyResult out{robot, {}, {}};
  out.options.gauge = ParseSpatialGauge(gauge.is_none() ? "auto" : AsText(gauge, "gauge"));
  out.options.loss = ParseLoss(AsText(loss, "loss"));
  if (!max_iterations.is_none()) {
    out.options.max_iterations = static_cast<int>(AsInteger(max_iterations, "max_iterations", 1, kMaxIdentifyIterations));
  }
  out.options.statics = equilibrium.is_none() || OnOff(equilibrium, "equilibrium");
  out.options.anchors = !identify.is_none() && ParseSpatialIdentify(AsText(identify, "identify"));
  CheckSpatialReadingsPlausible(robot, measurements.readings, "measurements");
  // As identify --plan: each pose starts from its commanded pose, matched by pose id.
  if (!plan_arg.is_none()) {
    const PySpatialPlan& plan = AsObject<PySpatialPlan>(plan_arg, "plan", "SpatialPlan");
    if (plan.num_cables != robot.num_cables()) Bad("plan", "made for a robot with another number of cables");
    CheckSpatialPlanMatchesRobot(robot, plan.poses, "plan");
    out.options.pose_starts = PoseStartsFromPlan(plan.poses, plan.pose_ids);
  }
  {
    py::gil_scoped_release release;
    out.result = IdentifySpatial(robot, measurements.readings, out.options);
  }
  // As the CLI: a result that is not one is an error, never returned.
  if (out.result.status == SpatialIdentifyStatus::kRankDeficient || out.result.status == SpatialIdentifyStatus::kPoorFit) {
    throw InputError("measurements", "", out.result.message);
  }
  if (!out.result.converged()) throw SolverFailure("measurements: " + out.result.message);
  for (const std::string& w : out.result.warnings) {
    if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
  }
  return py::cast(std::move(out));
}

py::object SpatialCalibratedRobot(const SpatialRobot& nominal, py::handle result_arg) {
  const PySpatialIdentifyResult& r = AsObject<PySpatialIdentifyResult>(result_arg, "result", "SpatialIdentifyResult");
  if (r.nominal.name != nominal.name || r.nominal.num_cables() != nominal.num_cables()) {
    Bad("result", "identified for " + r.nominal.name + " (" + std::to_string(r.nominal.num_cables()) + " cables), not " +
                      nominal.name + " (" + std::to_string(nominal.num_cables()) + " cables)");
  }
  return py::cast(CalibratedSpatialRobot(nominal, r.result));
}

std::string SpatialReport(const SpatialRobot& nominal, py::handle result_arg, py::handle directory,
                          py::handle holdout_arg, const std::function<std::string(const std::vector<std::string>&)>& draw) {
  const PySpatialIdentifyResult& r = AsObject<PySpatialIdentifyResult>(result_arg, "result", "SpatialIdentifyResult");
  if (r.nominal.name != nominal.name || r.nominal.num_cables() != nominal.num_cables()) {
    Bad("result", "identified for " + r.nominal.name + ", not " + nominal.name);
  }
  const std::string dir = AsPath(directory, "directory");
  OutputFolder folder("directory", dir, SpatialReportFileNames());
  ReportSources sources{CallText("report"), "the measurements given to cablecal.identify", ""};
  std::optional<SpatialValidationResult> validation;
  if (!holdout_arg.is_none()) {
    const PySpatialMeasurements& holdout =
        AsObject<PySpatialMeasurements>(holdout_arg, "holdout", "SpatialMeasurements");
    sources.holdout = "the held-out SpatialMeasurements given to cablecal.report";
    SpatialRobot calibrated = CalibratedSpatialRobot(nominal, r.result);
    calibrated.source = "identified from " + sources.measurements;
    py::gil_scoped_release release;
    validation = ValidateSpatial(calibrated, nominal, holdout.readings, "holdout");
  }
  const std::string figure_error =
      StageSpatialReport(folder, nominal, r.options, r.result,
                         SpatialIdentifyResultYaml(nominal, r.options, r.result, CallText("identify")),
                         validation ? &*validation : nullptr, sources, draw);
  folder.Commit();
  if (!figure_error.empty()) throw FigureFailure(ReportWithoutFiguresMessage(dir, figure_error));
  return dir + "/report.md";
}

py::object SpatialValidatePy(const SpatialRobot& robot, py::handle measurements_arg, py::handle nominal_arg,
                             bool skip_infeasible) {
  const PySpatialMeasurements& measurements =
      AsObject<PySpatialMeasurements>(measurements_arg, "measurements", "SpatialMeasurements");
  std::optional<SpatialRobot> nominal;
  if (!nominal_arg.is_none()) nominal = AsObject<SpatialRobot>(nominal_arg, "nominal", "SpatialRobot");
  SpatialValidationResult r;
  {
    py::gil_scoped_release release;
    r = ValidateSpatial(robot, nominal, measurements.readings, "measurements", skip_infeasible);
  }
  return py::cast(std::move(r));
}

// Long (~100 lines) for a reason: a binding table, each property in the order help() shows it.
void BindSpatialIdentify(py::module_& m) {
  py::class_<PySpatialIdentifyResult>(m, "SpatialIdentifyResult",
                                      "A spatial robot's identification (cablecal identify on a kind: spatial file).")
      .def_property_readonly("status", [](const PySpatialIdentifyResult& r) { return std::string(ToString(r.result.status)); })
      .def_property_readonly("iterations", [](const PySpatialIdentifyResult& r) { return r.result.iterations; })
      .def_property_readonly("final_cost", [](const PySpatialIdentifyResult& r) { return r.result.final_cost; })
      .def_property_readonly("names", [](const PySpatialIdentifyResult& r) { return r.result.names; },
                             "a1x a1y a1z .. amz l10 .. lm0, then b1x .. bmz with identify='anchors', then sw10 .. swm0 "
                             "and yaw0 when read, then mass comx comy comz when the statics are modelled")
      .def_property_readonly("values", [](const PySpatialIdentifyResult& r) { return Vector(r.result.geometry); },
                             "by names: m, rad, kg")
      .def_property_readonly("sigma", [](const PySpatialIdentifyResult& r) { return Vector(r.result.sigma); },
                             "by names; 0 where held")
      .def_property_readonly("covariance", [](const PySpatialIdentifyResult& r) { return Array(r.result.covariance); })
      .def_property_readonly("held", [](const PySpatialIdentifyResult& r) { return r.result.held; },
                             "the exit (and anchor) coordinates the gauge held at their nominal values")
      .def_property_readonly("null_directions",
                             [](const PySpatialIdentifyResult& r) { return Directions(r.result.null_directions); },
                             "what no reading sees: description, relative_singular_value, vector (by names)")
      .def_property_readonly("weak_directions",
                             [](const PySpatialIdentifyResult& r) { return Directions(r.result.weak_directions, true); },
                             "seen weakly: as null_directions, and nearly_rigid (within 5 % of a rigid motion of the "
                             "frame: the default gauge holds it)")
      .def_property_readonly("pose_ids", [](const PySpatialIdentifyResult& r) { return r.result.pose_ids; })
      .def_property_readonly("poses", [](const PySpatialIdentifyResult& r) { return Array(Poses(r.result.poses)); },
                             "(n, 6): x, y, z, roll, pitch, yaw identified")
      .def_property_readonly("tensions", [](const PySpatialIdentifyResult& r) -> py::object {
        if (r.result.tensions_N.empty()) return py::none();
        Eigen::MatrixXd t(r.result.tensions_N.size(), r.nominal.num_cables());
        for (std::size_t j = 0; j < r.result.tensions_N.size(); ++j) t.row(j) = r.result.tensions_N[j].transpose();
        return Array(t);
      }, "(n, m), N, when the statics are modelled; None otherwise")
      .def_property_readonly("worst_reading", [](const PySpatialIdentifyResult& r) {
        py::dict d;
        d["pose_id"] = r.result.worst_pose_id;
        d["sensor"] = r.result.worst_sensor;
        d["where"] = r.result.worst_where;
        d["sigmas"] = r.result.worst_residual;
        return d;
      }, "the largest whitened residual, its pose and sensor")
      .def_property_readonly("warnings", [](const PySpatialIdentifyResult& r) { return r.result.warnings; })
      .def_property_readonly("missing_sensors",
                             [](const PySpatialIdentifyResult& r) { return MissingSpatialSensors(r.nominal, r.result); })
      .def("to_yaml", [](const PySpatialIdentifyResult& r) {
        return SpatialIdentifyResultYaml(r.nominal, r.options, r.result, CallText("identify"));
      }, "The CLI's result.yaml (the command line reads python: cablecal.identify).")
      .def("to_json", [](const PySpatialIdentifyResult& r) {
        return SpatialIdentifyResultJson(r.nominal, r.options, r.result, CallText("identify"));
      }, "identify --json's line.");

  py::class_<SpatialValidationResult>(m, "SpatialValidation",
                                      "Each robot's predictions of held-out readings of a spatial robot (validate).")
      .def_property_readonly("pose_ids", [](const SpatialValidationResult& r) { return r.pose_ids; })
      .def_property_readonly("compared", [](const SpatialValidationResult& r) {
        std::vector<std::string> out;
        for (const SpatialSensor s : kSpatialSensors) {
          if (r.compared[static_cast<int>(s)]) out.push_back(ToString(s));
        }
        return out;
      })
      .def_property_readonly("robots", [](const SpatialValidationResult& r) {
        py::dict out;
        for (const SpatialRobotPrediction& p : r.robots) {
          py::dict e;
          e["robot"] = p.robot;
          e["poses"] = Array(Poses(p.q));
          for (const SpatialSensor s : kSpatialSensors) {
            const std::optional<ErrorSummary>& sum = p.summary[static_cast<int>(s)];
            if (!sum) continue;
            const std::vector<Eigen::VectorXd>& errors = p.errors[static_cast<int>(s)];
            Eigen::MatrixXd err(errors.size(), errors.empty() ? 0 : errors.front().size());
            for (std::size_t j = 0; j < errors.size(); ++j) err.row(j) = errors[j].transpose();
            py::dict d;
            d["errors"] = Array(err);
            d["rms"] = sum->rms;
            d["max_abs"] = sum->max_abs;
            e[ToString(s)] = d;
          }
          out[py::str(p.name)] = e;
        }
        return out;
      }, "'calibrated' (and 'nominal'): poses (n, 6) predicted, and per sensor compared its errors (n, k) = "
         "predicted - measured, rms and max_abs")
      .def_property_readonly("warnings", [](const SpatialValidationResult& r) { return r.warnings; })
      .def("to_csv", [](const SpatialValidationResult& r) { return SpatialValidationCsv(r, ""); })
      .def("to_yaml", [](const SpatialValidationResult& r) { return SpatialValidationSummaryYaml(r, CallText("validate")); });
}

}  // namespace cablecal::python
