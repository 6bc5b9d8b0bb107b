// Internal to design/: Ipopt solves of different starts at once, each in a child process
// (Debian's MUMPS, Ipopt's linear solver, is not thread-safe within one process).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "design/ipopt_nlp.h"

namespace cablecal::internal {

// A solve's outcome as bytes, for the pipe from a child: values appended as they are in memory
// (the child is a fork of the reader: same machine, same layout).
struct ByteWriter {
  std::string bytes;
  template <typename T>
  void Put(const T& value) {
    bytes.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void PutString(const std::string& s) {
    Put(static_cast<std::int64_t>(s.size()));
    bytes += s;
  }
};

struct ByteReader {
  const std::string& bytes;
  std::size_t at = 0;
  template <typename T>
  T Get() {
    CABLECAL_CHECK(at + sizeof(T) <= bytes.size(), "a design child's message is whole");
    T value;
    std::memcpy(&value, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return value;
  }
  std::string GetString() {
    const auto size = static_cast<std::size_t>(Get<std::int64_t>());
    CABLECAL_CHECK(at + size <= bytes.size(), "a design child's message is whole");
    std::string s = bytes.substr(at, size);
    at += size;
    return s;
  }
};

// `solve` run in a forked child, the bytes it returns sent back through a pipe: the same
// bytes, bit for bit, as in-process (same code, same inputs). Errors come back as the same
// kinds (SolverFailure, InputError, std::bad_alloc); a child that dies before reporting is a
// SolverFailure. Set, `interrupted` is passed on to the child as SIGINT. std::nullopt when no
// child process could be started: solve in-process.
std::optional<std::string> RunInChildProcess(const std::function<std::string()>& solve,
                                             const std::atomic<bool>* interrupted);

// SolveDesignNlp in a child process (RunInChildProcess).
std::optional<StartOutcome> SolveDesignNlpInChildProcess(const Robot& robot, const DesignOptions& options,
                                                         const std::vector<PlanPose>& start,
                                                         const std::vector<double>* widening);

}  // namespace cablecal::internal
