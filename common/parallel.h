// ParallelFor: an OpenMP loop that an exception can leave. An exception escaping an OpenMP
// region ends the process (std::terminate: "what(): std::bad_alloc", exit 134); here the
// first one is kept, the remaining iterations are skipped, and it is rethrown on the calling
// thread once the loop is over, so running out of memory in a parallel loop is the usual
// exit-2 message like anywhere else. Header-only: the including library links OpenMP.
#pragma once

#include <atomic>
#include <exception>
#include <mutex>

namespace cablecal {

template <typename Body>
void ParallelFor(long count, int chunk, const Body& body) {
  std::exception_ptr first;
  std::mutex mutex;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic, chunk)
  for (long k = 0; k < count; ++k) {
    if (failed.load(std::memory_order_relaxed)) continue;
    try {
      body(k);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(mutex);
      if (!first) first = std::current_exception();
      failed = true;
    }
  }
  if (first) std::rethrow_exception(first);
}

}  // namespace cablecal
