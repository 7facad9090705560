// Replaces the global operator new and delete (every form, malloc/free on
// both sides, so that AddressSanitizer sees no allocation released by another
// allocator) to count heap allocations: for the tests that show an
// evaluation allocates nothing. Include it in exactly one source file of a
// test executable; it defines the operators there.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace fgcal_test {
/// Allocations by operator new (any form) since the program started.
inline std::atomic<long> heap_allocations{0};
}  // namespace fgcal_test

// GCC flags free() on memory from a replaced operator new as mismatched; here
// both sides are ours and use malloc/free, which is exactly what is intended.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  ++fgcal_test::heap_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  ++fgcal_test::heap_allocations;
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#pragma GCC diagnostic pop
