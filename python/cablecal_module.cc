// The Python module `cablecal` (pybind11): the library's stages with the CLI's options as
// keyword arguments and the CLI's defaults, NumPy arrays in and out, the CLI's errors as
// exceptions (README, "Python"). It calls the same functions as the CLI (cli/commands.cc),
// so a result equals the CLI's file for the same inputs; tests/python/ checks that.
//
// Arguments are converted here, not by pybind11's casters, so that a wrong type, shape or a
// NaN is a cablecal.InputError naming the argument (a ValueError), as a bad flag is for the CLI.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <glog/logging.h>
#include <yaml-cpp/yaml.h>

#include <omp.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/version.h"
#include "design/design.h"
#include "identify/calibration_report.h"
#include "identify/experiment.h"
#include "identify/identify.h"
#include "identify/validate.h"
#include "model/robot.h"
#include "model/statics.h"
#include "montecarlo/montecarlo.h"
#include "sensors/sensors.h"
#include "workspace/workspace.h"

namespace py = pybind11;

namespace cablecal::python {
namespace {

// ---- Arguments ------------------------------------------------------------------------------

[[noreturn]] void Bad(const std::string& argument, const std::string& problem) { throw InputError(argument, "", problem); }

std::string TypeName(py::handle h) { return py::str(py::type::of(h).attr("__name__")); }

py::object Obj(py::handle h) { return py::reinterpret_borrow<py::object>(h); }

bool IsNumpy(py::handle h, const char* type) { return py::isinstance(h, py::module_::import("numpy").attr(type)); }
bool IsInteger(py::handle h) {
  // bool is an int in Python; True for a pose count is a slip, not a 1.
  return !py::isinstance<py::bool_>(h) && !IsNumpy(h, "bool_") && (py::isinstance<py::int_>(h) || IsNumpy(h, "integer"));
}

long long AsInteger(py::handle h, const std::string& name, long long lo, long long hi) {
  if (!IsInteger(h)) Bad(name, "expected an integer, got " + TypeName(h));
  long long v = 0;
  try {
    v = py::int_(Obj(h)).cast<long long>();
  } catch (const py::cast_error&) {
    Bad(name, "integer out of range");
  }
  if (v < lo || v > hi) Bad(name, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

std::uint64_t AsSeed(py::handle h) {
  if (!IsInteger(h)) Bad("seed", "expected an integer, got " + TypeName(h));
  // As the CLI's --seed: a seed out of range is refused, never wrapped or saturated to another.
  try {
    return py::int_(Obj(h)).cast<std::uint64_t>();
  } catch (const py::cast_error&) {
    Bad("seed", "must be a whole number from 0 to 18446744073709551615 (got " + py::str(Obj(h)).cast<std::string>() + ")");
  }
}

double AsNumber(py::handle h, const std::string& name) {
  if (!IsInteger(h) && !py::isinstance<py::float_>(h) && !IsNumpy(h, "floating")) {
    Bad(name, "expected a number, got " + TypeName(h));
  }
  const double v = py::float_(Obj(h)).cast<double>();
  if (!std::isfinite(v)) Bad(name, "not a finite number");
  return v;
}

// A path: a str or any os.PathLike (pathlib.Path).
std::string AsPath(py::handle h, const std::string& name) {
  if (!py::isinstance<py::str>(h) && py::hasattr(h, "__fspath__")) {
    py::object p = py::module_::import("os").attr("fspath")(h);
    if (py::isinstance<py::str>(p)) return p.cast<std::string>();
  }
  if (!py::isinstance<py::str>(h)) Bad(name, "expected a path (str or pathlib.Path), got " + TypeName(h));
  return h.cast<std::string>();
}

// One of the module's own objects (a Robot, a Plan, ...), or InputError naming the argument.
template <typename T>
const T& AsObject(py::handle h, const std::string& name, const char* type) {
  if (!py::isinstance<T>(h)) Bad(name, std::string("expected a cablecal.") + type + ", got " + TypeName(h));
  return h.cast<const T&>();
}

std::string AsText(py::handle h, const std::string& name) {
  if (!py::isinstance<py::str>(h)) Bad(name, "expected a string, got " + TypeName(h));
  return h.cast<std::string>();
}

// "on" or "off" (True or False too), as the CLI's on|off options.
bool OnOff(py::handle h, const std::string& name) {
  if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
  const std::string text = AsText(h, name);
  if (text != "on" && text != "off") Bad(name, "expected \"on\" or \"off\", got '" + text + "'");
  return text == "on";
}

// A 2-D float array of `rows` (-1: any) x `cols`, finite. A 1-D array is taken as one column
// when cols == 1.
Eigen::MatrixXd AsMatrix(py::handle h, const std::string& name, long rows, long cols) {
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(h);
  } catch (const py::error_already_set&) {
  }
  if (!a) Bad(name, "expected an array of numbers, got " + TypeName(h));
  if (a.ndim() == 1 && cols == 1) a = a.reshape({a.shape(0), py::ssize_t{1}});
  if (a.ndim() != 2) Bad(name, "expected a 2-D array, got " + std::to_string(a.ndim()) + " dimensions");
  if ((rows >= 0 && a.shape(0) != rows) || a.shape(1) != cols) {
    Bad(name, "expected shape (" + (rows >= 0 ? std::to_string(rows) : std::string("n")) + ", " + std::to_string(cols) +
                  "), got (" + std::to_string(a.shape(0)) + ", " + std::to_string(a.shape(1)) + ")");
  }
  Eigen::MatrixXd m(a.shape(0), a.shape(1));
  for (py::ssize_t r = 0; r < a.shape(0); ++r) {
    for (py::ssize_t c = 0; c < a.shape(1); ++c) {
      const double v = a.at(r, c);
      if (!std::isfinite(v)) Bad(name, "row " + std::to_string(r) + ", column " + std::to_string(c) + " is not finite");
      m(r, c) = v;
    }
  }
  return m;
}

// ---- Long calls: the GIL released, Ctrl-C honoured -------------------------------------------

// Runs f on a worker thread while this (Python's) thread waits without the GIL, checking for
// signals every 50 ms and calling `tick` (with the GIL, on this thread: Python callbacks run
// here, never on the worker). Ctrl-C, or an exception from `tick`, sets `stop` (which f's
// solver polls) and, once f has returned, is raised: no partial result comes back.
template <typename F>
auto Interruptible(std::atomic<bool>& stop, F&& f, const std::function<void()>& tick = {}) -> decltype(f()) {
  using Result = decltype(f());
  std::optional<Result> result;
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false;
  std::thread worker([&] {
    try {
      result.emplace(f());
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex);
    done = true;
    cv.notify_all();
  });
  std::optional<py::error_already_set> interrupt;
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(mutex);
      if (cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) break;
    }
    if (interrupt) continue;
    if (PyErr_CheckSignals() != 0) {
      interrupt.emplace();  // takes the pending KeyboardInterrupt
      stop = true;
      continue;
    }
    if (tick) {
      try {
        tick();
      } catch (py::error_already_set& e) {
        interrupt.emplace(std::move(e));
        stop = true;
      }
    }
  }
  worker.join();
  if (interrupt) throw std::move(*interrupt);
  if (error) std::rethrow_exception(error);
  return std::move(*result);
}

// ---- Values to Python ---------------------------------------------------------------------------

py::object ScalarFromYaml(const std::string& s) {
  if (s == "true") return py::bool_(true);
  if (s == "false") return py::bool_(false);
  try {
    std::size_t used = 0;
    const long long i = std::stoll(s, &used);
    if (used == s.size()) return py::int_(i);
  } catch (const std::exception&) {
  }
  try {
    std::size_t used = 0;
    const double d = std::stod(s, &used);
    if (used == s.size()) return py::float_(d);
  } catch (const std::exception&) {
  }
  return py::str(s);
}

py::object FromYaml(const YAML::Node& n) {
  if (n.IsMap()) {
    py::dict d;
    for (const auto& kv : n) d[py::str(kv.first.as<std::string>())] = FromYaml(kv.second);
    return d;
  }
  if (n.IsSequence()) {
    py::list l;
    for (const auto& e : n) l.append(FromYaml(e));
    return l;
  }
  if (n.IsNull()) return py::none();
  return ScalarFromYaml(n.Scalar());
}

// A dict in the robot file's schema to YAML text, for the file's own loader and its checks.
void ToYaml(YAML::Emitter& out, py::handle h, const std::string& where) {
  if (py::isinstance<py::dict>(h)) {
    out << YAML::BeginMap;
    for (const auto& kv : h.cast<py::dict>()) {
      if (!py::isinstance<py::str>(kv.first)) Bad(where, "keys must be strings, got " + TypeName(kv.first));
      const std::string key = kv.first.cast<std::string>();
      out << YAML::Key << key << YAML::Value;
      ToYaml(out, kv.second, where.empty() ? key : where + "." + key);
    }
    out << YAML::EndMap;
  } else if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h) || py::isinstance<py::array>(h)) {
    out << YAML::Flow << YAML::BeginSeq;
    int k = 0;
    for (const auto& e : h) ToYaml(out, e, where + "[" + std::to_string(k++) + "]");
    out << YAML::EndSeq;
  } else if (py::isinstance<py::bool_>(h) || IsNumpy(h, "bool_")) {
    out << (py::bool_(Obj(h)).cast<bool>() ? "true" : "false");
  } else if (IsInteger(h)) {
    out << py::str(py::int_(Obj(h))).cast<std::string>();
  } else if (py::isinstance<py::float_>(h) || IsNumpy(h, "floating")) {
    // repr gives the shortest text that reads back as the same double; nan and inf reach the
    // loader as text it refuses by name.
    out << py::repr(py::float_(h.cast<double>())).cast<std::string>();
  } else if (py::isinstance<py::str>(h)) {
    out << YAML::DoubleQuoted << h.cast<std::string>();
  } else {
    Bad("robot dict: " + (where.empty() ? std::string("robot") : where), "unsupported value of type " + TypeName(h));
  }
}

