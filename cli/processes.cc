#include "cli/processes.h"

#ifdef CABLECAL_WITH_MPI
#include <mpi.h>
#endif

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "common/error.h"

namespace cablecal::cli {
namespace {

// The exit code of an exception (error.h's tiers) and the words in front of its message.
int ExitCodeOf(const std::exception_ptr& error, const char** label) {
  *label = "internal error";
  try {
    std::rethrow_exception(error);
  } catch (const AlreadyReported& e) {
    return e.exit_code();
  } catch (const InputError&) {
    *label = "error";
    return kExitBadInput;
  } catch (const SolverFailure&) {
    *label = "solver failure";
    return kExitSolverFailed;
  } catch (const RankFailure&) {
    *label = "MPI run failed";
    return kExitRankFailed;
  } catch (const Interrupted&) {
    *label = "";
    return kExitInterrupted;
  } catch (...) {
    return kExitInternal;
  }
}

}  // namespace

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
  // PMPI_: Debian's sequential MUMPS (under Ipopt) exports stand-ins for MPI_Comm_rank,
  // MPI_Init, MPI_Finalize and MPI_Wtime that take precedence over Open MPI's; the
  // profiling names (which every MPI provides) always reach the real library.
  PMPI_Comm_rank(MPI_COMM_WORLD, &processes_.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &processes_.count);
#else
  (void)argc;
  (void)argv;
#endif
}

ProcessSession::~ProcessSession() {
#ifdef CABLECAL_WITH_MPI
  PMPI_Finalize();  // not MPI_Finalize: see the constructor
#endif
}

int ReportCurrentError(const Processes& processes) {
  const std::exception_ptr error = std::current_exception();
  const char* label = "";
  const int code = ExitCodeOf(error, &label);
  std::string message;
  try {
    std::rethrow_exception(error);
  } catch (const AlreadyReported&) {
    return code;
  } catch (const std::exception& e) {
    message = e.what();
  } catch (...) {
    message = "unknown exception";
  }
  const std::string who =
      processes.count > 1 ? " (rank " + std::to_string(processes.rank) + " of " + std::to_string(processes.count) + ")"
                          : "";
  if (code == kExitInterrupted) {
    std::fprintf(stderr, "\ncablecal%s: %s\n", who.c_str(), message.c_str());
  } else {
    std::fprintf(stderr, "cablecal%s: %s: %s\n", who.c_str(), label, message.c_str());
  }
  return code;
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
    const char* label = nullptr;
    code = ExitCodeOf(error, &label);
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
