// model: the robot description and its physics, the first stage of the data flow.
//   robot.h    Robot (immutable description), loading and validating robot files.
//   cable.h    cable length with pulley wrap, wrench matrix, gravity: templated on the
//              scalar so Ceres Jets, the Ipopt design and the simulator share one formula.
//   sensor_model.h  the sensors' systematic errors: added by simulate, removed by identify.
//   statics.h  equilibrium, stability, the feasible-pose test, inverse and forward
//              geometrico-static models.
//   kind.h     the kinds of robot (planar, spatial): pose coordinates, points, wrenches.
//   spatial_robot.h  SpatialRobot, the `kind: spatial` robot file (loading, writing, the
//              kind of a file), PlanarAsSpatial.
//   swivel.h   spatial cables through swivel pulleys, orientation, wrench matrix, gravity:
//              templated on the scalar like cable.h.
// Depends on Eigen, ceres/jet.h (for the stiffness derivatives), yaml-cpp and common/.
#pragma once

#include "model/cable.h"
#include "model/robot.h"
#include "model/sensor_model.h"
#include "model/spatial_robot.h"
#include "model/statics.h"
#include "model/swivel.h"
