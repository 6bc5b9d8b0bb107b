// Python values to the library's and back (converters.h says why they are not pybind11's
// casters).
#include "python/converters.h"

#include <cmath>
#include <cstddef>
#include <exception>
#include <string>

#include "common/error.h"

namespace cablecal::python {

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

std::string AsPath(py::handle h, const std::string& name) {
  if (!py::isinstance<py::str>(h) && py::hasattr(h, "__fspath__")) {
    py::object p = py::module_::import("os").attr("fspath")(h);
    if (py::isinstance<py::str>(p)) return p.cast<std::string>();
  }
  if (!py::isinstance<py::str>(h)) Bad(name, "expected a path (str or pathlib.Path), got " + TypeName(h));
  return h.cast<std::string>();
}

std::string AsText(py::handle h, const std::string& name) {
  if (!py::isinstance<py::str>(h)) Bad(name, "expected a string, got " + TypeName(h));
  return h.cast<std::string>();
}

bool OnOff(py::handle h, const std::string& name) {
  if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
  const std::string text = AsText(h, name);
  if (text != "on" && text != "off") Bad(name, "expected \"on\" or \"off\", got '" + text + "'");
  return text == "on";
}

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

// ---- Values to Python ---------------------------------------------------------------------------

namespace {

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

}  // namespace

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

void RethrowWithoutDictLine(const InputError& e) {
  // "robot dict:30: gravty: ..." names a line of the YAML made from the dict, not of anything
  // the user wrote: keep the key.
  std::string message = e.what();
  const std::string prefix = "robot dict:";
  const std::size_t colon = message.find(':', prefix.size());
  if (message.rfind(prefix, 0) == 0 && colon != std::string::npos &&
      message.find_first_not_of("0123456789", prefix.size()) == colon) {
    message = prefix + message.substr(colon + 1);
  }
  throw InputError("", "", message);
}

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

std::string CallText(const std::string& function) { return "python: cablecal." + function; }

}  // namespace cablecal::python
