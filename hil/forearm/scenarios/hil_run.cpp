#include "hil_run.hpp"

#include <signal.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hmpc/models/forearm_problems.hpp"
#include "hmpc/models/forearm_target_range.hpp"
#include "hmpc/platform/linux/child_process.hpp"

namespace hmpc::hil {
namespace {

namespace proto = forearm_protocol;
// Generous limits: under QEMU without KVM the three programs run ~10x slower than natively.
constexpr double kStartupS = 60;           // until the board and the host are listening
constexpr double kWallPerSimulatedS = 60;  // worst case wall seconds per simulated second
constexpr double kStopS = 30;              // for SIGTERM to end a program

std::string number_text(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// A log's header line, then one row per line by `parse(line, row)`.
template <class Row, class Parse>
bool read_log(const std::string& path, const char* what, std::vector<Row>& rows, std::string& error,
              Parse&& parse) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) {
    error = std::string(what) + " " + path + " is empty";
    return false;
  }
  while (std::getline(in, line)) {
    Row r{};
    if (!parse(line, r)) {
      error = std::string(what) + " " + path;
      error += ": malformed row '" + line + "'";
      return false;
    }
    rows.push_back(r);
  }
  return true;
}

std::string strategy_name(proto::Strategy s) {
  return proto::value_name(proto::kStrategyValues, std::uint32_t(s));
}

}  // namespace

bool read_plant_log(const std::string& path, std::vector<PlantRow>& rows, std::string& error) {
  return read_log(path, "plant log", rows, error, [](const std::string& line, PlantRow& r) {
    return std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r.time, &r.theta,
                       &r.theta_dot, &r.pressure_bar, &r.v_p, &r.v_m, &r.tau_p, &r.tau_m) == 8;
  });
}

bool read_board_log(const std::string& path, std::vector<BoardTickRow>& rows, std::string& error) {
  return read_log(path, "board log", rows, error, [](const std::string& line, BoardTickRow& r) {
    char mode[16] = {}, strategy[16] = {};
    double wall = 0;
    if (std::sscanf(line.c_str(), "%u,%lf,%15[^,],%u,%15[^,],%lf,%lf,%u,%u", &r.tick, &wall, mode,
                    &r.faults, strategy, &r.v_p, &r.v_m, &r.heartbeat_age, &r.sensor_age) != 9) {
      return false;
    }
    r.mode = mode;
    return true;
  });
}

double HilRunResult::number(const std::map<std::string, std::string>& summary,
                            const std::string& key) const {
  return hmpc::platform::summary_number(summary, key);
}

