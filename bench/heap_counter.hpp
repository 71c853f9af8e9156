// Counts heap allocations in a bench executable: malloc calls between start_counting() and
// stop_counting(). Under AddressSanitizer (bench/sanitize.sh), which owns malloc, its allocation
// hook counts; with glibc, malloc is interposed for the executable and the libraries it loads
// (operator new, Eigen and libpinocchio all end there). Elsewhere stop_counting() returns -1 (not
// counted). Include it in one translation unit per executable.
#pragma once

#include <cstddef>

#if defined(__SANITIZE_ADDRESS__)
#define ADPARM_COUNT_MALLOC 1
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*,
                                                                             std::size_t),
                                                         void (*free_hook)(const volatile void*));
namespace {
bool counting = false;
long allocations = 0;
void count_malloc(const volatile void*, std::size_t) {
  if (counting) ++allocations;
}
void ignore_free(const volatile void*) {}
const int hooks_installed = __sanitizer_install_malloc_and_free_hooks(count_malloc, ignore_free);
}  // namespace
#elif defined(__GLIBC__)
#define ADPARM_COUNT_MALLOC 1
extern "C" void* __libc_malloc(std::size_t size);
namespace {
bool counting = false;
long allocations = 0;
}  // namespace
extern "C" void* malloc(std::size_t size) {
  if (counting) ++allocations;
  return __libc_malloc(size);
}
#endif

namespace {

void start_counting() {
#ifdef ADPARM_COUNT_MALLOC
  allocations = 0;
  counting = true;
#endif
}

// The allocations since start_counting(), or -1 where they are not counted.
long stop_counting() {
#ifdef ADPARM_COUNT_MALLOC
  counting = false;
  return allocations;
#else
  return -1;
#endif
}

}  // namespace
