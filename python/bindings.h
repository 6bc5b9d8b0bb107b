// The module's sections, one .cc each, called in turn by the module's body (cablecal_module.cc),
// and the Python-side types more than one section hands around. A section binds its classes
// before its functions, and after the sections whose classes its signatures name: pybind11
// writes a type into a docstring by its Python name only if that type is bound by then.
#pragma once

#include <functional>

// Every section sees the same type casters, those the module was written with: a type whose
// caster a section lacked would still compile and fail only when converted.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <vector>

#include <cstdint>

#include "experiment/experiment.h"
#include "experiment/spatial_measurements.h"
#include "experiment/spatial_plan.h"
#include "model/spatial_robot.h"
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

// cablecal.SpatialPlan, cablecal.SpatialMeasurements: as Plan and Measurements, spatial.
struct PySpatialPlan {
  std::vector<SpatialPlanPose> poses;
  int num_cables = 0;
  std::vector<int> pose_ids;  // a loaded file's pose column; empty: 1..n in order (as simulate numbers them)
};
struct PySpatialMeasurements {
  std::vector<SpatialMeasurement> readings;
  int num_cables = 0;
};

void BindModel(py::module_& m);       // Robot, workspace
void BindSpatial(py::module_& m);     // SpatialRobot, SpatialPlan, SpatialMeasurements, SpatialExperiment
// The spatial halves of workspace, sample and simulate (python/spatial.cc), for a SpatialRobot.
py::object SpatialWorkspace(const SpatialRobot& robot, double step_m, py::handle rpy_deg);
py::object SpatialSample(const SpatialRobot& robot, int n, std::uint64_t seed, py::handle yaw_range_deg);
py::object SpatialSimulate(const SpatialRobot& robot, py::handle plan, py::handle truth, py::handle geometry_sigma,
                           NoisySensors noisy, bool encoder_noise, std::uint64_t seed, bool systematic_errors,
                           bool skip_infeasible);
// The spatial halves of identify, calibrated_robot and validate (python/spatial_identify.cc), for
// a SpatialRobot; SpatialMeasurements from arrays (dl, {sensor name: (n, k)}, pose ids).
void BindSpatialIdentify(py::module_& m);  // SpatialIdentifyResult, SpatialValidation
py::object SpatialIdentify(const SpatialRobot& robot, py::handle measurements, py::handle estimator, py::handle gauge,
                           py::handle max_iterations, py::handle loss, py::handle geometry_prior,
                           py::handle equilibrium, py::handle identify, py::handle plan);
py::object SpatialCalibratedRobot(const SpatialRobot& nominal, py::handle result);
py::object SpatialValidatePy(const SpatialRobot& robot, py::handle measurements, py::handle nominal,
                             bool skip_infeasible);
// report() for a SpatialRobot: the spatial report (identify/spatial_calibration_report.h) into
// `directory`, its figures through `draw`; returns report.md's path.
std::string SpatialReport(const SpatialRobot& nominal, py::handle result, py::handle directory, py::handle holdout,
                          const std::function<std::string(const std::vector<std::string>&)>& draw);
PySpatialMeasurements MakeSpatialMeasurements(const SpatialRobot& robot, py::handle dl, py::handle sensors,
                                              py::handle pose_ids);
void BindExperiment(py::module_& m);  // Plan, Measurements, sample, Experiment, simulate
void BindDesign(py::module_& m);      // DesignResult, design
void BindIdentify(py::module_& m);    // IdentifyResult, identify, calibrated_robot, report, Validation, validate
void BindSensors(py::module_& m);     // SensorsFit, fit_sensors
void BindMonteCarlo(py::module_& m);  // MonteCarloResult, montecarlo

}  // namespace cablecal::python
