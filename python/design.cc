// Binds the experiment design: cablecal.design and the cablecal.DesignResult it returns (the plan,
// its criteria against random sets, and each Ipopt start), or for a cablecal.SpatialRobot the
// cablecal.SpatialDesignResult (design/spatial_design.h).

#include <atomic>
#include <string>
#include <utility>

#include "common/error.h"
#include "design/design.h"
#include "design/spatial_design.h"
#include "model/robot.h"
#include "model/spatial_robot.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "python/interrupt.h"

namespace cablecal::python {
namespace {

// The design names its inputs by the CLI's flags ("--poses: at least 7 poses ..."); from Python
// the same problem is named by design()'s argument.
template <typename F>
auto WithArgumentNames(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    static const std::pair<const char*, const char*> kArguments[] = {
        {"--poses", "n"},           {"--criterion", "criterion"},         {"--starts", "starts"},
        {"--seed", "seed"},         {"--min-spacing", "min_spacing"},     {"--random-sets", "random_sets"},
        {"--geometry-sigma", "geometry_sigma"}, {"--robust-sigmas", "robust_sigmas"}, {"--prior", "prior"}};
    for (const auto& [flag, argument] : kArguments) {
      if (e.where() != flag || !e.key().empty()) continue;
      const std::string what = e.what();
      throw InputError(argument, "", what.substr(std::string(flag).size() + 2));
    }
    throw;
  }
}

struct PyDesign {
  DesignResult result;
  DesignOptions options;  // as run, without the interrupt flag
};

py::dict CriteriaDict(const CriteriaValues& v) {
  py::dict d;
  d["condition_number"] = v.condition_number;
  d["d_log_det_information"] = v.d_log_det_information;
  d["a_trace_covariance_m2"] = v.a_trace_covariance_m2;
  d["e_min_eigenvalue"] = v.e_min_eigenvalue;
  return d;
}

struct PySpatialDesign {
  SpatialRobot robot;
  SpatialDesignResult result;
  SpatialDesignOptions options;  // as run, without the interrupt flag
};

std::vector<std::string> LayoutNames(const SpatialInformationLayout& layout, const std::vector<int>& columns) {
  std::vector<std::string> names;
  for (int c : columns) names.push_back(layout.names[c]);
  return names;
}

void BindSpatialDesignResult(py::module_& m) {
  py::class_<PySpatialDesign>(m, "SpatialDesignResult", "cablecal.design on a SpatialRobot (README, \"Spatial robots\").")
      .def_property_readonly("plan", [](const PySpatialDesign& d) {
        return PySpatialPlan{d.result.poses, d.robot.num_cables(), {}};
      })
      .def_property_readonly("criteria", [](const PySpatialDesign& d) { return CriteriaDict(d.result.criteria); })
      .def_property_readonly("random_median", [](const PySpatialDesign& d) { return CriteriaDict(d.result.random_median); })
      .def_property_readonly("comparison", [](const PySpatialDesign& d) -> py::object {
        if (d.options.random_sets == 0) return py::none();
        return py::str(ImprovementText(Improvement(d.options.criterion, d.result.criteria, d.result.random_median),
                                       d.options.random_sets));
      }, "\"3.2 x better than the median of 100 random sets\" (or worse) on the criterion; None without random sets")
      .def_property_readonly("held", [](const PySpatialDesign& d) { return LayoutNames(d.result.layout, d.result.layout.held); },
                             "The exit coordinates the gauge holds (a1x, ...).")
      .def_property_readonly("weakly_seen_held", [](const PySpatialDesign& d) { return d.result.layout.weakly_seen_held; },
                             "The weakly seen directions nearly a rigid motion of the frame that the gauge holds too, "
                             "in words (empty for most robots).")
      .def_property_readonly("free", [](const PySpatialDesign& d) { return LayoutNames(d.result.layout, d.result.layout.information_unknowns()); },
                             "The gauge-fixed geometric unknowns the criteria are about.")
      .def_property_readonly("best_start", [](const PySpatialDesign& d) { return d.result.best_start; })
      .def_property_readonly("converged_starts", [](const PySpatialDesign& d) { return d.result.converged_starts; })
      .def_property_readonly("wall_time_s", [](const PySpatialDesign& d) { return d.result.wall_time_s; })
      .def_property_readonly("geometry_sigma_m", [](const PySpatialDesign& d) { return d.result.geometry_sigma_m; },
                             "The exit points' uncertainty the plan was made robust to (m).")
      .def_property_readonly("robustness_requested_k", [](const PySpatialDesign& d) { return d.result.robust_sigmas_requested; },
                             "The robust_sigmas asked for.")
      .def_property_readonly("robustness_achieved_k", [](const PySpatialDesign& d) { return d.result.robust_sigmas_achieved; },
                             "The k the plan holds for (true exit points within k x geometry_sigma_m of nominal): the "
                             "requested one, or the largest below it with verified poses.")
      .def_property_readonly("robustness", [](const PySpatialDesign& d) { return SpatialRobustnessText(d.robot, d.result); },
                             "What the plan holds for, in words (summary.yaml's robustness.holds).")
      .def_property_readonly("robustness_note", [](const PySpatialDesign& d) -> py::object {
        if (!d.result.robustness_lowered()) return py::none();
        return py::str(d.result.robustness_note);
      }, "The sentence saying the robustness was lowered and to what; None when the requested one holds.")
      .def_property_readonly("failure_at_requested", [](const PySpatialDesign& d) -> py::object {
        if (!d.result.robustness_lowered()) return py::none();
        return py::str(d.result.failure_at_requested);
      }, "Why the requested robustness gave no plan (each start's failure there); None when it holds.")
      .def_property_readonly("starts", [](const PySpatialDesign& d) {
        py::list l;
        for (const SpatialStartReport& s : d.result.starts) {
          py::dict e;
          e["start"] = s.start;
          e["ipopt_status"] = s.ipopt_status;
          e["iterations"] = s.iterations;
          e["converged"] = s.converged;
          e["verified"] = s.verified;
          e["verification_failure"] = s.verification_failure;
          e["objective"] = s.objective;
          e["robust_rounds"] = s.robust_rounds;
          e["first_solve_objective"] = s.first_objective;
          e["made_robust"] = s.made_robust;
          l.append(e);
        }
        return l;
      }, "Per Ipopt start: status (its last solve's), iterations (all its solves'), converged, verified "
         "(at the plan's robustness), verification_failure, objective (inf unless verified), robust_rounds, "
         "first_solve_objective, and made_robust (False: starts with lower first-solve objectives were, "
         "and one held; such a start is not verified).")
      .def("to_yaml", [](const PySpatialDesign& d) {
        return SpatialDesignSummaryYaml(d.robot, d.result, d.options, CallText("design"));
      }, "The CLI's summary.yaml.");
}

// The spatial design takes the planar one's arguments. geometry_sigma None: the robot file's
// tracker sigma, else the planar default (SpatialDesignOptions). prior: the path of an earlier
// identification's result.yaml, whose estimate is the robot designed for (design --prior).
py::object SpatialDesign(const SpatialRobot& nominal, py::handle n, py::handle criterion, py::handle starts,
                         py::handle seed, py::handle min_spacing, py::handle random_sets, py::handle geometry_sigma,
                         py::handle robust_sigmas, py::handle prior) {
  SpatialDesignOptions o;
  SpatialRobot robot = nominal;
  if (!prior.is_none()) {
    o.prior = ReadSpatialIdentifiedGeometry(nominal, AsPath(prior, "prior"));
    robot = CalibratedSpatialRobot(nominal, *o.prior);
  }
  o.poses = static_cast<int>(AsInteger(n, "n", 1, kMaxPlanPoses));
  o.criterion = ParseCriterion(AsText(criterion, "criterion"));
  o.starts = static_cast<int>(AsInteger(starts, "starts", 1, 1000));
  o.solve_in_child_processes = false;  // in process, as the planar design() (a fork copies Python's threads)
  o.seed = AsSeed(seed);
  o.min_spacing_m = AsNumber(min_spacing, "min_spacing");
  o.random_sets = static_cast<int>(AsInteger(random_sets, "random_sets", 0, 100000));
  if (!geometry_sigma.is_none()) {
    o.geometry_sigma_m = AsNumber(geometry_sigma, "geometry_sigma");
    if (!(*o.geometry_sigma_m >= 0.0 && *o.geometry_sigma_m <= kMaxGeometrySigma_m)) {
      Bad("geometry_sigma", "must be between 0 and " + FormatDouble(kMaxGeometrySigma_m) + " m (got " +
                                FormatDouble(*o.geometry_sigma_m) + ")");
    }
  }
  if (!robust_sigmas.is_none()) {
    o.robust_sigmas = AsNumber(robust_sigmas, "robust_sigmas");
    if (!(o.robust_sigmas >= 0.0 && o.robust_sigmas <= 10.0)) {
      Bad("robust_sigmas", "must be between 0 and 10 (got " + FormatDouble(o.robust_sigmas) + ")");
    }
  }
  std::atomic<bool> stop{false};
  o.interrupted = &stop;
  PySpatialDesign d{robot, Interruptible(stop, [&] { return WithArgumentNames([&] { return DesignSpatialPoses(robot, o); }); }), o};
  d.options.interrupted = nullptr;
  if (!d.result.prior_note.empty() && PyErr_WarnEx(PyExc_UserWarning, d.result.prior_note.c_str(), 1) < 0) {
    throw py::error_already_set();  // the CLI's warning
  }
  if (!d.result.redundancy_note.empty() &&
      PyErr_WarnEx(PyExc_UserWarning, d.result.redundancy_note.c_str(), 1) < 0) {
    throw py::error_already_set();
  }
  if (d.result.robustness_lowered()) {
    // The CLI's "robustness lowered" line: a plan, but for less than asked.
    const std::string note = "robustness lowered: " + d.result.robustness_note;
    if (PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1) < 0) throw py::error_already_set();
  }
  if (o.random_sets > 0 && !(Improvement(o.criterion, d.result.criteria, d.result.random_median) > 1.0)) {
    // The CLI's warning: a result, but not a good plan.
    const int warned = PyErr_WarnEx(PyExc_UserWarning,
                                    "the designed set is no better than the median random set on its criterion: try "
                                    "more starts, or another seed", 1);
    if (warned < 0) throw py::error_already_set();
  }
  return py::cast(std::move(d));
}

}  // namespace

