// Counts heap allocations made by the current thread, by replacing the global operator new
// (Drake's LimitMalloc idea). Include it in exactly one translation unit of a test executable.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace rigidtouch::testing {

/// Allocations made by the calling thread since it started.
inline thread_local std::uint64_t thread_allocations = 0;

}  // namespace rigidtouch::testing

// gcc cannot see that these new and delete replacements pair malloc with free
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t size) {
  ++rigidtouch::testing::thread_allocations;
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}

void* operator new[](std::size_t size) {
  ++rigidtouch::testing::thread_allocations;
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}

void operator delete(void* memory) noexcept {
  std::free(memory);
}
void operator delete[](void* memory) noexcept {
  std::free(memory);
}
void operator delete(void* memory, std::size_t) noexcept {
  std::free(memory);
}
void operator delete[](void* memory, std::size_t) noexcept {
  std::free(memory);
}

#pragma GCC diagnostic pop
