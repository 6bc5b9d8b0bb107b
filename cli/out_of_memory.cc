// The program's global operator new: the standard one (malloc, the new-handler, bad_alloc),
// except that a failure records the size asked for (common/error.h, FailedAllocationBytes),
// so that "out of memory" can say how much. Only the cablecal program replaces it; the
// libraries do not.
#include <cstdlib>
#include <new>

#include "common/error.h"

void* operator new(std::size_t bytes) {
  const std::size_t asked = bytes == 0 ? 1 : bytes;
  for (;;) {
    if (void* p = std::malloc(asked)) return p;
    if (std::new_handler handler = std::get_new_handler()) {
      handler();
      continue;
    }
    cablecal::FailedAllocationBytes().store(bytes);
    throw std::bad_alloc();
  }
}

void* operator new[](std::size_t bytes) { return ::operator new(bytes); }
// The nothrow forms too (std::stable_sort's buffer uses them): every replaced delete frees with
// free(), so every new that it may free must come from malloc (AddressSanitizer checks it).
void* operator new(std::size_t bytes, const std::nothrow_t&) noexcept {
  try {
    return ::operator new(bytes);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t bytes, const std::nothrow_t& tag) noexcept { return ::operator new(bytes, tag); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
