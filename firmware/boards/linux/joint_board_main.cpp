// hmpc-joint-board: the hydraulic joint board (firmware/app/joint_board.hpp) on Linux over
// SocketCAN, in the board runtime of board_main.hpp (real time or lock-step). In the HIL it
// hears both the robot bus's frames (host) and the I/O bus's (plant) on one interface, or the
// I/O bus's on the interface the plant node bridges (see hil/joint_bench). On SIGINT, SIGTERM or
// the end of --duration it sends a last ValveDrive with the valves centred and prints a summary
// of key=value pairs. The board lives in static storage; once the loop runs nothing is
// allocated (counted and reported as heap_allocations_in_loop).
#include <cstdint>
#include <cstdio>
#include <string>

#include "board_main.hpp"
#include "humanoid_leg_board.hpp"
#include "joint_board.hpp"
#include "joint_options.hpp"

namespace {

namespace proto = hmpc::joint_protocol;
using Board = hmpc::firmware::JointBoard<double>;

constexpr const char* kProgram = "hmpc-joint-board";

struct JointSupport {
  using Board = ::Board;
  using Description = proto::Description;
  using SafeMessage = proto::ValveDrive;
  struct Row {
    std::uint32_t tick;
    float wall_time_s;  // since the control loop started
    proto::BoardMode mode;
    std::uint16_t faults;
    float u[proto::kMaxJointsPerBoard];    // valve commands applied this tick
    float tau[proto::kMaxJointsPerBoard];  // N·m, the references the loops follow
    std::uint32_t heartbeat_age, sensor_age;
  };
  static constexpr const char* kCsvHeader =
      "tick,wall_time_s,mode,faults,u_0,u_1,u_2,u_3,tau_ref_0,tau_ref_1,tau_ref_2,tau_ref_3,"
      "heartbeat_age,sensor_age";
  static Row log_row(const Board& b, float wall_time_s) {
    Row r{b.ticks(), wall_time_s, b.mode(), b.faults(), {}, {}, b.heartbeat_age(), b.sensor_age()};
    for (std::size_t j = 0; j < proto::kMaxJointsPerBoard; ++j) {
      r.u[j] = float(b.valve_commands()[j]);
      r.tau[j] = float(b.applied_references()[j]);
    }
    return r;
  }
  static void write_row(std::FILE* file, const Row& r) {
    std::fprintf(file, "%u,%.6f,%s,%u,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%.3f,%.3f,%u,%u\n", r.tick,
                 double(r.wall_time_s),
                 proto::value_name(proto::kBoardModeValues, std::uint32_t(r.mode)),
                 unsigned(r.faults), double(r.u[0]), double(r.u[1]), double(r.u[2]), double(r.u[3]),
                 double(r.tau[0]), double(r.tau[1]), double(r.tau[2]), double(r.tau[3]),
                 r.heartbeat_age, r.sensor_age);
  }
  static bool work_due(const Board&) { return false; }  // the loops run inside the tick
  static void run_work(Board&) {}
  // Late ticks run their control steps late: reported in BoardStatus's overrun bit.
  static void on_late_ticks(Board& b) { b.note_overrun(); }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace hmpc::linux_board;
  JointOptions options;
  std::string error;
  const auto outcome = parse_joint_options(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_joint_usage);
  }

  Board::Config config;
  config.node = options.board.node;
  config.joints = std::size_t(options.joints);
  config.control_period_ticks = int(options.control_period_ms);
  config.require_zeroing = !options.stored_offsets;
  if (options.humanoid_leg) {
    std::array<double, hmpc::humanoid::kJointsPerLeg> zero_posture{};
    for (std::size_t j = 0; j < zero_posture.size(); ++j) zero_posture[j] = options.zero_posture[j];
    hmpc::firmware::configure_humanoid_leg(config, zero_posture);
  } else {
    for (std::size_t j = 0; j < config.joints; ++j) {
      config.joint[j].zero_posture = options.zero_posture[j];
    }
  }
  for (auto& joint : config.joint) {
    joint.actuator.bulk_modulus *= options.believed_actuator_scale;
    joint.actuator.valve_flow_gain *= options.believed_actuator_scale;
  }
  config.tune_torque_loops();
  if (!options.load_velocity_feedback) {
    for (auto& joint : config.joint) joint.torque_loop.load_velocity_gain = 0;
  }
  if (const char* invalid = config.check()) {
    std::fprintf(stderr, "%s: invalid configuration: %s\n", kProgram, invalid);
    return 2;
  }
  static Board board(config);
  char mode_text[160];
  std::snprintf(mode_text, sizeof mode_text,
                ", %zu joint(s)%s, %ld ms control period, %s, believed actuator x%.2f",
                config.joints, options.humanoid_leg ? " of a humanoid leg" : "",
                options.control_period_ms,
                options.load_velocity_feedback ? "PID with load-velocity feedback" : "plain PID",
                options.believed_actuator_scale);

  return run_board<JointSupport>(
      kProgram, options.board, board, proto::ValveDrive{}, mode_text, [&](const RunResult& r) {
        const LoopStats& stats = r.stats;
        const hmpc::firmware::JointBoardCounters c = board.counters();
        std::printf(
            "%s: summary ticks=%llu seconds=%.3f ticks_per_s=%.1f mode=%s faults=0x%04x "
            "control_steps=%u watchdog_trips=%u sensor_timeouts=%u refused_commands=%u "
            "refused_references=%u stale_references=%u estops=%u rejected_frames=%u "
            "dropped_frames=%u transmit_failures=%llu interface_down=%llu timer_overruns=%llu "
            "max_busy_ms=%.3f max_wakeup_latency_ms=%.3f heap_allocations_in_loop=%llu "
            "safe_outputs_sent=%d heartbeat_timeout_ticks=%d control_period_ticks=%d "
            "kp=%.6g ki=%.6g k_lv=%.6g\n",
            kProgram, static_cast<unsigned long long>(stats.ticks), r.elapsed_s,
            r.elapsed_s > 0 ? double(stats.ticks) / r.elapsed_s : 0.0,
            proto::value_name(proto::kBoardModeValues, std::uint32_t(board.mode())),
            unsigned(board.faults()), c.control_steps, c.watchdog_trips, c.sensor_timeouts,
            c.refused_commands, c.refused_references, c.stale_references, c.estops,
            board.rejects().total(), board.dropped_frames(),
            static_cast<unsigned long long>(stats.transmit_failures),
            static_cast<unsigned long long>(stats.interface_down),
            static_cast<unsigned long long>(stats.timer_overruns), stats.max_busy_s * 1e3,
            stats.max_wakeup_latency_s * 1e3,
            static_cast<unsigned long long>(r.heap_allocations_in_loop), r.safe_sent ? 1 : 0,
            config.heartbeat_timeout_ticks, config.control_period_ticks,
            board.config().joint[0].torque_loop.kp, board.config().joint[0].torque_loop.ki,
            board.config().joint[0].torque_loop.load_velocity_gain);
      });
}
