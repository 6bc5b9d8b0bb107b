// The built-in spatial robots: robots/cogiro.yaml, ipanema1.yaml and irma4u.yaml, embedded
// verbatim at configure time (as the planar built-in robot, model/robot.h BuiltinRobot), so
// that the Python module and the tests reach them wherever cablecal is installed.
#pragma once

#include <string>
#include <vector>

#include "model/spatial_robot.h"

namespace cablecal {

// "cogiro", "ipanema1", "irma4u".
const std::vector<std::string>& BuiltinSpatialRobotNames();
// The file's text; InputError naming `name` and the choices for another name.
const std::string& BuiltinSpatialRobotYaml(const std::string& name);
SpatialRobot BuiltinSpatialRobot(const std::string& name);

}  // namespace cablecal
