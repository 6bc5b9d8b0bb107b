// libFuzzer target: the pose-plan CSV reader.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "common/error.h"
#include "experiment/plan.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    cablecal::ReadPosePlanCsv(in, "fuzz.csv", 2);
  } catch (const cablecal::InputError&) {
  }
  return 0;
}
