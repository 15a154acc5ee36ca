// Host control loops do not allocate: every heap entry point reachable from our code is
// counted (operator new replaced, malloc family wrapped at link time) while the four
// Sec. 2.4 MPCs run closed loop. A positive control proves the counter sees allocations.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
}
}  // namespace

extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
void* __real_aligned_alloc(std::size_t, std::size_t);
void* __wrap_malloc(std::size_t n) { count(); return __real_malloc(n); }
void* __wrap_calloc(std::size_t a, std::size_t b) { count(); return __real_calloc(a, b); }
void* __wrap_realloc(void* p, std::size_t n) { count(); return __real_realloc(p, n); }
void* __wrap_aligned_alloc(std::size_t a, std::size_t n) { count(); return __real_aligned_alloc(a, n); }
}

void* operator new(std::size_t n) {
  count();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  count();
  const std::size_t align = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(align, (n + align - 1) / align * align)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace {

using namespace hmpc::sec24;
using M = Mpcs<double>;

template <class Mpc>
long allocations_in_closed_loop(Mpc& mpc) {
  const Parameters<double> p;
  Vector2<double> x = initial_state<double>();
  mpc.initialize(x, kOfflineIterations);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 60; ++k) {
    const Vector2<double> u = mpc.update(x);
    x = integrate_plant(p, x, u, kSamplingPeriod);
  }
  g_counting = false;
  return g_allocations.load();
}

TEST(HostAllocation, CounterSeesAllocations) {
  g_allocations = 0;
  g_counting = true;
  auto v = std::make_unique<std::vector<int>>(100);
  void* raw = std::malloc(16);
  g_counting = false;
  std::free(raw);
  EXPECT_GE(g_allocations.load(), 3);
}

TEST(HostAllocation, MpcLoopsDoNotAllocate) {
  auto fine = std::make_unique<M::Fine>(M::fine());
  auto coarse = std::make_unique<M::Coarse>(M::coarse());
  auto coarse_fast = std::make_unique<M::CoarseFast>(M::coarse_fast());
  auto slow_fast = std::make_unique<M::SlowFast>(M::slow_fast());
  EXPECT_EQ(allocations_in_closed_loop(*fine), 0);
  EXPECT_EQ(allocations_in_closed_loop(*coarse), 0);
  EXPECT_EQ(allocations_in_closed_loop(*coarse_fast), 0);
  EXPECT_EQ(allocations_in_closed_loop(*slow_fast), 0);
}

}  // namespace
