// The InputError message of loading a robot file's text ("" if it loads): for tests of the
// robot file's checks.
#pragma once

#include <string>

#include "common/error.h"
#include "model/robot.h"

namespace cablecal::testing {

inline std::string LoadError(const std::string& yaml) {
  try {
    LoadRobotFromString(yaml, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace cablecal::testing
