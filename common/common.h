// common: what every stage shares and none owns.
//   - InputError: the one exception type for bad user input (file, line, key, value);
//     the CLI turns it into exit code 2.
//   - SolverFailure: a solver that did not converge; the CLI turns it into exit code 3.
//   - AtomicOutput: write files under a temporary name, rename only when all succeeded.
//   - Rng: seeded, platform-independent random streams.
//   - FormatDouble / provenance: exact, reproducible text output.
// Depends on the C++ standard library only.
#pragma once

#include "common/atomic_output.h"
#include "common/error.h"
#include "common/format.h"
#include "common/random.h"
#include "common/version.h"
