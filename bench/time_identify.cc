// One identification of a measurement file, timed in-process: what the Monte Carlo runs per
// trial (estimator ml, gauge a1x, estimates only: no covariance, no identifiability), repeated
// and reported as the median wall time, with the estimates. bench/identify_vs_scipy.sh runs it
// beside an independent scipy identification of the same file (bench/scipy_identify.py).
//   time_identify ROBOT.yaml MEASUREMENTS.csv [REPETITIONS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

#include "experiment/experiment.h"
#include "identify/identify.h"

int main(int argc, char** argv) {
  using namespace cablecal;
  if (argc < 3) {
    std::fprintf(stderr, "usage: time_identify ROBOT.yaml MEASUREMENTS.csv [REPETITIONS]\n");
    return 2;
  }
  try {
    const Robot robot = LoadRobotFile(argv[1]);
    const std::vector<Measurement> measurements = ReadMeasurementsCsv(argv[2], robot.num_cables());
    const int repetitions = argc > 3 ? std::atoi(argv[3]) : 200;
    IdentifyOptions options;
    options.compute_covariance = false;
    options.compute_identifiability = false;
    options.check_plausible_geometry = false;
    std::vector<double> seconds;
    IdentifyResult result;
    for (int k = 0; k < repetitions; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      result = Identify(robot, measurements, options);
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (!result.converged()) {
        std::fprintf(stderr, "time_identify: %s\n", result.message.c_str());
        return 3;
      }
    }
    std::nth_element(seconds.begin(), seconds.begin() + seconds.size() / 2, seconds.end());
    std::printf("median_s %.9g\niterations %d\n", seconds[seconds.size() / 2], result.iterations);
    const std::vector<std::string> names = GeometryNames(robot.num_cables());
    for (std::size_t k = 0; k < names.size(); ++k) std::printf("%s %.17g\n", names[k].c_str(), result.geometry(k));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "time_identify: %s\n", e.what());
    return 2;
  }
}
