// The C allocator interposed for test::LimitMalloc (limit_malloc.h): every test executable links
// this file once; outside a live guard each call only forwards to glibc's allocator.
#include "limit_malloc.h"

namespace rigidtouch::test {

void ProbeAllocation() {
  void* volatile probe = std::malloc(64);
  std::free(probe);
}

}  // namespace rigidtouch::test

#if RIGIDTOUCH_MALLOC_COUNTING
extern "C" {
void* __libc_malloc(std::size_t) noexcept;
void* __libc_calloc(std::size_t, std::size_t) noexcept;
void* __libc_realloc(void*, std::size_t) noexcept;
void* __libc_memalign(std::size_t, std::size_t) noexcept;
void __libc_free(void*) noexcept;

void* malloc(std::size_t n) noexcept {
  rigidtouch::test::internal::CountAllocation();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t s) noexcept {
  rigidtouch::test::internal::CountAllocation();
  return __libc_calloc(n, s);
}
void* realloc(void* p, std::size_t n) noexcept {
  rigidtouch::test::internal::CountAllocation();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t a, std::size_t n) noexcept {
  rigidtouch::test::internal::CountAllocation();
  return __libc_memalign(a, n);
}
void* aligned_alloc(std::size_t a, std::size_t n) noexcept {
  rigidtouch::test::internal::CountAllocation();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, std::size_t a, std::size_t n) noexcept {
  rigidtouch::test::internal::CountAllocation();
  *p = __libc_memalign(a, n);
  return *p ? 0 : 12;  // ENOMEM
}
void free(void* p) noexcept {
  __libc_free(p);
}
}
#endif