py::array_t<double> Array(const Eigen::MatrixXd& m) {
  py::array_t<double> a({m.rows(), m.cols()});
  auto w = a.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) w(r, c) = m(r, c);
  }
  return a;
}
py::array_t<double> Vector(const Eigen::VectorXd& v) {
  py::array_t<double> a(v.size());
  auto w = a.mutable_unchecked<1>();
  for (Eigen::Index k = 0; k < v.size(); ++k) w(k) = v(k);
  return a;
}

// ---- Python-side types --------------------------------------------------------------------------

struct PyPlan {
  std::vector<PlanPose> poses;
  int num_cables = 0;
};
struct PyDesign {
  DesignResult result;
  DesignOptions options;  // as run, without the interrupt flag
};
struct PyMeasurements {
  std::vector<Measurement> readings;
  int num_cables = 0;
};
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

Eigen::MatrixXd PlanColumn(const PyPlan& p, Eigen::VectorXd PlanPose::*member) {
  Eigen::MatrixXd m(p.poses.size(), p.num_cables);
  for (std::size_t j = 0; j < p.poses.size(); ++j) {
    const Eigen::VectorXd& v = p.poses[j].*member;
    for (int i = 0; i < p.num_cables; ++i) m(j, i) = i < v.size() ? v(i) : std::nan("");
  }
  return m;
}

