// libFuzzer target: the measurement CSV reader, and the identification on whatever it
// accepts (small inputs only, so that every input runs in milliseconds): data that parse
// must give a converged result or a status, never a crash or a non-finite estimate.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "common/error.h"
#include "experiment/experiment.h"
#include "identify/identify.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  std::vector<cablecal::Measurement> measurements;
  try {
    measurements = cablecal::ReadMeasurementsCsv(in, "fuzz.csv", 2);
  } catch (const cablecal::InputError&) {
    return 0;
  }
  if (measurements.size() > 12) return 0;
  cablecal::IdentifyOptions options;
  options.max_iterations = 20;
  try {
    const cablecal::IdentifyResult r = cablecal::Identify(cablecal::BuiltinRobot(), measurements, options);
    if (r.converged() && !r.geometry.allFinite()) std::abort();  // a converged result is finite
  } catch (const cablecal::InputError&) {
  }
  return 0;
}
