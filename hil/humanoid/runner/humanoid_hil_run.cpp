#include "humanoid_hil_run.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "hmpc/platform/linux/candump_log.hpp"
#include "hmpc/platform/linux/child_process.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace hmpc::hil {

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::platform::Child;

// Lock-step runs take what the guest needs for the plant, the boards and the host's solves:
// about 15 s per simulated second in a QEMU guest without KVM, twice that as a margin.
constexpr double kWallPerSimulatedS = 30;
// Where the plant starts, which the boards take as their zero posture (the plant's default).
constexpr double kStartHeight = 0.85;
constexpr std::uint32_t kBitrate = 1'000'000;  // both buses

std::string zero_posture(int board) {
  const hm::BasicState<0> start = hm::standing_stance(hm::Parameters{}, kStartHeight);
  std::string out;
  for (int c = 0; c < hm::kJointsPerBoard; ++c) {
    out += (c ? "," : "") + std::to_string(start.q[7 + hm::joint_of(board, c)]);
  }
  return out;
}

using Row = std::vector<std::string>;

// A CSV file's rows after its header, split at commas.
std::vector<Row> read_csv(const std::string& path) {
  std::istringstream in(hmpc::platform::read_file(path));
  std::vector<Row> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    Row row;
    std::stringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) row.push_back(field);
    rows.push_back(row);
  }
  return rows;
}

double number(const Row& row, std::size_t i) {
  return i < row.size() ? std::strtod(row[i].c_str(), nullptr) : NAN;
}

// The frames a candump -l log holds.
std::size_t frames_in(const std::string& path) {
  std::istringstream in(hmpc::platform::read_file(path));
  std::size_t n = 0;
  std::string line, interface;
  while (std::getline(in, line)) {
    double t = 0;
    hmpc::platform::CanFrame f{};
    if (hmpc::platform::read_candump_line(line, t, interface, f)) ++n;
  }
  return n;
}

}  // namespace

HumanoidHilRun run_humanoid_hil(const HumanoidHilConfig& config) {
  HumanoidHilRun r;
  r.dir = config.dir + "/";
  std::error_code ignored;
  std::filesystem::remove_all(r.dir, ignored);
  std::filesystem::create_directories(r.dir, ignored);
  std::vector<Child> boards(hm::kLegBoards);
  for (int b = 0; b < hm::kLegBoards; ++b) {
    const std::vector<std::string> args{
        "--lockstep", "--interface",     "vcan0",          "--io-interface", "vcan1",
        "--node",     std::to_string(b), "--humanoid-leg", "--zero-posture", zero_posture(b)};
    if (!boards[std::size_t(b)].start(HMPC_JOINT_BOARD_PROGRAM, args,
                                      r.dir + "board" + std::to_string(b) + ".out", r.error) ||
        !boards[std::size_t(b)].await_output(": ready", 30)) {
      r.error = "board " + std::to_string(b) + " did not start: " + r.error +
                boards[std::size_t(b)].errors();
      return r;
    }
  }
  std::vector<std::string> host_args{"--lockstep",
                                     "--io-interface",
                                     "vcan1",
                                     "--duration",
                                     std::to_string(config.seconds),
                                     "--hold-seconds",
                                     std::to_string(config.hold_seconds),
                                     "--solve-time",
                                     "model",
                                     "--log-dir",
                                     r.dir};
  host_args.insert(host_args.end(), config.host_args.begin(), config.host_args.end());
  Child host, plant;
  if (!host.start(HMPC_HUMANOID_HOST_PROGRAM, host_args, r.dir + "host.out", r.error) ||
      !host.await_output(": ready", 60)) {
    r.error = "the host did not start: " + r.error + host.errors();
    return r;
  }
  if (!plant.start(HMPC_HUMANOID_PLANT_PROGRAM,
                   {"--lockstep", "--wait-host", "--duration", std::to_string(config.seconds),
                    "--start-height", std::to_string(kStartHeight), "--log", r.dir + "plant.csv"},
                   r.dir + "plant.out", r.error)) {
    return r;
  }
  const int plant_status = plant.wait(60 + kWallPerSimulatedS * config.seconds);
  const int host_status = host.wait(60);
  int board_status = 0;
  for (Child& b : boards) board_status |= b.stop(10);
  r.plant = hmpc::platform::parse_summary(plant.output());
  r.host = hmpc::platform::parse_summary(host.output());
  for (const Child& b : boards) r.boards.push_back(hmpc::platform::parse_summary(b.output()));
  if (plant_status != 0 || host_status != 0 || board_status != 0) {
    r.error = "exit status plant " + std::to_string(plant_status) + ", host " +
              std::to_string(host_status) + ", boards " + std::to_string(board_status) +
              "; plant said: " + plant.errors() + " host said: " + host.errors();
    return r;
  }
  r.ok = true;
  return r;
}

