// Python values to the library's and back, for every section of the module. Arguments are
// converted here, not by pybind11's casters, so that a wrong type, shape or a NaN is a
// cablecal.InputError naming the argument (a ValueError), as a bad flag is for the CLI.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "common/error.h"

namespace py = pybind11;

namespace cablecal::python {

// ---- Arguments ------------------------------------------------------------------------------

[[noreturn]] void Bad(const std::string& argument, const std::string& problem);
std::string TypeName(py::handle h);
py::object Obj(py::handle h);

bool IsNumpy(py::handle h, const char* type);
bool IsInteger(py::handle h);

long long AsInteger(py::handle h, const std::string& name, long long lo, long long hi);
std::uint64_t AsSeed(py::handle h);
double AsNumber(py::handle h, const std::string& name);
// A path: a str or any os.PathLike (pathlib.Path).
std::string AsPath(py::handle h, const std::string& name);
std::string AsText(py::handle h, const std::string& name);
// "on" or "off" (True or False too), as the CLI's on|off options.
bool OnOff(py::handle h, const std::string& name);
// A 2-D float array of `rows` (-1: any) x `cols`, finite. A 1-D array is taken as one column
// when cols == 1.
Eigen::MatrixXd AsMatrix(py::handle h, const std::string& name, long rows, long cols);

// One of the module's own objects (a Robot, a Plan, ...), or InputError naming the argument.
template <typename T>
const T& AsObject(py::handle h, const std::string& name, const char* type) {
  if (!py::isinstance<T>(h)) Bad(name, std::string("expected a cablecal.") + type + ", got " + TypeName(h));
  return h.cast<const T&>();
}

// ---- Values to Python ---------------------------------------------------------------------------

py::object FromYaml(const YAML::Node& n);
// A dict in the robot file's schema to YAML text, for the file's own loader and its checks.
void ToYaml(YAML::Emitter& out, py::handle h, const std::string& where);

[[noreturn]] void RethrowWithoutDictLine(const InputError& e);
// Robot.from_dict / SpatialRobot.from_dict: the dict (the robot file's schema) loaded by `load`
// (LoadRobotFromString or LoadSpatialRobotFromString) as a file named "robot dict", with its
// checks; an error names the key, not a line of the YAML made here. BadArgument if not a dict.
template <typename Load>
auto RobotFromDict(py::handle d, Load load) {
  if (!py::isinstance<py::dict>(d)) Bad("robot", "expected a dict in the robot file's schema, got " + TypeName(d));
  YAML::Emitter out;
  ToYaml(out, d, "");
  try {
    return load(std::string(out.c_str()), std::string("robot dict"));
  } catch (const InputError& e) {
    RethrowWithoutDictLine(e);
  }
}

py::array_t<double> Array(const Eigen::MatrixXd& m);
py::array_t<double> Vector(const Eigen::VectorXd& v);

// The command line a file written from Python records as its provenance.
std::string CallText(const std::string& function);

}  // namespace cablecal::python
