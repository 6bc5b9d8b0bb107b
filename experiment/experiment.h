// The experiment stage: what a calibration measures and how. The pose plan, its sampling and
// its CSV (plan.h), a lab's readings and their CSV (measurements.h), their correction for the
// robot file's systematic sensor errors (correction.h), and the simulated experiment that
// makes such readings from a plan on a true robot (simulation.h). Identification and design both depend on it, not on each other's
// files. Depends on model/ and on workspace/ (the pose plan and the feasibility of a pose).
#pragma once

#include "experiment/correction.h"
#include "experiment/measurements.h"
#include "experiment/plan.h"
#include "experiment/simulation.h"
