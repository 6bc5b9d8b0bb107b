// Binds the robot: cablecal.Robot (a robot file's content, loaded, built in or from a dict, and
// back to YAML) and cablecal.workspace (where the robot can hold its platform).
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "common/error.h"
#include "experiment/experiment.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "model/statics.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "workspace/spatial_workspace.h"
#include "workspace/workspace.h"

namespace cablecal::python {

void BindModel(py::module_& m) {
  // ---- Robot
  py::class_<Robot>(m, "Robot", "A robot file's content (README, \"Robot file\").")
      .def_static(
          "load",
          [](py::handle path) -> py::object {
            const std::string p = AsPath(path, "path");
            // A spatial file is a cablecal.SpatialRobot (bound after this class: looked up by name).
            if (RobotKindOfFile(p) == RobotKind::kSpatial) return py::module_::import("cablecal").attr("SpatialRobot").attr("load")(p);
            return py::cast(LoadRobotFile(p));
          },
          py::arg("path"), "Loads and validates a robot YAML file: a cablecal.Robot, or a cablecal.SpatialRobot for a file with kind: spatial.")
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
          [](py::handle d) -> py::object {
            // By its kind, as Robot.load reads a file: a spatial dict gives a SpatialRobot.
            const bool spatial = py::isinstance<py::dict>(d) && d.cast<py::dict>().contains("kind") &&
                                 py::str(d.cast<py::dict>()["kind"]).cast<std::string>() == "spatial";
            if (spatial) return py::cast(RobotFromDict(d, LoadSpatialRobotFromString));
            return py::cast(RobotFromDict(d, LoadRobotFromString));
          },
          py::arg("d"),
          "A robot from a dict in the robot file's schema (the file's checks apply); a SpatialRobot when its kind "
          "is spatial.")
      .def("to_dict", [](const Robot& r) { return FromYaml(YAML::Load(RobotToYaml(r))); })
      .def("to_yaml", [](const Robot& r) { return RobotToYaml(r); })
      .def_property_readonly("name", [](const Robot& r) { return r.name; })
      .def_property_readonly("num_cables", &Robot::num_cables)
      .def_property_readonly("kind", [](const Robot&) { return "planar"; })
      .def_property_readonly("geometry", [](const Robot& r) { return Vector(GeometryOf(r)); },
                             "a1x a1z ... amx amz l10 ... lm0 (m)")
      .def_property_readonly("geometry_names", [](const Robot& r) { return GeometryNames(r.num_cables()); })
      .def("__repr__", [](const Robot& r) {
        return "<cablecal.Robot '" + r.name + "', " + std::to_string(r.num_cables()) + " cables>";
      });

  // ---- workspace
  m.def(
      "workspace",
      [](py::handle robot_arg, py::handle step, py::handle rpy_deg) -> py::object {
        const bool spatial = py::isinstance<SpatialRobot>(robot_arg);
        // None: the CLI's default (planar 0.05 m; spatial DefaultSpatialStep).
        const double step_m = !step.is_none() ? AsNumber(step, "step")
                              : spatial       ? DefaultSpatialStep(robot_arg.cast<const SpatialRobot&>())
                                              : 0.05;
        if (!(step_m > 0.0)) Bad("step", "must be positive (m)");
        if (spatial) return SpatialWorkspace(robot_arg.cast<const SpatialRobot&>(), step_m, rpy_deg);
        if (!rpy_deg.is_none()) Bad("rpy_deg", "serves spatial robots only (a cablecal.SpatialRobot)");
        const Robot& robot = AsObject<Robot>(robot_arg, "robot", "Robot");
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
      py::arg("robot"), py::arg("step") = py::none(), py::arg("rpy_deg") = py::none(),
      "The feasible workspace on a grid: x, z, theta, tensions (NaN without equilibrium), feasible, reason, "
      "area_m2, and csv (the CLI's file). For a SpatialRobot the constant-orientation workspace at rpy_deg "
      "(roll, pitch, yaw in degrees; default home's): xyz (n, 3), rpy (n, 3), tensions, feasible, reason, volume_m3, csv.");
}

}  // namespace cablecal::python
