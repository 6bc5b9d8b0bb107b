// The spatial identification of bench/spatial_experiment.h's problem timed in-process, for
// bench/scipy_spatial_identify.py (bench/README.md): writes the readings (CSV) and prints the median wall time
// of IdentifySpatial (default gauge, the whole call), the held coordinates and the estimates.
//   time_spatial_identify N READINGS_OUT.csv [REPETITIONS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <vector>

#include "bench/spatial_experiment.h"
#include "identify/spatial_identify.h"

int main(int argc, char** argv) {
  using namespace cablecal;
  if (argc < 3) {
    std::fprintf(stderr, "usage: time_spatial_identify N READINGS_OUT.csv [REPETITIONS]\n");
    return 2;
  }
  try {
    const SpatialRobot nominal = bench::SpatialBenchRobot(CABLECAL_SOURCE_DIR);
    const std::vector<SpatialMeasurement> readings = bench::SpatialBenchReadings(nominal, std::atoi(argv[1]));
    std::ofstream(argv[2]) << SpatialMeasurementsCsv(readings, "# bench/time_spatial_identify\n");
    const int repetitions = argc > 3 ? std::atoi(argv[3]) : 100;
    std::vector<double> seconds;
    SpatialIdentifyResult result;
    for (int k = 0; k < repetitions; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      result = IdentifySpatial(nominal, readings, {});
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (!result.converged()) {
        std::fprintf(stderr, "time_spatial_identify: %s\n", result.message.c_str());
        return 3;
      }
    }
    std::nth_element(seconds.begin(), seconds.begin() + seconds.size() / 2, seconds.end());
    std::printf("median_s %.9g\niterations %d final_cost %.9g\nheld", seconds[seconds.size() / 2], result.iterations, result.final_cost);
    for (const std::string& h : result.held) std::printf(" %s", h.c_str());
    std::printf("\n");
    for (std::size_t k = 0; k < result.names.size(); ++k) {
      std::printf("%s %.17g\n", result.names[k].c_str(), result.geometry(k));
    }
    for (std::size_t j = 0; j < result.poses.size(); ++j) {
      std::printf("pose%d", result.pose_ids[j]);
      for (int a = 0; a < 6; ++a) std::printf(" %.17g", result.poses[j](a));
      std::printf("\n");
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "time_spatial_identify: %s\n", e.what());
    return 2;
  }
}
