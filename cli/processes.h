// The processes of one cablecal run. Without CABLECAL_MPI, or started without an MPI
// launcher, there is one. Built with MPI and started by mpirun or srun, every rank runs
// main(): montecarlo and reproduce split their work across the ranks (montecarlo/mpi.h)
// and only rank 0 prints results and writes files; other subcommands refuse to run on
// more than one process.
#pragma once

#include <functional>

namespace cablecal::cli {

struct Processes {
  int rank = 0;
  int count = 1;
  bool root() const { return rank == 0; }
};

bool BuiltWithMpi();

// Initialises MPI (in MPI builds) for the lifetime of main() and finalises it.
class ProcessSession {
 public:
  ProcessSession(int* argc, char*** argv);
  ~ProcessSession();
  ProcessSession(const ProcessSession&) = delete;
  ProcessSession& operator=(const ProcessSession&) = delete;
  const Processes& processes() const { return processes_; }

 private:
  Processes processes_;
  bool mpi_initialized_ = false;
};

// The exit code of the exception being handled (README, "Exit codes"); prints its message
// ("rank k of P" in front when there are several processes), except for AlreadyReported,
// which is silent.
int ReportCurrentError(const Processes& processes);

// Runs `step` on every process. If it throws on any, the lowest failing rank prints its
// error and every process throws AlreadyReported with that exit code: one message, and no
// process left waiting for another. With one process it simply runs `step`.
void RunAgreed(const Processes& processes, const std::function<void()>& step);

// Ends every process of the job after an error the others do not know of (MPI_Abort).
[[noreturn]] void AbortJob(int exit_code);

}  // namespace cablecal::cli
