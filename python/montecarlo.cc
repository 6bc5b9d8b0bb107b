// Binds the Monte Carlo study: cablecal.montecarlo (interruptible, with progress callbacks) and
// the cablecal.MonteCarloResult it returns.

#include <omp.h>

#include <atomic>
#include <cmath>
#include <string>
#include <utility>

#include "model/robot.h"
#include "model/spatial_robot.h"
#include "montecarlo/montecarlo.h"
#include "montecarlo/spatial_montecarlo.h"
#include "python/bindings.h"
#include "python/converters.h"
#include "python/interrupt.h"

namespace cablecal::python {

void BindMonteCarlo(py::module_& m) {
  py::class_<MonteCarloResult>(m, "MonteCarloResult")
      .def_readonly("wall_time_s", &MonteCarloResult::wall_time_s)
      .def("summary_csv", [](const MonteCarloResult& r) { return SummaryCsv(r); }, "The CLI's summary.csv.")
      .def("failures_csv", [](const MonteCarloResult& r) { return FailuresCsv(r); })
      .def_property_readonly("summary", [](const MonteCarloResult& r) {
        py::list rows;
        for (const MonteCarloCell& cell : r.cells) {
          for (const std::string& parameter : SummaryParameters(r.geometry_names)) {
            const ErrorStats s = Summarise(cell, r.geometry_names, parameter);
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
         py::handle equilibrium, py::handle com_error, py::handle exact_platform, py::handle skip_infeasible,
         py::handle tension_margin, py::handle frame_margin, py::handle tilt_margin_deg, py::handle random_pool) {
        // A SpatialRobot's study (montecarlo/spatial_montecarlo.h) takes the same arguments; the
        // planar-only ones must stay at their defaults.
        const bool spatial = py::isinstance<SpatialRobot>(robot_arg);
        const Robot* planar = spatial ? nullptr : &AsObject<Robot>(robot_arg, "robot", "Robot or SpatialRobot");
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
        o.design_in_child_processes = false;  // as design() (design.cc)
        SpatialMonteCarloOptions spatial_options;
        if (!py::isinstance<py::bool_>(exact_platform)) Bad("exact_platform", "expected True or False");
        if (!spatial && exact_platform.cast<bool>()) Bad("exact_platform", "serves spatial robots only (a cablecal.SpatialRobot)");
        spatial_options.exact_platform = exact_platform.cast<bool>();
        // The spatial study's planning margins and pool (montecarlo --skip-infeasible,
        // --tension-margin, --frame-margin, --tilt-margin-deg, --random-pool): refused for a
        // planar robot unless at their defaults, as the CLI's flags.
        if (!py::isinstance<py::bool_>(skip_infeasible)) Bad("skip_infeasible", "expected True or False");
        spatial_options.skip_infeasible = skip_infeasible.cast<bool>();
        spatial_options.plan_tension_margin_N = AsNumber(tension_margin, "tension_margin");
        spatial_options.plan_margin_m = AsNumber(frame_margin, "frame_margin");
        spatial_options.plan_tilt_margin_rad = AsNumber(tilt_margin_deg, "tilt_margin_deg") * M_PI / 180.0;
        spatial_options.random_pool = static_cast<int>(AsInteger(random_pool, "random_pool", 0, 100000));
        if (!spatial) {
          const std::pair<bool, const char*> spatial_only[] = {
              {spatial_options.skip_infeasible, "skip_infeasible"},
              {spatial_options.plan_tension_margin_N != 0.0, "tension_margin"},
              {spatial_options.plan_margin_m != 0.0, "frame_margin"},
              {spatial_options.plan_tilt_margin_rad != 0.0, "tilt_margin_deg"},
              {spatial_options.random_pool != 0, "random_pool"}};
          for (const auto& [given, name] : spatial_only) {
            if (given) Bad(name, "serves spatial robots only (a cablecal.SpatialRobot)");
          }
        }
        if (spatial) {
          spatial_options.study = o;
          ValidateSpatialMonteCarloOptions(robot_arg.cast<const SpatialRobot&>(), spatial_options);
        } else {
          ValidateOptions(o, planar);
        }
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
              if (spatial) {
                spatial_options.study.progress = o.progress;
                spatial_options.study.interrupted = o.interrupted;
                return RunSpatialMonteCarlo(robot_arg.cast<const SpatialRobot&>(), spatial_options);
              }
              return RunMonteCarlo(*planar, o);
            },
            report);
        report();  // the last count: (total, total)
        RefuseIfEveryTrialFailed(r);  // SolverError, as the CLI's exit 3: no statistics to return
        const FailureTally tally = TallyFailures(r);
        if (2 * tally.failed > tally.trials) {  // the CLI's warning
          const std::string note = std::to_string(tally.failed) + " of " + std::to_string(tally.trials) +
                                   " trials failed (" + tally.by_cause +
                                   "): the statistics speak of the few that did not; failures_csv() says why";
          if (PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1) < 0) throw py::error_already_set();
        }
        return r;
      },
      py::arg("robot"), py::arg("poses"), py::arg("trials"), py::arg("designs") = "random,optimized",
      py::arg("estimator") = "ml", py::arg("gauge") = "a1x", py::arg("sensors") = "both",
      py::arg("geometry_sigma") = 0.01, py::arg("seed") = 1, py::arg("design_starts") = 2,
      py::arg("threads") = py::none(), py::arg("progress") = py::none(), py::arg("loss") = "none",
      py::arg("outliers") = "0", py::arg("geometry_prior") = false,
      py::arg("equilibrium") = kDefaultEquilibrium ? "on" : "off", py::arg("com_error") = 0.0,
      py::arg("exact_platform") = false, py::arg("skip_infeasible") = false, py::arg("tension_margin") = 0.0,
      py::arg("frame_margin") = 0.0, py::arg("tilt_margin_deg") = 0.0, py::arg("random_pool") = 0,
      "The Monte Carlo study (cablecal montecarlo) of a Robot or a SpatialRobot (designs also grid:2x2x2, "
      "grid:3x3x3; the planar-only arguments at their defaults); Ctrl-C raises KeyboardInterrupt. progress(done, total), if "
      "given, is called now and then with the trials done. geometry_prior: identify every trial with "
      "geometry_sigma as a prior (montecarlo --geometry-prior). exact_platform: a SpatialRobot's true platforms "
      "have its file's mass and centre of mass (montecarlo --exact-platform), not values drawn from its priors. "
      "skip_infeasible, tension_margin (N), frame_margin (m), tilt_margin_deg, random_pool: a SpatialRobot's "
      "montecarlo --skip-infeasible, --tension-margin, --frame-margin, --tilt-margin-deg, --random-pool.");
}

}  // namespace cablecal::python
