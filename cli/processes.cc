#include "cli/processes.h"

#ifdef CABLECAL_WITH_MPI
#include <mpi.h>

#include "montecarlo/mpi.h"
#endif

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "common/error.h"

namespace cablecal::cli {

bool BuiltWithMpi() {
#ifdef CABLECAL_WITH_MPI
  return true;
#else
  return false;
#endif
}

ProcessSession::ProcessSession(int* argc, char*** argv) {
#ifdef CABLECAL_WITH_MPI
  // Only the main thread calls MPI; OpenMP threads never do.
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  const MpiWorld world = WorldOf();
  processes_ = {world.rank, world.size};
#else
  (void)argc;
  (void)argv;
#endif
}

ProcessSession::~ProcessSession() {
#ifdef CABLECAL_WITH_MPI
  PMPI_Finalize();  // not MPI_Finalize, which MUMPS's stand-in would answer (WorldOf, montecarlo/mpi.cc)
#endif
}

int ReportCurrentError(const Processes& processes) {
  const ErrorOutcome error = OutcomeOf(std::current_exception());
  if (error.already_reported) return error.exit_code;
  const std::string who =
      processes.count > 1 ? " (rank " + std::to_string(processes.rank) + " of " + std::to_string(processes.count) + ")"
                          : "";
  if (error.exit_code == kExitInterrupted) {
    std::fprintf(stderr, "\ncablecal%s: %s\n", who.c_str(), error.message.c_str());
  } else {
    std::fprintf(stderr, "cablecal%s: %s: %s\n", who.c_str(), error.label, error.message.c_str());
  }
  return error.exit_code;
}

void RunAgreed(const Processes& processes, const std::function<void()>& step) {
  if (processes.count == 1) {
    step();
    return;
  }
#ifdef CABLECAL_WITH_MPI
  int code = 0;
  std::exception_ptr error;
  try {
    step();
  } catch (...) {
    error = std::current_exception();
    code = OutcomeOf(error).exit_code;
  }
  std::vector<int> codes(processes.count);
  MPI_Allgather(&code, 1, MPI_INT, codes.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int k = 0; k < processes.count; ++k) {
    if (codes[k] == 0) continue;
    if (k == processes.rank) {
      try {
        std::rethrow_exception(error);
      } catch (...) {
        ReportCurrentError(processes);
      }
    }
    throw AlreadyReported(codes[k]);
  }
#endif
}

void AbortJob(int exit_code) {
#ifdef CABLECAL_WITH_MPI
  MPI_Abort(MPI_COMM_WORLD, exit_code);
#endif
  std::exit(exit_code);
}

}  // namespace cablecal::cli
