// Binds the sensors' bench fit: cablecal.fit_sensors and the cablecal.SensorsFit it returns (the
// inclinometer's and the laser's error models, and the robot with them).

#include <string>
#include <utility>
#include <vector>

#include "common/format.h"
#include "model/robot.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "sensors/sensors.h"

namespace cablecal::python {
namespace {

struct PySensorsFit {
  SensorsFit fit;
  Robot robot;  // whose other sensor entries the block keeps
};

// A sensor's bench readings: a CSV path, or an (n, 2) array of (reference, reading) in SI units.
std::vector<BenchReading> BenchReadings(BenchSensor sensor, py::handle h, const std::string& name, char delimiter) {
  if (py::isinstance<py::str>(h) || py::hasattr(h, "__fspath__")) {
    std::vector<std::string> ignored;
    std::vector<BenchReading> readings = ReadBenchCsv(sensor, AsPath(h, name), delimiter,
                                                      [&](const std::vector<std::string>& names) { ignored = names; });
    if (!ignored.empty()) {
      if (PyErr_WarnEx(PyExc_UserWarning, (name + ": ignoring columns " + QuotedList(ignored)).c_str(), 1) < 0) {
        throw py::error_already_set();
      }
    }
    CheckReadingsAgainstTheirReference(sensor, readings);  // as the CLI's sensors fit
    return readings;
  }
  const Eigen::MatrixXd a = AsMatrix(h, name, -1, 2);
  std::vector<BenchReading> readings;
  for (Eigen::Index k = 0; k < a.rows(); ++k) {
    BenchReading r{a(k, 0), a(k, 1), name + ": row " + std::to_string(k)};
    CheckBenchReading(sensor, r);
    readings.push_back(std::move(r));
  }
  CheckReadingsAgainstTheirReference(sensor, readings);
  return readings;
}

py::dict BenchDict(const BenchSummary& b, const std::string& unit) {
  py::dict d;
  d["readings"] = b.readings;
  d["references"] = b.references;
  d["repeated_references"] = b.repeated_references;
  d[py::str("reference_min_" + unit)] = b.reference_min;
  d[py::str("reference_max_" + unit)] = b.reference_max;
  return d;
}

}  // namespace

void BindSensors(py::module_& m) {
  py::class_<PySensorsFit>(m, "SensorsFit", "Sensor error models fitted from bench readings (cablecal sensors fit).")
      .def_property_readonly("inclinometer", [](const PySensorsFit& p) -> py::object {
        if (!p.fit.inclinometer) return py::none();
        const InclinometerFit& f = *p.fit.inclinometer;
        py::dict d = BenchDict(f.bench, "rad");
        d["offset_rad"] = f.offset_rad;
        d["offset_se_rad"] = f.offset_se_rad;
        d["sec_coefficient_rad"] = f.sec_coefficient_rad;
        d["sec_coefficient_se_rad"] = f.sec_coefficient_se_rad;
        d["correlation"] = f.correlation;
        d["accuracy_rad"] = f.accuracy_rad;
        d["repeatability_rad"] = f.repeatability_rad;
        return d;
      }, "e = offset + k (sec theta - 1): coefficients and standard errors (se), 3-sigma ranges, rad; or None.")
      .def_property_readonly("laser", [](const PySensorsFit& p) -> py::object {
        if (!p.fit.laser) return py::none();
        const LaserFit& f = *p.fit.laser;
        py::dict d = BenchDict(f.bench, "m");
        d["offset_m"] = f.offset_m;
        d["offset_se_m"] = f.offset_se_m;
        d["accuracy_m"] = f.accuracy_m;
        d["repeatability_m"] = f.repeatability_m;
        return d;
      }, "e = offset: the offset and its standard error (se), 3-sigma ranges, m; or None.")
      .def_property_readonly("robot", [](const PySensorsFit& p) {
        Robot r = p.robot;
        r.sensors = FittedSensors(p.robot, p.fit);
        return r;
      }, "The robot given to fit_sensors with the fitted sensors.")
      .def("to_yaml", [](const PySensorsFit& p) { return SensorsFitYaml(p.robot, p.fit, CallText("fit_sensors")); },
           "The CLI's sensors.yaml: the sensors: block for a robot file (the command line reads python: "
           "cablecal.fit_sensors).");
  m.def(
      "fit_sensors",
      [](py::handle inclinometer, py::handle laser, py::handle robot_arg, py::handle delimiter) {
        const Robot robot = robot_arg.is_none() ? BuiltinRobot() : AsObject<Robot>(robot_arg, "robot", "Robot");
        const char d = ParseDelimiter(AsText(delimiter, "delimiter"));
        if (inclinometer.is_none() && laser.is_none()) {
          Bad("inclinometer", "give inclinometer, laser or both: the bench readings to fit");
        }
        PySensorsFit p{{}, robot};
        if (!inclinometer.is_none()) {
          const std::string source = py::isinstance<py::str>(inclinometer) || py::hasattr(inclinometer, "__fspath__")
                                         ? AsPath(inclinometer, "inclinometer")
                                         : "inclinometer";
          p.fit.inclinometer =
              FitInclinometer(BenchReadings(BenchSensor::kInclinometer, inclinometer, "inclinometer", d), source);
        }
        if (!laser.is_none()) {
          const std::string source =
              py::isinstance<py::str>(laser) || py::hasattr(laser, "__fspath__") ? AsPath(laser, "laser") : "laser";
          p.fit.laser = FitLaser(BenchReadings(BenchSensor::kLaser, laser, "laser", d), source);
        }
        FittedSensors(robot, p.fit);  // refuses what a robot file would refuse, as the CLI
        for (const std::string& w : FitWarnings(robot, p.fit)) {
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        }
        return p;
      },
      py::arg("inclinometer") = py::none(), py::arg("laser") = py::none(), py::arg("robot") = py::none(),
      py::arg("delimiter") = ",",
      "Fits the sensors' error models from bench readings (cablecal sensors fit): each a CSV path (reference_rad,"
      "reading_rad or reference_m,reading_m) or an (n, 2) array of (reference, reading) in rad or m. robot (default "
      "the built-in one) gives the entries that are not fitted.");
}

}  // namespace cablecal::python
