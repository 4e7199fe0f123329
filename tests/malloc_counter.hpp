#pragma once
// Counts heap allocations made through malloc, realloc and calloc, Eigen's included (it calls
// malloc, not operator new), so that a test can assert "allocation-free". Include it in ONE
// source file of a test executable: it replaces the C library's functions for that program.
// Only where the C library allows it (glibc) and not under a sanitizer (which owns malloc): then
// HAPSYN_COUNT_MALLOC is defined and g_mallocs counts; otherwise the tests that need it skip
// that assertion.
#include <atomic>
#include <cstddef>

// GCC names a sanitizer build by __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__, clang by
// __has_feature: either way the sanitizer's malloc must stay in place.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HAPSYN_MALLOC_OWNED_BY_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define HAPSYN_MALLOC_OWNED_BY_SANITIZER 1
#endif
#endif

#if defined(__GLIBC__) && !defined(HAPSYN_MALLOC_OWNED_BY_SANITIZER)
#define HAPSYN_COUNT_MALLOC 1
namespace {
std::atomic<long> g_mallocs{0};
}  // namespace
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* malloc(std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
extern "C" void* realloc(void* p, std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, size);
}
extern "C" void* calloc(std::size_t count, std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(count, size);
}
#endif
