// Error tiers:
//   InputError     bad user input: a file, a flag, a value. Exit code 2.
//   SolverFailure  a solver that did not converge or returned a result that failed
//                  verification. Exit code 3.
//   RankFailure    a process of an MPI run could not finish its share. Exit code 4.
//   FigureFailure  a figure could not be made; the command's other outputs were written. Exit code 5.
//   CABLECAL_CHECK a broken internal invariant: always on, aborts with a message.
#pragma once

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <stdexcept>
#include <string>

namespace cablecal {

enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,   // a bug: an unexpected exception or a failed invariant
  kExitBadInput = 2,   // bad file, flag or value
  kExitSolverFailed = 3,
  kExitRankFailed = 4,  // a process of an MPI run failed; nothing written
  kExitFigureFailed = 5,  // a plotting script failed; the computed results were written
  kExitInterrupted = 130,
};

// Bad user input. `where` names the source ("robots/x.yaml:12" or "--step"),
// `key` the field ("platform.mass"); what() is the full one-line message.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& where, const std::string& key, const std::string& problem)
      : std::runtime_error(Compose(where, key, problem)), where_(where), key_(key), problem_(problem) {}
  const std::string& where() const { return where_; }
  const std::string& key() const { return key_; }
  // The message without its where and key: for a caller that names the place better.
  const std::string& problem() const { return problem_; }

 private:
  static std::string Compose(const std::string& where, const std::string& key,
                             const std::string& problem) {
    std::string s = where;
    if (!key.empty()) s += (s.empty() ? "" : ": ") + key;
    return s + (s.empty() ? "" : ": ") + problem;
  }
  std::string where_, key_, problem_;
};

class SolverFailure : public std::runtime_error {
 public:
  explicit SolverFailure(const std::string& message) : std::runtime_error(message) {}
};

// A plotting script failed. Computed results are never discarded for a figure: the command
// commits its other outputs first, then reports this. Exit code 5.
class FigureFailure : public std::runtime_error {
 public:
  explicit FigureFailure(const std::string& message) : std::runtime_error(message) {}
};

// The user stopped a run (Ctrl-C); nothing is written. Exit code 130.
class Interrupted : public std::runtime_error {
 public:
  Interrupted() : std::runtime_error("interrupted: no output written") {}
};

// One or more processes of an MPI run could not finish their share of a study; the message
// names them and the cells they lost. Nothing is written. Exit code 4.
class RankFailure : public std::runtime_error {
 public:
  explicit RankFailure(const std::string& message) : std::runtime_error(message) {}
};

// In a run of several processes, the failure has been reported by the process that prints
// it (rank 0, or the rank where it happened); this one exits with the same code quietly.
class AlreadyReported : public std::runtime_error {
 public:
  explicit AlreadyReported(int exit_code)
      : std::runtime_error("reported by another process"), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

// The size of the last allocation that failed, in bytes (0: unknown). The cablecal program
// replaces the global operator new to record it (cli/out_of_memory.cc), so that running out
// of memory names the size asked for; a library user's program leaves it 0.
inline std::atomic<std::size_t>& FailedAllocationBytes() {
  static std::atomic<std::size_t> bytes{0};
  return bytes;
}

// How an exception ends a run: its exit code (the tiers above), the words printed in front
// of its message, and the message. The one place that maps exceptions to exit codes, for
// main() and for the ranks of an MPI run alike.
struct ErrorOutcome {
  int exit_code = kExitInternal;
  const char* label = "internal error";
  std::string message = "unknown exception";
  bool already_reported = false;  // AlreadyReported: exit quietly with exit_code
};
inline ErrorOutcome OutcomeOf(const std::exception_ptr& error) {
  ErrorOutcome out;
  try {
    std::rethrow_exception(error);
  } catch (const AlreadyReported& e) {
    out.exit_code = e.exit_code();
    out.already_reported = true;
    out.message = e.what();
  } catch (const InputError& e) {
    out = {kExitBadInput, "error", e.what()};
  } catch (const SolverFailure& e) {
    out = {kExitSolverFailed, "solver failure", e.what()};
  } catch (const RankFailure& e) {
    out = {kExitRankFailed, "MPI run failed", e.what()};
  } catch (const FigureFailure& e) {
    out = {kExitFigureFailed, "error", e.what()};
  } catch (const Interrupted& e) {
    out = {kExitInterrupted, "", e.what()};
  } catch (const std::bad_alloc&) {
    // Not a bug: the inputs asked for more memory than this machine has.
    const std::size_t bytes = FailedAllocationBytes().load();
    char size[64] = "";
    if (bytes >= 1e9) {
      std::snprintf(size, sizeof(size), " (an allocation of %.2f GB failed)", bytes / 1e9);
    } else if (bytes >= 1e6) {
      std::snprintf(size, sizeof(size), " (an allocation of %.0f MB failed)", bytes / 1e6);
    } else if (bytes > 0) {
      std::snprintf(size, sizeof(size), " (an allocation of %zu bytes failed)", bytes);
    }
    out = {kExitBadInput, "error",
           std::string("out of memory") + size +
               ": the inputs ask for more memory than this machine has (fewer poses, trials, pose counts or a "
               "coarser --step)"};
  } catch (const std::exception& e) {
    out.message = e.what();
  } catch (...) {
  }
  return out;
}

[[noreturn]] inline void CheckFailed(const char* expr, const char* file, int line,
                                     const std::string& message) {
  std::fprintf(stderr, "cablecal: internal error: %s:%d: check '%s' failed: %s\n", file, line,
               expr, message.c_str());
  std::abort();
}

}  // namespace cablecal

#define CABLECAL_CHECK(expr, message)                                    \
  do {                                                                   \
    if (!(expr)) ::cablecal::CheckFailed(#expr, __FILE__, __LINE__, (message)); \
  } while (0)
