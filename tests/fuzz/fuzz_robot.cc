// libFuzzer target: the robot-file loader. Any input must either load or be rejected with
// an InputError; any other exception, crash, sanitizer report or hang is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/error.h"
#include "model/robot.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    cablecal::LoadRobotFromString(text, "fuzz.yaml");
  } catch (const cablecal::InputError&) {
  }
  return 0;
}
