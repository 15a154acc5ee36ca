// hmpc-forearm-board: the forearm actuator board (firmware/app/forearm_board.hpp) on Linux over
// SocketCAN, in the board runtime of board_main.hpp (real time or lock-step). Its background
// work is the MPC step: in real time against its wall-clock deadline; in lock-step without one
// (deterministic), or with --emulate-target charged the target's compute time instead. On
// SIGINT, SIGTERM or the end of --duration the board sends a last ActuatorCommand with the
// safe outputs and prints a summary of key=value pairs. The board lives in static storage;
// once the loop runs nothing is allocated (counted and reported as heap_allocations_in_loop).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "board_main.hpp"
#include "forearm_board.hpp"
#include "forearm_options.hpp"
#include "hmpc/models/forearm_solvers.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using Board = hmpc::firmware::ForearmBoard<double>;

constexpr const char* kProgram = "hmpc-forearm-board";

struct ForearmSupport {
  using Board = ::Board;
  using Description = proto::Description;
  using SafeMessage = proto::ActuatorCommand;
  struct Row {
    std::uint32_t tick;
    float wall_time_s;  // since the control loop started
    proto::BoardMode mode;
    std::uint8_t faults;
    proto::Strategy strategy;
    float v_p, v_m;                           // V, the outputs applied this tick
    std::uint32_t heartbeat_age, sensor_age;  // ticks since the last accepted one
  };
  // Modes and strategies by their DBC names, so the CSV reads like a decoded bus trace.
  static constexpr const char* kCsvHeader =
      "tick,wall_time_s,mode,faults,strategy,v_p,v_m,heartbeat_age,sensor_age";
  static Row log_row(const Board& b, float wall_time_s) {
    const auto& out = b.outputs();
    return {b.ticks(),      wall_time_s,    b.mode(),          b.faults(),    b.strategy(),
            float(out.v_p), float(out.v_m), b.heartbeat_age(), b.sensor_age()};
  }
  static void write_row(std::FILE* file, const Row& r) {
    std::fprintf(file, "%u,%.6f,%s,%u,%s,%.4f,%.4f,%u,%u\n", r.tick, double(r.wall_time_s),
                 proto::value_name(proto::kBoardModeValues, std::uint32_t(r.mode)),
                 unsigned(r.faults),
                 proto::value_name(proto::kStrategyValues, std::uint32_t(r.strategy)),
                 double(r.v_p), double(r.v_m), r.heartbeat_age, r.sensor_age);
  }
  static bool work_due(const Board& b) { return b.mpc_due(); }
  static void run_work(Board& b) { b.run_mpc(); }
  // The MPC step's own deadline is what the board counts as an overrun (mpc_budget_s).
  static void on_late_ticks(Board&) {}
};

}  // namespace

int main(int argc, char** argv) {
  using namespace hmpc::linux_board;
  Options options;
  std::string error;
  const auto outcome = parse_options(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }

  Board::Config config;
  config.node = options.board.node;
  if (options.emulate_cortex_m7) config.emulated_target = &hmpc::forearm::kCortexM7ComputeModel;
  if (options.w_v > 0) config.weights.w_v = options.w_v;
  config.offset_free = options.offset_free;
  config.two_stage_terminal_rate = options.terminal_rate;
  config.solver_failure_from_tick = std::uint32_t(std::lround(options.fail_solver_at_s * 1e3));
  // Lock-step has no deadline: the simulator, not this machine, decides how long a solve takes.
  static Board board(config, options.board.lockstep ? nullptr : &hmpc::platform::monotonic_seconds);
  const proto::ActuatorCommand safe{float(config.safe_v_p), float(config.safe_v_m), 0};

  return run_board<ForearmSupport>(
      kProgram, options.board, board, safe,
      options.emulate_cortex_m7 ? ", emulating the Cortex-M7's compute time" : "",
      [&](const RunResult& r) {
        const LoopStats& stats = r.stats;
        const hmpc::firmware::BoardCounters c = board.counters();
        std::printf(
            "%s: summary ticks=%llu seconds=%.3f ticks_per_s=%.1f mode=%s faults=0x%02x "
            "mpc_steps=%u solver_failures=%u mpc_overruns=%u fallbacks=%u watchdog_trips=%u "
            "sensor_timeouts=%u refused_commands=%u rejected_frames=%u dropped_frames=%u "
            "transmit_failures=%llu interface_down=%llu timer_overruns=%llu max_busy_ms=%.3f "
            "max_wakeup_latency_ms=%.3f "
            "heap_allocations_in_loop=%llu safe_outputs_sent=%d heartbeat_timeout_ticks=%d "
            "sensor_timeout_ticks=%d cost_weight_updates=%u w_theta=%g w_p=%g w_tau=%g w_v=%g "
            "offset_free=%d disturbance_estimate_nm=%.4f two_stage_terminal_rate=%d\n",
            kProgram, static_cast<unsigned long long>(stats.ticks), r.elapsed_s,
            r.elapsed_s > 0 ? double(stats.ticks) / r.elapsed_s : 0.0,
            proto::value_name(proto::kBoardModeValues, std::uint32_t(board.mode())),
            unsigned(board.faults()), c.mpc_steps, c.solver_failures, c.overruns, c.fallbacks,
            c.watchdog_trips, c.sensor_timeouts, c.refused_commands, board.rejects().total(),
            board.dropped_frames(), static_cast<unsigned long long>(stats.transmit_failures),
            static_cast<unsigned long long>(stats.interface_down),
            static_cast<unsigned long long>(stats.timer_overruns), stats.max_busy_s * 1e3,
            stats.max_wakeup_latency_s * 1e3,
            static_cast<unsigned long long>(r.heap_allocations_in_loop), r.safe_sent ? 1 : 0,
            config.heartbeat_timeout_ticks, config.sensor_timeout_ticks, c.cost_weight_updates,
            double(board.config().weights.w_theta), double(board.config().weights.w_P),
            double(board.config().weights.w_tau), double(board.config().weights.w_v),
            board.config().offset_free ? 1 : 0, double(board.disturbance_estimate()),
            board.config().two_stage_terminal_rate ? 1 : 0);
      });
}
