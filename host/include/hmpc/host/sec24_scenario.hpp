// Closed-loop reproduction of the thesis's numerical example (Sec. 2.4): each MPC drives the
// plant of Eq. 2.37 for 0.4 s at 1 ms sampling; every solve is timed and logged.
#pragma once

#include <string>
#include <vector>

namespace hmpc::sec24 {

enum class Method { kFine, kCoarse, kSlowFast, kCoarseFast };
constexpr Method kAllMethods[] = {Method::kFine, Method::kCoarse, Method::kSlowFast,
                                  Method::kCoarseFast};
const char* to_string(Method method);

struct StepRecord {
  double time = 0;
  double y = 0, z = 0;    // plant state at the start of the sample
  double u1 = 0, u2 = 0;  // applied input
  double solve_seconds = 0;
  int iterations = 0;  // iLQR iterations of all layers in this update
  bool plan_usable = true;
};

struct RunResult {
  Method method = Method::kFine;
  std::vector<StepRecord> steps;
  double final_y = 0, final_z = 0;
  double accumulated_cost = 0;  // sum over samples of Eq. 2.38's stage cost times Delta t
  double max_solve_seconds = 0;
  double median_solve_seconds = 0;
  int unusable_solves = 0;  // solves whose plan could not be applied
};

struct RunOptions {
  int samples = 400;  // Sec. 2.4.1: 0.4 s at 1 ms
};

// Runs one method closed loop. The control loop itself does not allocate: the log is
// reserved before the first sample.
RunResult run(Method method, const RunOptions& options = {});

// CSV with one row per sample: method,time,y,z,u1,u2,solve_ms,iterations.
void write_trajectories_csv(const std::vector<RunResult>& runs, const std::string& path);

}  // namespace hmpc::sec24
