// What the forearm HIL tests share: where runs write, the run every test starts from (Two-stage
// or another strategy at 1 Hz, the demo's mismatch and noise), and the checks that every run's
// programs ended cleanly and wrote complete logs.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "hil_run.hpp"

namespace hmpc::hil::test {

inline std::string work_dir() {
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp ? tmp : "/tmp") + "/hmpc-forearm-hil-test";
}

inline HilRunSpec spec(forearm_protocol::Strategy strategy, const std::string& name) {
  HilRunSpec s;
  s.strategy = strategy;
  s.target.frequency_hz = 1.0;
  s.noise_scale = 1;
  s.seed = 1;
  s.mismatch = kDemoMismatch;
  s.directory = work_dir() + "/" + name;
  return s;
}

inline std::size_t lines_of(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// Every program finished cleanly and wrote all it should: one plant log row per simulated
// millisecond, one host row per SolveTelemetry report, the joint within the stops.
inline void expect_intact(const HilRunResult& r, const HilRunSpec& s) {
  ASSERT_TRUE(r.ok) << r.error;
  const double steps = r.number(r.plant, "steps");
  EXPECT_EQ(steps, std::round((s.run_at_s + s.run_for_s + s.settle_s) * 1e3));
  EXPECT_EQ(double(lines_of(s.directory + "/plant.csv")), steps + 1);  // with the header
  EXPECT_EQ(double(lines_of(s.directory + "/host.csv")), r.number(r.host, "telemetry_frames") + 1);
  EXPECT_TRUE(r.within_stops) << "theta range [" << r.theta_min << ", " << r.theta_max << "]";
  EXPECT_EQ(r.number(r.board, "heap_allocations_in_loop"), 0);
}

}  // namespace hmpc::hil::test