HilRunResult run_hil(const HilRunSpec& spec, const HilPrograms& programs) {
  HilRunResult result;
  std::error_code ec;
  std::filesystem::create_directories(spec.directory, ec);
  if (ec) {
    result.error = "cannot create " + spec.directory + ": " + ec.message();
    return result;
  }
  const std::string dir = spec.directory + "/";
  const double duration = spec.run_at_s + spec.run_for_s + spec.settle_s;
  // theta_d(t) on the run's clock: the sinusoid in closed form, as the host streams it; any
  // other shape from its points.
  trajectory::TargetSpec target = spec.target;
  target.duration_s = spec.run_for_s;
  std::vector<trajectory::TrajectoryPoint> points;
  std::string why;
  if (!trajectory::make_points(target, forearm::target_range(), trajectory::kMaxPoints, points,
                               why)) {
    result.error = "invalid target: " + why;
    return result;
  }
  trajectory::JointTrajectoryTarget target_points(points.size());
  target_points.assign(points.data(), points.size());
  const auto theta_d_at = [&](double t) {
    if (target.shape != trajectory::TargetShape::kSine) return target_points.position(t);
    return target.offset + target.amplitude * std::sin(2 * M_PI * target.frequency_hz * t);
  };

  const std::string node = std::to_string(spec.node);
  std::vector<std::string> board_args{"--lockstep", "--emulate-target", "cortex-m7", "--node", node,
                                      "--log",      dir + "board.csv"};
  if (spec.w_v > 0) {
    board_args.push_back("--w-v");
    board_args.push_back(number_text(spec.w_v));
  }
  board_args.insert(board_args.end(), spec.board_args.begin(), spec.board_args.end());
  std::vector<std::string> host_args{"--lockstep",
                                     "--node",
                                     node,
                                     "--run",
                                     strategy_name(spec.strategy),
                                     "--target",
                                     trajectory::shape_name(target.shape),
                                     "--frequency",
                                     number_text(target.frequency_hz),
                                     "--amplitude-deg",
                                     number_text(target.amplitude * 180 / M_PI),
                                     "--offset-deg",
                                     number_text(target.offset * 180 / M_PI),
                                     "--chirp-to",
                                     number_text(target.chirp_end_hz),
                                     "--step-at",
                                     number_text(target.step_at_s),
                                     "--step-rate-deg-s",
                                     number_text(target.step_rate * 180 / M_PI),
                                     "--run-at",
                                     number_text(spec.run_at_s),
                                     "--run-for",
                                     number_text(spec.run_for_s),
                                     "--log",
                                     dir + "host.csv"};
  if (target.shape == trajectory::TargetShape::kFile) {
    host_args.push_back("--target-file");
    host_args.push_back(target.file);
  }
  host_args.insert(host_args.end(), spec.host_args.begin(), spec.host_args.end());
  std::vector<std::string> plant_args{"--lockstep",
                                      "--node",
                                      node,
                                      "--wait-host",
                                      "--duration",
                                      number_text(duration),
                                      "--noise",
                                      number_text(spec.noise_scale),
                                      "--seed",
                                      std::to_string(spec.seed),
                                      "--mass-scale",
                                      number_text(spec.mismatch.mass_scale),
                                      "--friction-scale",
                                      number_text(spec.mismatch.friction_scale),
                                      "--pam-time-scale",
                                      number_text(spec.mismatch.pam_time_constant_scale),
                                      "--log",
                                      dir + "plant.csv"};
  plant_args.insert(plant_args.end(), spec.plant_args.begin(), spec.plant_args.end());

  platform::Child board, host, plant;
  if (!board.start(programs.board, board_args, dir + "board.out", result.error) ||
      !host.start(programs.host, host_args, dir + "host.out", result.error)) {
    return result;
  }
  if (!board.await_output(": ready", kStartupS) || !host.await_output(": ready", kStartupS)) {
    result.error = "board or host did not start: " + board.errors() + host.errors();
    return result;
  }
  if (!plant.start(programs.plant, plant_args, dir + "plant.out", result.error)) return result;
  const int plant_status = plant.wait(kStartupS + kWallPerSimulatedS * duration);
  const int host_status = host.stop(kStopS);
  const int board_status = board.stop(kStopS);
  result.board = platform::parse_summary(board.output());
  result.plant = platform::parse_summary(plant.output());
  result.host = platform::parse_summary(host.output());
  const int expected_host_status = spec.host_dies ? 128 + SIGKILL : 0;
  if (plant_status != 0 || host_status != expected_host_status || board_status != 0) {
    result.error = "exit status plant " + std::to_string(plant_status) + ", host " +
                   std::to_string(host_status) + ", board " + std::to_string(board_status) +
                   " (-1: timed out); plant said: " + plant.errors() +
                   " host said: " + host.errors() + " board said: " + board.errors();
    return result;
  }

  if (!read_plant_log(dir + "plant.csv", result.plant_log, result.error) ||
      !read_board_log(dir + "board.csv", result.board_log, result.error)) {
    return result;
  }
  const std::vector<PlantRow>& rows = result.plant_log;
  // A host that died left no summary: the run started where its script starts it.
  const double t0 = spec.host_dies ? spec.run_at_s : result.number(result.host, "run_start_s");
  if (!(t0 >= 0)) {
    result.error = "the host never started the run (run_start_s missing)";
    return result;
  }
  forearm::CostWeights<double> weights;
  if (spec.w_v > 0) weights.w_v = spec.w_v;
  const forearm::Parameters<double> model;
  const long first = std::lround(t0 * 1e3), periods = std::lround(spec.run_for_s / 0.004);
  int counted = 0;
  double squared_error = 0;
  result.theta_min = 1e9;
  result.theta_max = -1e9;
  for (const PlantRow& r : rows) {
    result.theta_min = std::min(result.theta_min, r.theta);
    result.theta_max = std::max(result.theta_max, r.theta);
  }
  // Row i holds the state at (i + 1) ms and the input applied during the millisecond before.
  for (long j = 0; j < periods; ++j) {
    const long ms = first + 4 * j;
    if (ms < 1 || ms >= long(rows.size())) break;
    const PlantRow& x = rows[std::size_t(ms - 1)];
    const PlantRow& u = rows[std::size_t(ms)];  // applied from ms to ms + 1
    const double t = 1e-3 * double(ms);
    const double theta_d = theta_d_at(t - t0);
    result.accumulated_cost +=
        forearm::tracking_cost(model, weights, x.theta, theta_d, x.pressure_bar, u.v_m, true)
            .value +
        weights.w_v * (u.v_m * u.v_m + u.v_p * u.v_p);
    squared_error += (x.theta - theta_d) * (x.theta - theta_d);
    ++counted;
  }
  if (counted < periods) {
    result.error = "the plant log covers " + std::to_string(counted) + " of " +
                   std::to_string(periods) + " control periods of the run";
    return result;
  }
  long torque_rows = 0;
  for (long ms = first; ms < first + 4 * periods && ms < long(rows.size()); ++ms, ++torque_rows) {
    result.mean_abs_pam_torque += std::abs(rows[std::size_t(ms)].tau_p);
    result.mean_abs_motor_torque += std::abs(rows[std::size_t(ms)].tau_m);
  }
  result.mean_abs_pam_torque /= double(torque_rows);
  result.mean_abs_motor_torque /= double(torque_rows);
  result.rms_error = std::sqrt(squared_error / counted);
  result.solve_time_max_us = result.number(result.host, "solve_time_max_us");
  result.solve_time_median_us = result.number(result.host, "solve_time_median_us");
  result.deadline_misses = result.number(result.board, "mpc_overruns");
  result.within_stops = result.number(result.plant, "within_stops") == 1;
  result.ok = true;
  return result;
}

HilPrograms HilPrograms::built() {
  return {HMPC_FOREARM_BOARD_PROGRAM, HMPC_FOREARM_PLANT_PROGRAM, HMPC_FOREARM_HOST_PROGRAM};
}

}  // namespace hmpc::hil
