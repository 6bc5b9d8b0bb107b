// model: the robot description and its physics, the first stage of the data flow.
//   robot.h    Robot (immutable description), loading and validating robot files.
//   cable.h    cable length with pulley wrap, wrench matrix, gravity: templated on the
//              scalar so Ceres Jets, the Ipopt design and the simulator share one formula.
//   sensor_model.h  the sensors' systematic errors: added by simulate, removed by identify.
//   statics.h  equilibrium, stability, the feasible-pose test, inverse and forward
//              geometrico-static models.
// Depends on Eigen, ceres/jet.h (for the stiffness derivatives), yaml-cpp and common/.
#pragma once

#include "model/cable.h"
#include "model/robot.h"
#include "model/sensor_model.h"
#include "model/statics.h"
