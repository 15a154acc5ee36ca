// The linker sends the program's calls to malloc & co. to the __wrap_ functions below (the
// hmpc::heap_monitor target carries the --wrap options). Calls made inside shared libraries bypass
// --wrap, libstdc++'s operator new among them, so operator new is replaced here to allocate through
// the wrapped malloc.
#include "hmpc/platform/linux/heap_monitor.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {
std::atomic<bool> g_armed{false};
std::atomic<std::uint64_t> g_allocations{0};

void note_allocation() {
  if (g_armed.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}
}  // namespace

namespace hmpc::platform::heap_monitor {
void arm() { g_armed.store(true); }
void disarm() { g_armed.store(false); }
std::uint64_t allocations() { return g_allocations.load(); }
}  // namespace hmpc::platform::heap_monitor

// The linker's --wrap=SYMBOL sends calls to SYMBOL to __wrap_SYMBOL and __real_SYMBOL to the
// original: the reserved names are its interface.
// NOLINTBEGIN(bugprone-reserved-identifier)
extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
void* __real_aligned_alloc(std::size_t, std::size_t);
int __real_posix_memalign(void**, std::size_t, std::size_t);

void* __wrap_malloc(std::size_t size) {
  note_allocation();
  return __real_malloc(size);
}
void* __wrap_calloc(std::size_t count, std::size_t size) {
  note_allocation();
  return __real_calloc(count, size);
}
void* __wrap_realloc(void* pointer, std::size_t size) {
  note_allocation();
  return __real_realloc(pointer, size);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_aligned_alloc(alignment, size);
}
int __wrap_posix_memalign(void** pointer, std::size_t alignment, std::size_t size) {
  note_allocation();
  return __real_posix_memalign(pointer, alignment, size);
}
// NOLINTEND(bugprone-reserved-identifier)
}

#if defined(__SANITIZE_THREAD__)
#define HMPC_SANITIZER_OWNS_NEW 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HMPC_SANITIZER_OWNS_NEW 1
#endif
#endif

#ifdef HMPC_SANITIZER_OWNS_NEW
// ThreadSanitizer links its own operator new and delete (it must see every allocation), so they
// cannot be replaced; the linker wraps the program's calls to them instead (the mangled names in
// common/CMakeLists.txt). Calls made inside libstdc++ itself go uncounted in this build only.
// NOLINTBEGIN(bugprone-reserved-identifier)
extern "C" {
void* __real__Znwm(std::size_t);
void* __real__Znam(std::size_t);
void* __real__ZnwmSt11align_val_t(std::size_t, std::align_val_t);
void* __real__ZnamSt11align_val_t(std::size_t, std::align_val_t);

void* __wrap__Znwm(std::size_t size) {
  note_allocation();
  return __real__Znwm(size);
}
void* __wrap__Znam(std::size_t size) {
  note_allocation();
  return __real__Znam(size);
}
void* __wrap__ZnwmSt11align_val_t(std::size_t size, std::align_val_t alignment) {
  note_allocation();
  return __real__ZnwmSt11align_val_t(size, alignment);
}
void* __wrap__ZnamSt11align_val_t(std::size_t size, std::align_val_t alignment) {
  note_allocation();
  return __real__ZnamSt11align_val_t(size, alignment);
}
}
// NOLINTEND(bugprone-reserved-identifier)
#else
void* operator new(std::size_t size) {
  if (void* p = std::malloc(size != 0 ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t alignment) {
  const std::size_t a = static_cast<std::size_t>(alignment);
  // aligned_alloc wants a size that is a multiple of the alignment.
  const std::size_t rounded = (size + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, rounded != 0 ? rounded : a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return operator new(size, alignment);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#endif
