// Internal to design/: one Ipopt solve in a child process (README, "Experiment design",
// speed). Debian's Ipopt links MUMPS, which is not thread-safe (coin-or/Ipopt#733), so two
// solves cannot share one process; in two processes they run at once. The child is a fork of
// the caller: it solves, writes the outcome to a pipe and leaves with _exit (no atexit
// handlers, no flushing of the parent's buffered output, no second leak report).
#include "design/solve_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <functional>
#include <new>
#include <stdexcept>
#include <string>

#include "common/error.h"

namespace cablecal::internal {
namespace {

// What the child sends: a tag, then the outcome or the error's kind and message.
enum Tag : std::int32_t { kOutcome = 1, kSolverFailure = 2, kInputError = 3, kOutOfMemory = 4, kOtherError = 5 };

std::string Encode(const StartOutcome& o) {
  ByteWriter w;
  w.PutString(o.status);
  w.Put(static_cast<std::int32_t>(o.iterations));
  w.Put(static_cast<std::int32_t>(o.converged));
  w.Put(static_cast<std::int64_t>(o.poses.size()));
  for (const PlanarPose& q : o.poses) {
    for (int i = 0; i < PlanarKind::kPoseDim; ++i) w.Put(q(i));
  }
  w.Put(static_cast<std::int64_t>(o.tensions_N.size()));
  for (const Eigen::VectorXd& t : o.tensions_N) {
    w.Put(static_cast<std::int64_t>(t.size()));
    for (Eigen::Index i = 0; i < t.size(); ++i) w.Put(t(i));
  }
  return w.bytes;
}

StartOutcome Decode(const std::string& bytes) {
  ByteReader r{bytes};
  StartOutcome o;
  o.status = r.GetString();
  o.iterations = r.Get<std::int32_t>();
  o.converged = r.Get<std::int32_t>() != 0;
  o.poses.resize(static_cast<std::size_t>(r.Get<std::int64_t>()));
  for (PlanarPose& q : o.poses) {
    for (int i = 0; i < PlanarKind::kPoseDim; ++i) q(i) = r.Get<double>();
  }
  o.tensions_N.resize(static_cast<std::size_t>(r.Get<std::int64_t>()));
  for (Eigen::VectorXd& t : o.tensions_N) {
    t.resize(r.Get<std::int64_t>());
    for (Eigen::Index i = 0; i < t.size(); ++i) t(i) = r.Get<double>();
  }
  return o;
}

bool WriteAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t k = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    done += static_cast<std::size_t>(k);
  }
  return true;
}

[[noreturn]] void RunChild(int fd, pid_t parent, const std::function<std::string()>& solve) {
  // A child outlives no parent: killed with it (a killed cablecal leaves no solver running).
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(1);
  ByteWriter w;
  try {
    const std::string outcome = solve();
    w.Put(kOutcome);
    w.bytes += outcome;
  } catch (const SolverFailure& e) {
    w.bytes.clear();
    w.Put(kSolverFailure);
    w.PutString(e.what());
  } catch (const InputError& e) {
    w.bytes.clear();
    w.Put(kInputError);
    w.PutString(e.what());
  } catch (const std::bad_alloc&) {
    w.bytes.clear();
    w.Put(kOutOfMemory);
    w.PutString("");
  } catch (const std::exception& e) {
    w.bytes.clear();
    w.Put(kOtherError);
    w.PutString(e.what());
  }
  ::_exit(WriteAll(fd, w.bytes) ? 0 : 1);
}

}  // namespace

std::optional<std::string> RunInChildProcess(const std::function<std::string()>& solve,
                                             const std::atomic<bool>* interrupted) {
#if defined(CABLECAL_ADDRESS_SANITIZER)
  // A child forked while another thread holds AddressSanitizer's allocator lock waits for it
  // forever (seen in CI: a design test's child stuck in the allocator): the instrumented build
  // solves in this process, taking turns, which gives the same outcome.
  (void)solve, (void)interrupted;
  return std::nullopt;
#endif
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return std::nullopt;
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {  // no process to be had (EAGAIN, ENOMEM): the caller solves in-process
    ::close(fds[0]);
    ::close(fds[1]);
    return std::nullopt;
  }
  if (pid == 0) {
    ::close(fds[0]);
    RunChild(fds[1], parent, solve);
  }
  ::close(fds[1]);
  std::string bytes;
  char buffer[1 << 16];
  bool told_child = false;
  for (;;) {
    // Ctrl-C at a terminal reaches the child too, a SIGINT sent to this process alone does
    // not: pass it on, so that the child's Ipopt stops at its next iteration as ours would.
    if (!told_child && interrupted && interrupted->load()) {
      ::kill(pid, SIGINT);
      told_child = true;
    }
    pollfd readable{fds[0], POLLIN, 0};
    const int ready = ::poll(&readable, 1, 100);  // ms: how soon an interruption is passed on
    if (ready == 0 || (ready < 0 && errno == EINTR)) continue;
    const ssize_t k = ready < 0 ? -1 : ::read(fds[0], buffer, sizeof(buffer));
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) break;
    bytes.append(buffer, static_cast<std::size_t>(k));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0) || bytes.empty()) {
    const std::string how = WIFSIGNALED(status) ? "was ended by signal " + std::to_string(WTERMSIG(status))
                                                : "ended with exit code " + std::to_string(WEXITSTATUS(status));
    throw SolverFailure("the process solving a design start " + how + " before reporting");
  }
  ByteReader r{bytes};
  const auto tag = r.Get<std::int32_t>();
  if (tag != kOutcome) {
    const std::string message = r.GetString();
    switch (tag) {
      case kSolverFailure: throw SolverFailure(message);
      case kInputError: throw InputError("", "", message);
      case kOutOfMemory: throw std::bad_alloc();
      default: throw std::runtime_error(message);
    }
  }
  return bytes.substr(r.at);
}

std::optional<StartOutcome> SolveDesignNlpInChildProcess(const Robot& robot, const DesignOptions& options,
                                                         const std::vector<PlanPose>& start,
                                                         const std::vector<double>* widening) {
  const std::optional<std::string> bytes =
      RunInChildProcess([&] { return Encode(SolveDesignNlp(robot, options, start, widening)); }, options.interrupted);
  if (!bytes) return std::nullopt;
  return Decode(*bytes);
}

}  // namespace cablecal::internal
