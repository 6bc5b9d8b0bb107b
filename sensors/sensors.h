// sensors: the laser's and the inclinometer's error models fitted from bench readings of known
// references (cablecal sensors fit, bench_fit.h): the systematic terms with standard errors,
// the accuracy and repeatability left over, and the robot file's sensors block that holds
// them. A bench test is an experiment of its own, with its own files; the lab's readings are
// corrected for the fitted errors in experiment/correction.h, and the model both use (and
// simulate --systematic-errors) is model/sensor_model.h.
// Depends on model/, common/ and Eigen.
#pragma once

#include "sensors/bench_fit.h"
