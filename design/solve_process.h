// Internal to design/: Ipopt solves of different starts at once, each in a child process
// (Debian's MUMPS, Ipopt's linear solver, is not thread-safe within one process).
#pragma once

#include <optional>
#include <vector>

#include "design/ipopt_nlp.h"

namespace cablecal::internal {

// SolveDesignNlp in a forked child, its outcome sent back through a pipe: the same outcome,
// bit for bit, as in-process (same code, same inputs). Errors come back as the same kinds
// (SolverFailure, InputError, std::bad_alloc); a child that dies before reporting is a
// SolverFailure. std::nullopt when no child process could be started: solve in-process.
std::optional<StartOutcome> SolveDesignNlpInChildProcess(const Robot& robot, const DesignOptions& options,
                                                         const std::vector<PlanPose>& start,
                                                         const std::vector<double>* widening);

}  // namespace cablecal::internal
