#include <gtest/gtest.h>
#include <cstdio>
#include "hmpc/host/sec24_scenario.hpp"
using namespace hmpc::sec24;
TEST(Sec24, Explore) {
  for (Method m : kAllMethods) {
    auto r = run(m);
    std::printf("%s y=%f z=%f J=%f max=%f med=%f unusable=%d\n", to_string(m), r.final_y, r.final_z, r.accumulated_cost, r.max_solve_seconds*1e3, r.median_solve_seconds*1e3, r.unusable_solves);
  }
}
