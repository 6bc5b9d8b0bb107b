// sensors: the laser's and the inclinometer's error models, beside the stages of the data flow.
//   bench_fit.h   fitting them from bench readings of known references (cablecal sensors fit):
//                 the systematic terms with standard errors, the accuracy and repeatability
//                 left over, and the robot file's sensors block that holds them.
//   correction.h  a lab's readings corrected for them before the identification.
// The model itself (the formulas both use, and simulate --systematic-errors) is in
// model/sensor_model.h, since the simulation in identify/ applies it and this stage depends on
// identify/ (for the measurements it corrects).
// Depends on model/, identify/ (experiment.h), common/ and Eigen.
#pragma once

#include "sensors/bench_fit.h"
#include "sensors/correction.h"
