// The worker thread and the wait of Python's thread behind Interruptible (interrupt.h).
#include "python/interrupt.h"

#include <pybind11/pybind11.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace py = pybind11;

namespace cablecal::python {

void RunInterruptible(std::atomic<bool>& stop, const std::function<void()>& work, const std::function<void()>& tick) {
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false;
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex);
    done = true;
    cv.notify_all();
  });
  std::optional<py::error_already_set> interrupt;
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(mutex);
      if (cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) break;
    }
    if (interrupt) continue;
    if (PyErr_CheckSignals() != 0) {
      interrupt.emplace();  // takes the pending KeyboardInterrupt
      stop = true;
      continue;
    }
    if (tick) {
      try {
        tick();
      } catch (py::error_already_set& e) {
        interrupt.emplace(std::move(e));
        stop = true;
      }
    }
  }
  worker.join();
  if (interrupt) throw std::move(*interrupt);
  if (error) std::rethrow_exception(error);
}

}  // namespace cablecal::python
