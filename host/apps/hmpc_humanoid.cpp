// hmpc-humanoid: runs a humanoid motion (Tables 2.2-2.3) in closed loop under a chosen MPC of
// Table 2.4 on the 1 ms simulator, prints its figures and writes its log and pictures
// (trajectory.csv, filmstrip.png, base.png; viewing.hpp).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/humanoid/physical_checks.hpp"
#include "hmpc/humanoid/viewing.hpp"

namespace {

using namespace hmpc::humanoid;

constexpr int kFellStatus = 3;
constexpr int kLostStatus = 4;

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-humanoid --motion NAME|FILE [options]\n"
      "  --motion NAME|FILE  a motion file, or the name of one shipped in\n"
      "                      " HMPC_HUMANOID_MOTIONS
      " (e.g. I-standing, V-low-jump,\n"
      "                      reaching)\n"
      "  --mpc KIND          fine, coarse or coarse-fast (default: coarse-fast)\n"
      "  --duration S        simulated seconds, 0.03..60 (default: the motion file's)\n"
      "  --threads T         linearisation threads, 1..64 (default: 2)\n"
      "  --frames N          stick figures in filmstrip.png, 2..16 (default: 8)\n"
      "  --out DIR           where to write trajectory.csv and the pictures\n"
      "                      (default: humanoid-MOTION-KIND)\n"
      "  --no-warm-start     skip the offline optimisation of the initial inputs\n"
      "  --no-truncate       let a solve run past the sampling time\n"
      "  --real-robot-timing the real robot's Coarse-Fast timing (Sec. 2.7.3): 12 ms\n"
      "                      sampling, upper layer 12 ms x 10, lower 6 ms x 10 (default:\n"
      "                      Table 2.4's 30 ms and 10 ms; not with --mpc fine)\n"
      "  --initial-velocity VX,VY,VZ  the whole robot moving at the start [m/s], world,\n"
      "                      at most 1 m/s (default: at rest)\n"
      "  --estimator NAME    what the MPC solves from: truth (the simulator's state,\n"
      "                      default), invariant-ekf or whole-body-ukf (the estimate\n"
      "                      from a simulated BMI088 IMU and the joint encoders, after\n"
      "                      a 0.5 s rest; the UKF also takes the applied torques;\n"
      "                      biped motions, started at rest); writes estimation.csv\n"
      "                      and estimation.png; or true-base (the simulator's base\n"
      "                      with the encoders' angles and the boards' velocities)\n"
      "  --sensor-seed N     the simulated sensors' noise and biases, 0..2^31 (default 1)\n"
      "  --iteration-cap N   iLQR iterations per sample (Coarse-Fast: per layer), 1..1000\n"
      "                      (default: Table 2.4's %d, reaching Sec. 2.6.2's %d)\n"
      "  --model-slip-velocity V  the slip velocity of the MPC's friction law [m/s],\n"
      "                      0.001..1 (default: the simulated plant's %g)\n"
      "exit status: 0 motion completed, %d the robot fell (head, hips or a knee on the\n"
      "ground), %d the estimate was lost (the MPC stopped), 2 bad arguments or motion\n"
      "file, 1 the log or pictures could not be written\n",
      kIterationCap, kReachingIterationCap, ContactParameters{}.slip_velocity, kFellStatus,
      kLostStatus);
}