bool figures_of(const HumanoidHilRun& run, HumanoidHilFigures& out, std::string& error) {
  out = {};
  // solves.csv: tick, motion_time_s, wall_ms, charged_ms, effective_tick, upper_iterations,
  // fast_iterations, usable, estimate_tick.
  const std::vector<Row> solves = read_csv(run.dir + "solves.csv");
  // estimate.csv: time_s, phase, x, y, z, qw, qx, qy, qz, vx, vy, vz (world), ...
  const std::vector<Row> estimate = read_csv(run.dir + "estimate.csv");
  // plant.csv: time_s, x, y, z, qw, qx, qy, qz, 8 joints, wx, wy, wz, vx, vy, vz (torso), ...
  const std::vector<Row> plant = read_csv(run.dir + "plant.csv");
  if (solves.empty() || estimate.empty() || plant.empty()) {
    error = "the run logged no solve, estimate or plant state";
    return false;
  }
  const double period_ms = 12;  // the upper layer's sampling (Sec. 2.7.3)
  const std::uint32_t reference_period =
      jp::frame_spec(jp::FrameType::kTorqueReference).cycle_time_ms;
  std::vector<int> latency;
  int over = 0;
  for (const Row& s : solves) {
    const double charged = number(s, 3);
    ++out.solves;
    out.largest_solve_ms = std::max(out.largest_solve_ms, charged);
    over += charged > period_ms ? 1 : 0;
    const auto effective = std::uint32_t(number(s, 4)), from = std::uint32_t(number(s, 8));
    // The host sends references on the ticks that are multiples of their period.
    const std::uint32_t sent =
        (effective + reference_period - 1) / reference_period * reference_period;
    latency.push_back(int(sent - from));
  }
  out.share_over_period = double(over) / out.solves;
  std::sort(latency.begin(), latency.end());
  out.latency_min = latency.front();
  out.latency_max = latency.back();
  out.latency_median = latency[latency.size() / 2];

  // The truth by millisecond.
  std::map<long, const Row*> truth;
  for (const Row& p : plant) truth[std::lround(number(p, 0) * 1e3)] = &p;
  double h2 = 0, v2 = 0, t2 = 0;
  int n = 0;
  for (const Row& e : estimate) {
    if (e.size() < 12 || e[1] != "mpc") continue;
    const double t = number(e, 0);
    if (n == 0) out.mpc_start_s = t;
    const auto it = truth.find(std::lround(t * 1e3));
    if (it == truth.end()) continue;
    const Row& p = *it->second;
    const Eigen::Quaterniond qe(number(e, 5), number(e, 6), number(e, 7), number(e, 8));
    const Eigen::Quaterniond qt(number(p, 4), number(p, 5), number(p, 6), number(p, 7));
    const Eigen::Vector3d ve(number(e, 9), number(e, 10), number(e, 11));
    const std::size_t v = 8 + hm::kJoints + 3;  // the torso's linear velocity, torso axes
    const Eigen::Vector3d vt =
        qt.normalized() * Eigen::Vector3d(number(p, v), number(p, v + 1), number(p, v + 2));
    const double dz = number(e, 4) - number(p, 3);
    h2 += dz * dz;
    v2 += (ve - vt).head<2>().squaredNorm();
    const double cosine = (qe.normalized() * Eigen::Vector3d::UnitZ())
                              .dot(qt.normalized() * Eigen::Vector3d::UnitZ());
    const double tilt = std::acos(std::clamp(cosine, -1.0, 1.0));
    t2 += tilt * tilt;
    ++n;
  }
  if (n == 0) {
    error = "the MPC never ran, or the plant's log does not cover it";
    return false;
  }
  out.height_rms = std::sqrt(h2 / n);
  bool first = true;
  Eigen::Vector3d hip0 = Eigen::Vector3d::Zero();
  for (const Row& p : plant) {
    if (number(p, 0) < out.mpc_start_s) continue;
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(number(p, 4), number(p, 5), number(p, 6), number(p, 7)).normalized();
    const Eigen::Vector3d hip =
        Eigen::Vector3d(number(p, 1), number(p, 2), number(p, 3)) + q * hm::kBasePoint;
    if (first) {
      hip0 = hip;
      out.min_height = number(p, 3);
      first = false;
    }
    out.hip_drift = std::max(out.hip_drift, (hip - hip0).head<2>().norm());
    const double up = (q * Eigen::Vector3d::UnitZ()).z();
    out.max_tilt = std::max(out.max_tilt, std::acos(std::clamp(up, -1.0, 1.0)));
    out.min_height = std::min(out.min_height, number(p, 3));
  }
  out.horizontal_velocity_rms = std::sqrt(v2 / n);
  out.tilt_rms = std::sqrt(t2 / n);

  const double simulated = hmpc::platform::summary_number(run.plant, "sim_seconds");
  const double wall = hmpc::platform::summary_number(run.plant, "wall_seconds");
  if (!(simulated > 0) || !(wall > 0)) {
    error = "the plant's summary has no simulated or wall time";
    return false;
  }
  const double bits = double(protocol::kWorstCaseFrameBits) / (simulated * kBitrate);
  out.robot_bus_load = double(frames_in(run.dir + "robot_bus.log")) * bits;
  out.io_bus_load = double(frames_in(run.dir + "io_bus.log")) * bits;
  out.robot_bus_design_load = jp::bus_load(jp::Bus::kRobot, kBitrate, jp::BusLayout{});
  out.io_bus_design_load = jp::bus_load(jp::Bus::kIo, kBitrate, jp::BusLayout{});
  out.lockstep_speed = simulated / wall;
  return true;
}

}  // namespace hmpc::hil
