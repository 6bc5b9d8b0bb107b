#include "cli/processes.h"

#include <unistd.h>

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
#include "common/format.h"

namespace cablecal::cli {

bool BuiltWithMpi() {
#ifdef CABLECAL_WITH_MPI
  return true;
#else
  return false;
#endif
}

#ifdef CABLECAL_WITH_MPI
namespace {

// Whether an MPI launcher started this process (mpirun/mpiexec of Open MPI or MPICH, srun).
// Without one, MPI is not initialised at all: Open MPI's singleton start-up spawns a helper
// daemon and costs about half a second on every command, for a run of one process.
bool StartedByMpiLauncher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "SLURM_STEP_ID"}) {
    if (std::getenv(name)) return true;
  }
  return false;
}

}  // namespace
#endif

ProcessSession::ProcessSession(int* argc, char*** argv) {
#ifdef CABLECAL_WITH_MPI
  if (!StartedByMpiLauncher()) return;
  // Only the main thread calls MPI; OpenMP threads never do.
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  mpi_initialized_ = true;
  const MpiWorld world = WorldOf();
  processes_ = {world.rank, world.size};
#else
  (void)argc;
  (void)argv;
#endif
}

ProcessSession::~ProcessSession() {
#ifdef CABLECAL_WITH_MPI
  if (mpi_initialized_) PMPI_Finalize();  // not MPI_Finalize, which MUMPS's stand-in would answer (WorldOf, montecarlo/mpi.cc)
#endif
}

int ReportCurrentError(const Processes& processes) {
  const ErrorOutcome error = OutcomeOf(std::current_exception());
  if (error.already_reported) return error.exit_code;
  const std::string who =
      processes.count > 1 ? " (rank " + std::to_string(processes.rank) + " of " + std::to_string(processes.count) + ")"
                          : "";
  // Messages quote file contents and names: escaped, so that they cannot drive the terminal.
  const std::string message = PrintableText(error.message);
  if (error.exit_code == kExitInterrupted) {
    // On a terminal, off the line the shell's ^C echo left; elsewhere no blank line.
    std::fprintf(stderr, "%scablecal%s: %s\n", ::isatty(2) ? "\n" : "", who.c_str(), message.c_str());
  } else {
    std::fprintf(stderr, "cablecal%s: %s: %s\n", who.c_str(), error.label, message.c_str());
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
  int initialized = 0;
  PMPI_Initialized(&initialized);
  if (initialized) MPI_Abort(MPI_COMM_WORLD, exit_code);
#endif
  std::exit(exit_code);
}

}  // namespace cablecal::cli