// The run on the biped (A = 0) or, for a reaching motion, the robot with an arm (A = 1).
template <int A>
int run_and_report(const Motion& motion, const ClosedLoopConfig& config, const std::string& stem,
                   const std::string& out, int frames) {
  const BasicClosedLoopRun<A> run = run_closed_loop<A>(motion, config);
  const ClosedLoopSummary s = summarise(run);
  const BasicClosedLoopSample<A>& last = run.samples.back();
  std::printf("motion %s, %s MPC%s, %.2f s simulated\n", stem.c_str(), name_of(config.mpc),
              config.warm_start ? "" : " (no warm start)", last.time);
  std::printf(
      "base point height %.3f..%.3f m, final %.3f m; final velocity (%.2f, %.2f, %.2f) m/s\n",
      s.min_height, s.max_height, last.base.position.z(), last.base.velocity.x(),
      last.base.velocity.y(), last.base.velocity.z());
  std::printf(
      "solve per %.0f ms sample: max %.1f ms, median %.1f ms, 99th percentile %.1f ms; mean "
      "iterations %.2f; truncated %d, over %.0f ms %d, unusable %d of %zu\n",
      run.sampling_period * 1e3, s.max_solve_ms, s.median_solve_ms, s.p99_solve_ms,
      s.mean_iterations, s.truncated, run.sampling_period * 1e3, s.overruns, s.unusable,
      run.samples.size());
  std::printf("accumulated cost (Sec. 4.3.1, per 30 ms): %.2f\n", s.total_cost);
  std::printf("applied torque's change per sample: RMS %.3f N m, largest %.2f N m\n",
              s.torque_change_rms, s.torque_change_max);
  if (config.mpc == MpcKind::kCoarseFast) {
    std::printf(
        "lower layer changed an applied torque by over %.0f %% of its limit in %d of %d "
        "samples\n",
        kLowerLayerActs * 100.0, s.lower_layer_acted, s.samples);
  }
  if (run.fell()) {
    std::printf("the robot FELL at %.2f s (head, hips or a knee within %.2f m of the ground)\n",
                run.fell_at, config.fallen_clearance);
  }
  if (config.feedback != StateFeedback::kTruth) {
    const FeedbackErrors e = feedback_errors(run);
    std::printf(
        "%s estimate against the truth, RMS over the samples: torso height %.2f mm, "
        "horizontal velocity %.4f m/s, tilt %.3f deg; degraded in %d of %zu samples\n",
        name_of(config.feedback), 1e3 * e.height_rms, e.horizontal_velocity_rms,
        e.tilt_rms * 180.0 / 3.141592653589793, e.degraded, run.samples.size());
  }
  if (run.estimate_lost()) {
    std::printf("the estimate was LOST at %.2f s: the MPC stopped (a robot's boards would hold)\n",
                run.estimate_lost_at);
  }

  if constexpr (A == 1) {
    const PhysicalCheck check = check_reaching(motion, run);
    std::printf("physical check of reaching: %s: %s\n", check.passed ? "PASSED" : "FAILED",
                check.verdict.c_str());
  } else {
    if (const std::optional<MotionCheck> c = check_for(stem, motion, run)) {
      std::printf("physical check of %s: %s: %s\n", c->what.c_str(),
                  c->check.passed ? "PASSED" : "FAILED", c->check.verdict.c_str());
    }
  }
  const std::string title = stem + ", " + name_of(config.mpc) + " MPC";
  std::string error;
  if (!write_run(out, title, motion, run, frames, error)) {
    std::fprintf(stderr, "hmpc-humanoid: %s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s/trajectory.csv, filmstrip.png, base.png%s\n", out.c_str(),
              config.feedback == StateFeedback::kTruth ? "" : ", estimation.csv, estimation.png");
  return run.fell() ? kFellStatus : run.estimate_lost() ? kLostStatus : 0;
}
}  // namespace

