// Host control loops do not allocate: every heap entry point reachable from our code is
// counted (hmpc::heap_monitor: operator new replaced, malloc family wrapped at link time)
// while the four Sec. 2.4 MPCs run closed loop. A positive control proves the counter sees
// allocations.
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"

namespace {

using namespace hmpc::sec24;
using M = Mpcs<double>;
namespace heap_monitor = hmpc::platform::heap_monitor;

template <class Mpc>
long allocations_in_closed_loop(Mpc& mpc) {
  const Parameters<double> p;
  Vector2<double> x = initial_state<double>();
  mpc.initialize(x, kOfflineIterations);
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  for (int k = 0; k < 60; ++k) {
    const Vector2<double> u = mpc.update(x);
    x = integrate_plant(p, x, u, kSamplingPeriod);
  }
  heap_monitor::disarm();
  return static_cast<long>(heap_monitor::allocations() - before);
}

TEST(HostAllocation, CounterSeesAllocations) {
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  auto v = std::make_unique<std::vector<int>>(100);
  void* volatile raw = std::malloc(16);  // volatile: the compiler may not elide the pair
  heap_monitor::disarm();
  std::free(raw);
  EXPECT_GE(heap_monitor::allocations() - before, 3u);
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