std::string CallText(const std::string& function) { return "python: cablecal." + function; }

py::dict CriteriaDict(const CriteriaValues& v) {
  py::dict d;
  d["condition_number"] = v.condition_number;
  d["d_log_det_information"] = v.d_log_det_information;
  d["a_trace_covariance_m2"] = v.a_trace_covariance_m2;
  d["e_min_eigenvalue"] = v.e_min_eigenvalue;
  return d;
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
    m.has_laser = !z.is_none();
    m.has_inclinometer = !theta.is_none();
    if (m.has_laser) m.z_m = z_m(j, 0);
    if (m.has_inclinometer) m.theta_rad = theta_rad(j, 0);
    out.readings.push_back(m);
  }
  return out;
}

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

// Draws a report's figures with this interpreter (it has NumPy; matplotlib is its own to have):
// "" or why not, as the CLI's runner says it.
std::string DrawReportWithPython(const std::vector<std::string>& arguments) {
  const std::string script = PlotScriptsDir() + "/plot_report.py";
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
}  // namespace cablecal::python

using namespace cablecal;          // NOLINT: the module's body names the library throughout
using namespace cablecal::python;  // NOLINT

PYBIND11_MODULE(cablecal, m) {
  m.doc() = "cablecal: experiment design, identification and Monte Carlo for planar cable-driven parallel robots";
  m.attr("__version__") = Version();
  m.attr("commit") = GitCommit();
  // Ceres' log lines (glog) would land on the notebook's stderr; results and errors say what
  // matters. cablecal.set_solver_logging(True) shows them.
  FLAGS_minloglevel = google::GLOG_FATAL;
  m.def("set_solver_logging", [](bool on) { FLAGS_minloglevel = on ? google::GLOG_INFO : google::GLOG_FATAL; },
        py::arg("on"), "Show (True) or hide (False, the default) Ceres' log lines on stderr.");

  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<SolverFailure>(m, "SolverError", PyExc_RuntimeError);
  py::register_exception<FigureFailure>(m, "FigureError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted&) {
      PyErr_SetString(PyExc_KeyboardInterrupt, "interrupted");
    }
  });

  // ---- Robot
  py::class_<Robot>(m, "Robot", "A robot file's content (README, \"Robot file\").")
      .def_static("load", [](py::handle path) { return LoadRobotFile(AsPath(path, "path")); }, py::arg("path"),
                  "Loads and validates a robot YAML file.")
      .def_static(
          "builtin",
          [](py::handle name) {
            const std::string n = AsText(name, "name");
            if (n != BuiltinRobot().name) Bad("name", "no built-in robot '" + n + "' (there is '" + BuiltinRobot().name + "')");
            return BuiltinRobot();
          },
          py::arg("name") = "wang2022", "The built-in robot (wang2022).")
      .def_static(
          "from_dict",
          [](py::handle d) {
            if (!py::isinstance<py::dict>(d)) Bad("robot", "expected a dict in the robot file's schema, got " + TypeName(d));
            YAML::Emitter out;
            ToYaml(out, d, "");
            try {
              return LoadRobotFromString(out.c_str(), "robot dict");
            } catch (const InputError& e) {
              // "robot dict:30: gravty: ..." names a line of the YAML made here, not of anything
              // the user wrote: keep the key.
              std::string message = e.what();
              const std::size_t colon = message.find(':', std::string("robot dict:").size());
              if (message.rfind("robot dict:", 0) == 0 && colon != std::string::npos &&
                  message.find_first_not_of("0123456789", 11) == colon) {
                message = "robot dict:" + message.substr(colon + 1);
              }
              throw InputError("", "", message);
            }
          },
          py::arg("d"), "A robot from a dict in the robot file's schema (the file's checks apply).")
      .def("to_dict", [](const Robot& r) { return FromYaml(YAML::Load(RobotToYaml(r))); })
      .def("to_yaml", [](const Robot& r) { return RobotToYaml(r); })
      .def_property_readonly("name", [](const Robot& r) { return r.name; })
      .def_property_readonly("num_cables", &Robot::num_cables)
      .def_property_readonly("geometry", [](const Robot& r) { return Vector(GeometryOf(r)); },
                             "a1x a1z ... amx amz l10 ... lm0 (m)")
      .def_property_readonly("geometry_names", [](const Robot& r) { return GeometryNames(r.num_cables()); })
      .def("__repr__", [](const Robot& r) {
        return "<cablecal.Robot '" + r.name + "', " + std::to_string(r.num_cables()) + " cables>";
      });

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
        if (p.readings.empty() || !p.readings.front().has_laser) return py::none();
        Eigen::VectorXd v(p.readings.size());
        for (std::size_t j = 0; j < p.readings.size(); ++j) v(j) = p.readings[j].z_m;
        return Vector(v);
      }, "(n,) laser heights, m; None without a laser")
      .def_property_readonly("theta", [](const PyMeasurements& p) -> py::object {
        if (p.readings.empty() || !p.readings.front().has_inclinometer) return py::none();
        Eigen::VectorXd v(p.readings.size());
        for (std::size_t j = 0; j < p.readings.size(); ++j) v(j) = p.readings[j].theta_rad;
        return Vector(v);
      }, "(n,) inclinometer angles, rad; None without an inclinometer")
      .def_property_readonly("pose_ids", [](const PyMeasurements& p) {
        std::vector<int> ids;
        for (const Measurement& r : p.readings) ids.push_back(r.pose_id);
        return ids;
      })
      .def("to_csv", [](const PyMeasurements& p) { return MeasurementsCsv(p.readings, ""); })
      .def("__len__", [](const PyMeasurements& p) { return p.readings.size(); });

  // ---- workspace
  m.def(
      "workspace",
      [](py::handle robot_arg, py::handle step) {
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const double step_m = AsNumber(step, "step");
        if (!(step_m > 0.0)) Bad("step", "must be positive (m)");
        WorkspaceGrid grid;
        {
          py::gil_scoped_release release;
          grid = ComputeWorkspaceGrid(robot, step_m);
        }
        const int mc = robot.num_cables();
        const long n = static_cast<long>(grid.points.size());
        Eigen::MatrixXd xzt(n, 3), t(n, mc);
        py::array_t<bool> feasible(n);
        py::list reasons;
        auto f = feasible.mutable_unchecked<1>();
        for (long k = 0; k < n; ++k) {
          const WorkspacePoint& p = grid.points[k];
          const bool has = p.evaluation.has_equilibrium;
          xzt(k, 0) = p.x_m;
          xzt(k, 1) = p.z_m;
          xzt(k, 2) = has ? p.evaluation.equilibrium.q(2) : std::nan("");
          for (int i = 0; i < mc; ++i) t(k, i) = has ? p.evaluation.equilibrium.tensions_N(i) : std::nan("");
          f(k) = p.evaluation.feasible();
          reasons.append(ToString(p.evaluation.feasibility));
        }
        py::dict d;
        d["x"] = Vector(xzt.col(0));
        d["z"] = Vector(xzt.col(1));
        d["theta"] = Vector(xzt.col(2));
        d["tensions"] = Array(t);
        d["feasible"] = feasible;
        d["reason"] = reasons;
        d["area_m2"] = grid.feasible_area_m2();
        d["csv"] = WorkspaceCsv(robot, grid, "");
        return d;
      },
      py::arg("robot"), py::arg("step") = 0.05,
      "The feasible workspace on a grid: x, z, theta, tensions (NaN without equilibrium), feasible, reason, "
      "area_m2, and csv (the CLI's file).");

  // ---- sample
  m.def(
      "sample",
      [](py::handle robot_arg, py::handle n, py::handle seed) {
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const int count = static_cast<int>(AsInteger(n, "n", 1, kMaxPlanPoses));
        const std::uint64_t s = AsSeed(seed);
        py::gil_scoped_release release;
        return PyPlan{SampleFeasiblePoses(robot, count, s), robot.num_cables()};
      },
      py::arg("robot"), py::arg("n"), py::arg("seed") = 1, "n uniform random feasible poses (cablecal sample).");

  // ---- design
  py::class_<PyDesign>(m, "DesignResult")
      .def_property_readonly("plan", [](const PyDesign& d) { return PyPlan{d.result.poses, d.result.num_cables}; })
      .def_property_readonly("criteria", [](const PyDesign& d) { return CriteriaDict(d.result.criteria); })
      .def_property_readonly("random_median", [](const PyDesign& d) { return CriteriaDict(d.result.random_median); })
      .def_property_readonly("comparison", [](const PyDesign& d) -> py::object {
        if (d.options.random_sets == 0) return py::none();
        return py::str(ImprovementText(Improvement(d.options.criterion, d.result.criteria, d.result.random_median),
                                       d.options.random_sets));
      }, "\"3.2 x better than the median of 100 random sets\" (or worse) on the criterion; None without random sets")
      .def_property_readonly("best_start", [](const PyDesign& d) { return d.result.best_start; })
      .def_property_readonly("converged_starts", [](const PyDesign& d) { return d.result.converged_starts; })
      .def_property_readonly("wall_time_s", [](const PyDesign& d) { return d.result.wall_time_s; })
      .def_property_readonly("starts", [](const PyDesign& d) {
        py::list l;
        for (const StartReport& s : d.result.starts) {
          py::dict e;
          e["start"] = s.start;
          e["ipopt_status"] = s.ipopt_status;
          e["iterations"] = s.iterations;
          e["converged"] = s.converged;
          e["verified"] = s.verified;
          e["verification_failure"] = s.verification_failure;
          e["objective"] = s.objective;
          l.append(e);
        }
        return l;
      }, "Per Ipopt start: status, iterations, converged, verified, objective.")
      .def("to_yaml", [](const PyDesign& d) { return DesignSummaryYaml(d.result, d.options, CallText("design")); },
           "The CLI's summary.yaml.");
  m.def(
      "design",
      [](py::handle robot_arg, py::handle n, py::handle criterion, py::handle starts, py::handle seed,
         py::handle min_spacing, py::handle random_sets, py::handle geometry_sigma, py::handle robust_sigmas,
         py::handle prior) {
        Robot robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        DesignOptions o;
        if (!prior.is_none()) {
          // The next round of a calibration, planned around the estimate (design --prior).
          DesignPrior p = LoadDesignPrior(robot, AsPath(prior, "prior"));
          robot = p.robot;
          o.prior_information = p.information;
        }
        o.poses = static_cast<int>(AsInteger(n, "n", 1, kMaxPlanPoses));
        o.criterion = ParseCriterion(AsText(criterion, "criterion"));
        o.starts = static_cast<int>(AsInteger(starts, "starts", 1, 1000));
        o.seed = AsSeed(seed);
        o.min_spacing_m = AsNumber(min_spacing, "min_spacing");
        o.random_sets = static_cast<int>(AsInteger(random_sets, "random_sets", 0, 100000));
        o.geometry_sigma_m = AsNumber(geometry_sigma, "geometry_sigma");
        o.robust_sigmas = AsNumber(robust_sigmas, "robust_sigmas");
        // In process: a Python process may run threads of its own, and a fork copies them
        // half-way; the plans are bit for bit the same (tests/design).
        o.solve_in_child_processes = false;
        std::atomic<bool> stop{false};
        o.interrupted = &stop;
        PyDesign d{Interruptible(stop, [&] { return DesignPoses(robot, o); }), o};
        d.options.interrupted = nullptr;
        if (o.random_sets > 0 && !(Improvement(o.criterion, d.result.criteria, d.result.random_median) > 1.0)) {
          // The CLI's warning: a result, but not a good plan.
          const int warned =
              PyErr_WarnEx(PyExc_UserWarning, NoBetterThanRandomWarning(o, "geometry_sigma").c_str(), 1);
          if (warned < 0) throw py::error_already_set();  // warnings filtered into errors
        }
        return d;
      },
      py::arg("robot"), py::arg("n"), py::arg("criterion") = "a", py::arg("starts") = 8, py::arg("seed") = 1,
      py::arg("min_spacing") = 0.0, py::arg("random_sets") = 100, py::arg("geometry_sigma") = 0.01,
      py::arg("robust_sigmas") = 3.0, py::arg("prior") = py::none(),
      "Optimal measurement poses (cablecal design); SolverError if no start converges. prior: the path of an earlier "
      "identification's result.yaml (design --prior).");

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
         py::handle skip_infeasible) {
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
        return std::move(*run);
      },
      py::arg("robot"), py::arg("plan"), py::arg("truth") = py::none(), py::arg("geometry_sigma") = py::none(),
      py::arg("sensors") = "both", py::arg("encoder_noise") = true, py::arg("seed") = 1,
      py::arg("systematic_errors") = false, py::arg("skip_infeasible") = false,
      "The sensors' readings of a plan on a true robot (cablecal simulate); systematic_errors=True also adds the "
      "robot's systematic laser and inclinometer errors (simulate --systematic-errors); skip_infeasible=True skips "
      "the poses the true robot cannot hold (Experiment.skipped) instead of raising InputError at the first "
      "(simulate --skip-infeasible).");

  // ---- identify
  py::class_<IdentifyResult>(m, "IdentifyResult")
      .def_property_readonly("status", [](const IdentifyResult& r) { return std::string(ToString(r.status)); })
      .def_readonly("message", &IdentifyResult::message)
      .def_readonly("iterations", &IdentifyResult::iterations)
      .def_readonly("final_cost", &IdentifyResult::final_cost)
      .def_readonly("rms_encoder_m", &IdentifyResult::rms_encoder_m)
      .def_readonly("rms_laser_m", &IdentifyResult::rms_laser_m)
      .def_readonly("rms_inclinometer_rad", &IdentifyResult::rms_inclinometer_rad)
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
          d["laser_sigmas"] = f.laser_sigmas ? py::cast(*f.laser_sigmas) : py::none();
          d["inclinometer_sigmas"] = f.inclinometer_sigmas ? py::cast(*f.inclinometer_sigmas) : py::none();
          d["encoder_weights"] = Vector(f.encoder_weights);
          d["laser_weight"] = f.laser_weight;
          d["inclinometer_weight"] = f.inclinometer_weight;
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
         py::handle max_iterations, py::handle loss, py::handle geometry_prior, py::handle equilibrium) {
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        const PyMeasurements& measurements = AsObject<PyMeasurements>(measurements_arg, "measurements", "Measurements");
        if (measurements.num_cables != robot.num_cables()) Bad("measurements", "read for a robot with another number of cables");
        IdentifyOptions o;
        o.estimator = ParseEstimator(AsText(estimator, "estimator"));
        o.gauge = ParseGauge(AsText(gauge, "gauge"));
        o.max_iterations = static_cast<int>(AsInteger(max_iterations, "max_iterations", 1, kMaxIdentifyIterations));
        o.loss = ParseLoss(AsText(loss, "loss"));
        if (!geometry_prior.is_none()) o.geometry_prior_sigma_m = AsNumber(geometry_prior, "geometry_prior");  // 0 refused
        o.equilibrium = OnOff(equilibrium, "equilibrium");
        o.source = "measurements";
        // As the CLI: a robot with systematic sensor errors has them removed before the solve.
        const std::vector<Measurement> readings = CorrectedReadings(robot, measurements.readings, "measurements");
        IdentifyResult r;
        {
          py::gil_scoped_release release;
          r = Identify(robot, readings, o);
        }
        if (robot.sensors.systematic.any()) r.corrected_for = robot.sensors.systematic;
        RequireUsableResult(r, "measurements");
        for (const std::string& w : r.warnings) {
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        }
        return r;
      },
      py::arg("robot"), py::arg("measurements"), py::arg("estimator") = "ml", py::arg("gauge") = "a1x",
      py::arg("max_iterations") = 100, py::arg("loss") = "none", py::arg("geometry_prior") = py::none(),
      py::arg("equilibrium") = kDefaultEquilibrium ? "on" : "off",
      "Identifies exit points and initial lengths (cablecal identify); InputError when the data cannot "
      "calibrate this robot, SolverError when the solve does not converge. geometry_prior: the standard "
      "deviation (m) of the nominal geometry, a prior as identify --geometry-prior (None: none).");
  m.def("calibrated_robot", [](py::handle nominal_arg, py::handle result_arg) {
        const Robot& nominal = AsObject<Robot>(nominal_arg, "nominal", "Robot");
        const IdentifyResult& r = AsObject<IdentifyResult>(result_arg, "result", "IdentifyResult");
        RequireResultOfRobot("result", r.robot_name, static_cast<int>(r.geometry.size()) / 3, nominal);
        return WithGeometry(nominal, r.geometry);
      },
        py::arg("nominal"), py::arg("result"), "The nominal robot with the identified geometry.");
  m.def(
      "report",
      [](py::handle nominal_arg, py::handle result_arg, py::handle directory, py::handle holdout_arg) {
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
                        validation ? &*validation : nullptr, sources, DrawReportWithPython);
        folder.Commit();
        if (!figure_error.empty()) throw FigureFailure(ReportWithoutFiguresMessage(dir, figure_error));
        return dir + "/report.md";
      },
      py::arg("nominal"), py::arg("result"), py::arg("directory"), py::arg("holdout") = py::none(),
      "Writes the calibration report of `result` into `directory` as identify --report does (report.md, its figures "
      "and data files; the folder is created if new, its parent must exist) and returns report.md's path. holdout: "
      "held-out Measurements, validated with the calibrated and the nominal robot. The figures are drawn with this "
      "interpreter's matplotlib; if they cannot be, the rest is written and FigureError raised.");

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
      [](py::handle robot_arg, py::handle measurements_arg, py::handle nominal_arg, py::handle skip_infeasible) {
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        if (!py::isinstance<py::bool_>(skip_infeasible)) Bad("skip_infeasible", "expected True or False");
        const bool skip = skip_infeasible.cast<bool>();
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
        return r;
      },
      py::arg("robot"), py::arg("measurements"), py::arg("nominal") = py::none(), py::arg("skip_infeasible") = false,
      "Predicts every measured pose with `robot` (and `nominal`) and compares z and theta with the readings "
      "(cablecal validate); InputError when a robot cannot hold a pose's lengths, or with skip_infeasible=True "
      "such readings are left out and listed in Validation.skipped (validate --skip-infeasible).");

  // ---- sensors fit
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

  // ---- montecarlo
  py::class_<MonteCarloResult>(m, "MonteCarloResult")
      .def_readonly("wall_time_s", &MonteCarloResult::wall_time_s)
      .def("summary_csv", [](const MonteCarloResult& r) { return SummaryCsv(r); }, "The CLI's summary.csv.")
      .def("failures_csv", [](const MonteCarloResult& r) { return FailuresCsv(r); })
      .def_property_readonly("summary", [](const MonteCarloResult& r) {
        py::list rows;
        for (const MonteCarloCell& cell : r.cells) {
          for (const std::string& parameter : SummaryParameters(r.num_cables)) {
            const ErrorStats s = Summarise(cell, r.num_cables, parameter);
            py::dict d;
            d["n"] = cell.n;
            d["design"] = ToString(cell.design);
            d["parameter"] = parameter;
            d["mean"] = s.mean;
            d["std"] = s.std;
            d["rms"] = s.rms;
            d["max_abs"] = s.max_abs;
            d["share_within_5mm"] = s.share_within_5mm;
            d["failures"] = cell.failures();
            rows.append(d);
          }
        }
        return rows;
      }, "One dict per (n, design, parameter), as summary.csv's rows (errors in m).");
  m.def(
      "montecarlo",
      [](py::handle robot_arg, py::handle poses, py::handle trials, py::handle designs, py::handle estimator,
         py::handle gauge, py::handle sensors, py::handle geometry_sigma, py::handle seed, py::handle design_starts,
         py::handle threads, py::handle progress, py::handle loss, py::handle outliers, py::handle geometry_prior,
         py::handle equilibrium, py::handle com_error) {
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
        MonteCarloOptions o;
        if (py::isinstance<py::str>(poses)) {
          o.pose_counts = ParsePoseCounts(poses.cast<std::string>());
        } else if (IsInteger(poses)) {
          o.pose_counts = {static_cast<int>(AsInteger(poses, "poses", 1, kMaxPlanPoses))};
        } else {
          if (!py::isinstance<py::sequence>(poses)) Bad("poses", "expected \"first:last[:step]\", an integer or a list of them");
          for (const auto& e : poses) o.pose_counts.push_back(static_cast<int>(AsInteger(e, "poses", 1, kMaxPlanPoses)));
        }
        o.trials = static_cast<int>(AsInteger(trials, "trials", 1, 100000000));
        o.designs = ParseDesigns(AsText(designs, "designs"));
        o.estimator = ParseEstimator(AsText(estimator, "estimator"));
        o.gauge = ParseGauge(AsText(gauge, "gauge"));
        o.sensors = ParseNoisySensors(AsText(sensors, "sensors"));
        o.geometry_sigma_m = AsNumber(geometry_sigma, "geometry_sigma");
        o.seed = AsSeed(seed);
        o.design_starts = static_cast<int>(AsInteger(design_starts, "design_starts", 1, 1000));
        o.loss = ParseLoss(AsText(loss, "loss"));
        o.outliers = ParseOutliers(AsText(outliers, "outliers"));
        if (!py::isinstance<py::bool_>(geometry_prior)) Bad("geometry_prior", "expected True or False");
        o.geometry_prior = geometry_prior.cast<bool>();
        o.equilibrium = OnOff(equilibrium, "equilibrium");
        o.com_error_m = AsNumber(com_error, "com_error");
        o.design_in_child_processes = false;  // as design() above
        ValidateOptions(o, &robot);
        if (!progress.is_none() && !PyCallable_Check(progress.ptr())) Bad("progress", "expected a callable or None");
        std::atomic<bool> stop{false};
        o.interrupted = &stop;
        // The study reports (done, total) from one of its threads; Python hears it from here.
        std::atomic<long> done{0}, total{0};
        o.progress = [&](long d, long t) {
          done = d;
          total = t;
        };
        long reported = -1;
        const auto report = [&] {
          if (progress.is_none() || total == 0 || done == reported) return;
          reported = done;
          progress(reported, total.load());
        };
        // OpenMP threads of the worker that runs the study (its own setting, as --threads);
        // the results do not depend on it.
        const int thread_count = threads.is_none() ? 0 : static_cast<int>(AsInteger(threads, "threads", 1, 1024));
        MonteCarloResult r = Interruptible(
            stop,
            [&] {
              if (thread_count > 0) omp_set_num_threads(thread_count);
              return RunMonteCarlo(robot, o);
            },
            report);
        report();  // the last count: (total, total)
        return r;
      },
      py::arg("robot"), py::arg("poses"), py::arg("trials"), py::arg("designs") = "random,optimized",
      py::arg("estimator") = "ml", py::arg("gauge") = "a1x", py::arg("sensors") = "both",
      py::arg("geometry_sigma") = 0.01, py::arg("seed") = 1, py::arg("design_starts") = 2,
      py::arg("threads") = py::none(), py::arg("progress") = py::none(), py::arg("loss") = "none",
      py::arg("outliers") = "0", py::arg("geometry_prior") = false,
      py::arg("equilibrium") = kDefaultEquilibrium ? "on" : "off", py::arg("com_error") = 0.0,
      "The Monte Carlo study (cablecal montecarlo); Ctrl-C raises KeyboardInterrupt. progress(done, total), if "
      "given, is called now and then with the trials done. geometry_prior: identify every trial with "
      "geometry_sigma as a prior (montecarlo --geometry-prior).");

  m.def("loaded_blas", [] { return LoadedLibraryPath("libblas.so"); },
        "The BLAS this process uses: designs equal the CLI's bit for bit with the reference BLAS (README, \"Python\").");
}
