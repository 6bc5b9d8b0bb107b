// The Python module `cablecal` (pybind11): the library's stages with the CLI's options as
// keyword arguments and the CLI's defaults, NumPy arrays in and out, the CLI's errors as
// exceptions (README, "Python"). It calls the same functions as the CLI (cli/commands.cc),
// so a result equals the CLI's file for the same inputs; tests/python/ checks that.
//
// This file is the module's body: its attributes, its exceptions and its sections in turn
// (bindings.h; one .cc each); converters.h converts the arguments, interrupt.h runs long calls.
#include <glog/logging.h>

#include "common/error.h"
#include "common/version.h"
#include "python/bindings.h"

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

  BindModel(m);
  BindSpatial(m);
  BindExperiment(m);
  BindDesign(m);
  BindSpatialIdentify(m);
  BindIdentify(m);
  BindSensors(m);
  BindMonteCarlo(m);

  m.def("loaded_blas", [] { return LoadedLibraryPath("libblas.so"); },
        "The BLAS this process uses: designs equal the CLI's bit for bit with the reference BLAS (README, \"Python\").");
}