void BindDesign(py::module_& m) {
  BindSpatialDesignResult(m);
  py::class_<PyDesign>(m, "DesignResult")
      .def_property_readonly("plan", [](const PyDesign& d) { return PyPlan{d.result.poses, d.result.num_cables}; })
      .def_property_readonly("criteria", [](const PyDesign& d) { return CriteriaDict(d.result.criteria); })
      .def_property_readonly("random_median", [](const PyDesign& d) { return CriteriaDict(d.result.random_median); })
      .def_property_readonly("comparison", [](const PyDesign& d) -> py::object {
        if (d.options.random_sets == 0) return py::none();
        return py::str(ImprovementText(Improvement(d.options.criterion, d.result.criteria, d.result.random_median),
                                       d.options.random_sets));
      }, "\"3.2 x better than the median of 100 random sets\" (or worse) on the criterion; None without random sets")
      .def_property_readonly("robustness_requested_k", [](const PyDesign& d) { return d.result.robust_sigmas_requested; },
                             "The robust_sigmas asked for.")
      .def_property_readonly("robustness_achieved_k", [](const PyDesign& d) { return d.result.robust_sigmas_achieved; },
                             "The k the plan holds for (true geometries within k x geometry_sigma of nominal): the "
                             "requested one, or the largest below it with verified poses (README, \"Experiment design\").")
      .def_property_readonly("robustness_note", [](const PyDesign& d) -> py::object {
        if (!d.result.robustness_lowered()) return py::none();
        return py::str(d.result.robustness_note);
      }, "The sentence saying the robustness was lowered and to what; None when the requested one holds.")
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
      }, "Per Ipopt start: status, iterations, converged, verified, objective, robust re-solves.")
      .def("to_yaml", [](const PyDesign& d) { return DesignSummaryYaml(d.result, d.options, CallText("design")); },
           "The CLI's summary.yaml.");
  m.def(
      "design",
      [](py::handle robot_arg, py::handle n, py::handle criterion, py::handle starts, py::handle seed,
         py::handle min_spacing, py::handle random_sets, py::handle geometry_sigma, py::handle robust_sigmas,
         py::handle prior) -> py::object {
        if (py::isinstance<SpatialRobot>(robot_arg)) {
          return SpatialDesign(robot_arg.cast<const SpatialRobot&>(), n, criterion, starts, seed, min_spacing,
                               random_sets, geometry_sigma, robust_sigmas, prior);
        }
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
        // None: the CLI's defaults (DesignOptions').
        if (!geometry_sigma.is_none()) o.geometry_sigma_m = AsNumber(geometry_sigma, "geometry_sigma");
        if (!robust_sigmas.is_none()) o.robust_sigmas = AsNumber(robust_sigmas, "robust_sigmas");
        // In process: a Python process may run threads of its own, and a fork copies them
        // half-way; the plans are bit for bit the same (tests/design).
        o.solve_in_child_processes = false;
        std::atomic<bool> stop{false};
        o.interrupted = &stop;
        PyDesign d{Interruptible(stop, [&] { return WithArgumentNames([&] { return DesignPoses(robot, o); }); }), o};
        d.options.interrupted = nullptr;
        DesignOptions achieved = o;  // the warnings speak of the robustness the plan holds for
        achieved.robust_sigmas = d.result.robust_sigmas_achieved;
        if (d.result.robustness_lowered()) {
          // The CLI's "robustness lowered" line: a plan, but for less than asked.
          const std::string note = "robustness lowered: " + d.result.robustness_note;
          if (PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1) < 0) throw py::error_already_set();
        }
        if (o.random_sets > 0 && !(Improvement(o.criterion, d.result.criteria, d.result.random_median) > 1.0)) {
          // The CLI's warning: a result, but not a good plan.
          const int warned =
              PyErr_WarnEx(PyExc_UserWarning, NoBetterThanRandomWarning(achieved, "geometry_sigma").c_str(), 1);
          if (warned < 0) throw py::error_already_set();  // warnings filtered into errors
        }
        return py::cast(std::move(d));
      },
      py::arg("robot"), py::arg("n"), py::arg("criterion") = "a", py::arg("starts") = 8, py::arg("seed") = 1,
      py::arg("min_spacing") = 0.0, py::arg("random_sets") = 100, py::arg("geometry_sigma") = py::none(),
      py::arg("robust_sigmas") = py::none(), py::arg("prior") = py::none(),
      "Optimal measurement poses (cablecal design); at the largest robustness up to robust_sigmas that gives verified "
      "poses (robustness_achieved_k, with a UserWarning when lower); SolverError if none does, not even without "
      "robustness. prior: the path of an earlier "
      "identification's result.yaml (design --prior). geometry_sigma and robust_sigmas: None is 0.01 m and 3. "
      "For a SpatialRobot: a SpatialDesignResult, robust to the exit points (geometry_sigma None: the robot "
      "file's tracker sigma, else 0.01 m); prior as planar (its result.yaml of the same robot).");
}

}  // namespace cablecal::python
