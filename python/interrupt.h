// Long calls with the GIL released and Ctrl-C honoured: the design and the Monte Carlo run on a
// worker thread while Python's thread waits, so that a notebook's interrupt button or a progress
// callback is heard during a solve that takes minutes.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <utility>

namespace cablecal::python {

// Runs `work` on a worker thread while this (Python's) thread waits without the GIL, checking
// for signals every 50 ms and calling `tick` (with the GIL, on this thread: Python callbacks run
// here, never on the worker). Ctrl-C, or an exception from `tick`, sets `stop` (which the
// work's solver polls) and, once `work` has returned, is raised; else `work`'s exception is.
void RunInterruptible(std::atomic<bool>& stop, const std::function<void()>& work, const std::function<void()>& tick);

// f's result, by RunInterruptible: no partial result comes back from an interrupted call.
template <typename F>
auto Interruptible(std::atomic<bool>& stop, F&& f, const std::function<void()>& tick = {}) -> decltype(f()) {
  std::optional<decltype(f())> result;
  RunInterruptible(stop, [&] { result.emplace(f()); }, tick);
  return std::move(*result);
}

}  // namespace cablecal::python