int main(int argc, char** argv) {
  std::string motion_name, out;
  ClosedLoopConfig config;
  bool no_warm_start = false, no_truncate = false;
  int frames = 8;
  hmpc::cli::OptionParser parser;
  parser.text("--motion", [&](const std::string& v) {
    motion_name = v;
    return v.empty() ? std::string("--motion needs a name or file") : std::string();
  });
  parser.text("--mpc", [&](const std::string& v) {
    return parse_mpc_kind(v, config.mpc)
               ? std::string()
               : hmpc::cli::bad_value("--mpc", "fine, coarse or coarse-fast", v);
  });
  parser.number("--duration", 0.03, 60.0, "seconds in 0.03..60", config.duration);
  parser.integer("--threads", 1, 64, config.threads);
  parser.integer("--frames", 2, 16, frames);
  parser.text("--out", [&](const std::string& v) {
    out = v;
    return v.empty() ? std::string("--out needs a directory") : std::string();
  });
  parser.text("--initial-velocity", [&](const std::string& v) {
    const std::string what = "three numbers VX,VY,VZ [m/s] of norm at most 1";
    std::stringstream in(v);
    std::string part;
    for (int i = 0; i < 3; ++i) {
      double value = 0.0;
      if (!std::getline(in, part, ',') || !hmpc::cli::parse_number(part, -1.0, 1.0, value)) {
        return hmpc::cli::bad_value("--initial-velocity", what, v);
      }
      config.initial_velocity[i] = value;
    }
    const bool extra = static_cast<bool>(std::getline(in, part));
    return extra || config.initial_velocity.norm() > 1.0
               ? hmpc::cli::bad_value("--initial-velocity", what, v)
               : std::string();
  });
  parser.text("--estimator", [&](const std::string& v) {
    return parse_state_feedback(v, config.feedback)
               ? std::string()
               : hmpc::cli::bad_value("--estimator",
                                      "truth, invariant-ekf, whole-body-ukf or true-base", v);
  });
  int seed = 1;
  parser.integer("--sensor-seed", 0, 2147483647, seed);
  parser.integer("--iteration-cap", 1, 1000, config.iteration_cap);
  parser.number("--model-slip-velocity", 0.001, 1.0, "m/s in 0.001..1",
                config.problem.model_slip_velocity);
  parser.flag("--no-warm-start", no_warm_start);
  parser.flag("--no-truncate", no_truncate);
  bool real_robot_timing = false;
  parser.flag("--real-robot-timing", real_robot_timing);
  std::string error;
  const auto outcome = parser.parse(argc, argv, error);
  if (outcome == hmpc::cli::ParseOutcome::kRun && motion_name.empty()) {
    return hmpc::cli::exit_status(hmpc::cli::ParseOutcome::kError, "hmpc-humanoid",
                                  "--motion is required", usage);
  }
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, "hmpc-humanoid", error, usage);
  }
  config.warm_start = !no_warm_start;
  config.sensors.seed = static_cast<std::uint64_t>(seed);
  config.truncate = !no_truncate;
  if (real_robot_timing) {
    if (config.mpc == MpcKind::kFine) {
      return hmpc::cli::exit_status(hmpc::cli::ParseOutcome::kError, "hmpc-humanoid",
                                    "--real-robot-timing is for --mpc coarse-fast or coarse",
                                    usage);
    }
    config.timing = kRealRobotTiming;
  }

  Motion motion;
  try {
    motion = load_motion(motion_path(motion_name, HMPC_HUMANOID_MOTIONS));
  } catch (const MotionFileError& e) {
    std::fprintf(stderr, "hmpc-humanoid: %s\n", e.what());
    return 2;
  }
  const std::string stem =
      std::filesystem::path(motion_path(motion_name, HMPC_HUMANOID_MOTIONS)).stem().string();
  if (out.empty()) {
    out = "humanoid-" + stem + "-" + name_of(config.mpc);
    if (config.feedback != StateFeedback::kTruth)
      out += std::string("-") + name_of(config.feedback);
  }

  if (config.feedback != StateFeedback::kTruth &&
      (motion.reach.active || !config.initial_velocity.isZero())) {
    std::fprintf(stderr, "hmpc-humanoid: --estimator %s needs a biped motion started at rest\n",
                 name_of(config.feedback));
    return 2;
  }
  return motion.reach.active ? run_and_report<1>(motion, config, stem, out, frames)
                             : run_and_report<0>(motion, config, stem, out, frames);
}
