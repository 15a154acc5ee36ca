// hmpc-humanoid-hil: the humanoid over CAN (plant, two leg boards, host as programs in lock-step
// over vcan0 and vcan1), one run of a task, and its figures as Sec. 2.7.4 reports the real
// robot's: solves and their share over the 12 ms sampling period, the estimate's errors against
// the plant's truth, each bus's load, sensor-to-torque latency, the lock-step's speed.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "humanoid_hil_run.hpp"

namespace {

namespace cli = hmpc::cli;

void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-humanoid-hil [--seconds S] [--hold-seconds S] [--motion NAME] [--dir DIR]\n"
      "  --seconds S       simulated, 1..600 (default 11.5: 833 solves of 12 ms after the\n"
      "                    take-over at about 1.4 s, as many as Sec. 2.7.4 counts)\n"
      "  --hold-seconds S  the boards' hold before the MPC, 0.6..60 (default 1; the thesis 10)\n"
      "  --motion NAME     the host's task (default hip-hold)\n"
      "  --dir DIR         the run's logs (default $TMPDIR/hmpc-humanoid-hil)\n"
      "Needs vcan0 and vcan1 (hil/vcan/run-with-vcan.sh makes them). Exit status: 0 when the\n"
      "run and its figures are complete; 1 when a program or a log failed; 2 for bad arguments.\n");
}

}  // namespace

int main(int argc, char** argv) {
  hmpc::hil::HumanoidHilConfig config;
  config.seconds = 11.5;
  const char* tmp = std::getenv("TMPDIR");
  config.dir = std::string(tmp ? tmp : "/tmp") + "/hmpc-humanoid-hil";
  std::string motion = "hip-hold";
  cli::OptionParser p;
  p.number("--seconds", 1, 600, "seconds in [1, 600]", config.seconds);
  p.number("--hold-seconds", 0.6, 60, "seconds in [0.6, 60]", config.hold_seconds);
  p.text("--motion", [&motion](const std::string& v) -> std::string {
    if (v.empty() || v.find('/') != std::string::npos) return "--motion needs a motion's name";
    motion = v;
    return {};
  });
  p.text("--dir", [&config](const std::string& v) -> std::string {
    if (v.empty()) return "--dir needs a directory";
    config.dir = v;
    return {};
  });
  std::string error;
  const cli::ParseOutcome outcome = p.parse(argc, argv, error);
  if (outcome != cli::ParseOutcome::kRun) {
    return cli::exit_status(outcome, "hmpc-humanoid-hil", error, print_usage);
  }
  if (config.hold_seconds + 0.5 >= config.seconds) {
    std::fprintf(stderr, "hmpc-humanoid-hil: --seconds must leave the MPC time after the hold\n");
    print_usage(stderr);
    return 2;
  }
  config.host_args = {"--motion", motion};
  std::printf(
      "humanoid over CAN: %s, %.1f s simulated, %.1f s of the boards' hold first; logs in %s\n",
      motion.c_str(), config.seconds, config.hold_seconds, config.dir.c_str());
  std::fflush(stdout);
  const hmpc::hil::HumanoidHilRun run = hmpc::hil::run_humanoid_hil(config);
  if (!run.ok) {
    std::fprintf(stderr, "hmpc-humanoid-hil: the run failed: %s\n", run.error.c_str());
    return 1;
  }
  hmpc::hil::HumanoidHilFigures f;
  if (!hmpc::hil::figures_of(run, f, error)) {
    std::fprintf(stderr, "hmpc-humanoid-hil: %s\n", error.c_str());
    return 1;
  }
  const auto at = [](const hmpc::hil::Summary& s, const char* key) {
    const auto it = s.find(key);
    return it == s.end() ? std::string() : it->second;
  };
  std::printf(
      "| solves | largest solve | over 12 ms | height RMS | horizontal velocity RMS | tilt RMS | "
      "robot bus | I/O bus | sensor to torque | lock-step |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n"
      "| %d | %.2f ms | %.2f %% | %.1f mm | %.3f m/s | %.2f deg | %.1f %% (%.1f %% by design) | "
      "%.1f %% (%.1f %%) | %d..%d ticks, median %.0f | %.3f x real time |\n",
      f.solves, f.largest_solve_ms, 100 * f.share_over_period, 1e3 * f.height_rms,
      f.horizontal_velocity_rms, f.tilt_rms * 180 / 3.14159265358979, 100 * f.robot_bus_load,
      100 * f.robot_bus_design_load, 100 * f.io_bus_load, 100 * f.io_bus_design_load, f.latency_min,
      f.latency_max, f.latency_median, f.lockstep_speed);
  const std::string reason = at(run.host, "reason");
  std::printf(
      "the MPC took over at %.3f s; from then on the hip (base point) within %.1f mm of where it "
      "was, the torso tilted up to %.3f rad and down to %.3f m; the host ended in %s%s\n",
      f.mpc_start_s, 1e3 * f.hip_drift, f.max_tilt, f.min_height, at(run.host, "phase").c_str(),
      reason.empty() ? "" : (" (" + reason + ")").c_str());
  return 0;
}
