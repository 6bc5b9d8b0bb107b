// The module's sections, one .cc each, called in turn by the module's body (cablecal_module.cc),
// and the Python-side types more than one section hands around. A section binds its classes
// before its functions, and after the sections whose classes its signatures name: pybind11
// writes a type into a docstring by its Python name only if that type is bound by then.
#pragma once

// Every section sees the same type casters, those the module was written with: a type whose
// caster a section lacked would still compile and fail only when converted.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <vector>

#include "experiment/experiment.h"
#include "workspace/workspace.h"

namespace py = pybind11;

namespace cablecal::python {

// cablecal.Plan: a plan's poses for a robot of num_cables cables.
struct PyPlan {
  std::vector<PlanPose> poses;
  int num_cables = 0;
};
// cablecal.Measurements.
struct PyMeasurements {
  std::vector<Measurement> readings;
  int num_cables = 0;
};

void BindModel(py::module_& m);       // Robot, workspace
void BindExperiment(py::module_& m);  // Plan, Measurements, sample, Experiment, simulate
void BindDesign(py::module_& m);      // DesignResult, design
void BindIdentify(py::module_& m);    // IdentifyResult, identify, calibrated_robot, report, Validation, validate
void BindSensors(py::module_& m);     // SensorsFit, fit_sensors
void BindMonteCarlo(py::module_& m);  // MonteCarloResult, montecarlo

}  // namespace cablecal::python
