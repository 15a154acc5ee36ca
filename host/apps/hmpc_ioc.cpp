// hmpc-ioc: inverse optimal control for the humanoid (thesis Ch. 4).
//   demos     demonstrations by the robot's own Coarse MPC under a motion's weights
//   learn     demonstrations -> the 13 weights of Eq. 4.31 (local IOC, Sec. 4.2.2)
//   generate  a motion with learned weights through the Coarse-Fast MPC (Sec. 4.2.3)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/humanoid/physical_checks.hpp"
#include "hmpc/humanoid/viewing.hpp"
#include "hmpc/ioc/demonstrations.hpp"
#include "hmpc/ioc/files.hpp"
#include "hmpc/ioc/learn.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;

constexpr int kFellStatus = 3;
constexpr const char* kProgram = "hmpc-ioc";
// The own-MPC demonstrations' starts: the first at rest, the others with the whole robot
// moving at this speed [m/s] in evenly spread horizontal directions (as the humanoid
// benchmark's perturbed starts), so that they differ.
constexpr double kDemoNudge = 0.05;

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: hmpc-ioc COMMAND [options]\n"
               "  hmpc-ioc demos --motion NAME|FILE --out FILE [--count D] [--from plans|runs] [--duration S]\n"
               "                 [--threads T]\n"
               "      D demonstrations (1..200, default 4) by the robot's own Coarse MPC (untruncated)\n"
               "      under the motion's weights: 'plans' (default) writes the plan the MPC made at\n"
               "      every sample, 'runs' the executed trajectories\n"
               "  hmpc-ioc learn --motion NAME|FILE --demos FILE --out FILE [--iterations N] [--threads T]\n"
               "      learns the 13 weights of Eq. 4.31 (N: L-BFGS iterations, 1..1000, default 200);\n"
               "      the motion gives the targets and the weights that are not learned\n"
               "  hmpc-ioc generate --motion NAME|FILE --weights FILE [--out DIR] [--mpc KIND]\n"
               "                    [--no-truncate] [--duration S] [--threads T]\n"
               "      runs the motion with the learned weights (default Coarse-Fast MPC in real time)\n"
               "      and writes trajectory.csv, filmstrip.png and base.png to DIR\n"
               "  S: simulated seconds, 0.03..60 (default: the motion file's)\n"
               "  NAME: a motion shipped in " HMPC_HUMANOID_MOTIONS " (e.g. V-low-jump)\n"
               "exit status: 0 done, 2 bad arguments or input file, 1 an output could not be written,\n"
               "%d (generate) the robot fell\n",
               kFellStatus);
}

int fail(const std::string& message, int status) {
  std::fprintf(stderr, "%s: %s\n", kProgram, message.c_str());
  return status;
}

humanoid::Motion load(const std::string& name) {
  return humanoid::load_motion(humanoid::motion_path(name, HMPC_HUMANOID_MOTIONS));
}

std::string stem_of(const std::string& name) {
  return std::filesystem::path(humanoid::motion_path(name, HMPC_HUMANOID_MOTIONS)).stem().string();
}

int demos(const humanoid::Motion& motion, int count, bool plans, const humanoid::ClosedLoopConfig& run_config,
          const std::string& out) {
  const int threads = run_config.threads;
  humanoid::ThreadPool pool(threads);
  std::vector<Demonstration> demonstrations;
  for (int i = 0; i < count; ++i) {
    humanoid::ClosedLoopConfig config = run_config;
    config.mpc = humanoid::MpcKind::kCoarse;
    config.truncate = false;
    if (i > 0) {
      const double angle = 2.0 * M_PI * (i - 1) / std::max(1, count - 1);
      config.initial_velocity = kDemoNudge * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    }
    const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(motion, config);
    if (run.fell()) {
      std::printf("demonstration %d: the robot fell at %.2f s; left out\n", i, run.fell_at);
      continue;
    }
    if (plans) {
      const std::vector<Demonstration> made = coarse_mpc_plans(motion, run, config.problem, &pool);
      demonstrations.insert(demonstrations.end(), made.begin(), made.end());
    } else {
      demonstrations.push_back(demonstration_of(run));
    }
    std::printf("demonstration %d: start velocity (%.3f, %.3f, %.3f) m/s, %zu samples\n", i,
                config.initial_velocity.x(), config.initial_velocity.y(), config.initial_velocity.z(),
                run.samples.size());
  }
  if (demonstrations.empty()) return fail("no demonstration: the robot fell in every run", 1);
  std::ofstream file(out);
  write_demonstrations(file, demonstrations);
  if (!file.flush()) return fail("cannot write " + out, 1);
  std::printf("wrote %s: %zu demonstrations\n", out.c_str(), demonstrations.size());
  return 0;
}

int learn(const humanoid::Motion& motion, const std::string& demos_path, int iterations, int threads,
          const std::string& out) {
  const std::vector<Demonstration> demonstrations = load_demonstrations(demos_path);
  humanoid::ThreadPool pool(threads);
  const auto start = std::chrono::steady_clock::now();
  const LocalIoc ioc(motion, demonstrations, &pool);
  std::printf("%zu demonstrations, %d windows of %d steps\n", demonstrations.size(), ioc.window_count(), kWindowSteps);
  if (ioc.window_count() == 0) return fail("no demonstration is a whole window long", 2);
  LearnConfig config;
  config.lbfgs.max_iterations = iterations;
  std::printf("iteration   0  log p %.6e (initial weights, Sec. 4.3.1)\n", ioc.log_likelihood(config.initial));
  const LearnResult result = learn_weights(ioc, config, [](int i, const Weights&, double value) {
    std::printf("iteration %3d  log p %.6e\n", i, value);
    std::fflush(stdout);
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s after %d iterations (%d likelihood evaluations), %.1f s on %d threads\n", result.stop.c_str(),
              result.iterations, result.evaluations, seconds, threads);
  const Weights file_weights = weights_of(motion.weights);
  std::printf("%-9s %12s %12s\n", "weight", "learned", "motion file");
  for (int k = 0; k < kWeightCount; ++k) {
    std::printf("%-9s %12.5g %12.5g\n", kWeightNames[k], result.weights[k], file_weights[k]);
  }
  std::printf("cosine similarity to the motion file's weights: %.4f\n", cosine_similarity(result.weights, file_weights));
  std::ostringstream comment;
  comment << "learned by hmpc-ioc from " << demos_path << ": " << ioc.window_count() << " windows, "
          << result.iterations << " L-BFGS iterations (" << result.stop << "), log p " << result.log_likelihood;
  std::ofstream file(out);
  write_weights(file, result.weights, comment.str());
  if (!file.flush()) return fail("cannot write " + out, 1);
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

int generate(humanoid::Motion motion, const std::string& stem, const std::string& weights_path,
             humanoid::ClosedLoopConfig config, std::string out) {
  motion.weights = with_weights(motion.weights, load_weights(weights_path));
  if (motion.reach.active) return fail("generate runs the biped's motions, not reaching", 2);
  const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(motion, config);
  const humanoid::ClosedLoopSummary s = humanoid::summarise(run);
  std::printf("motion %s with the weights of %s, %s MPC%s: %.2f s simulated\n", stem.c_str(), weights_path.c_str(),
              humanoid::name_of(config.mpc), config.truncate ? " in real time" : " (untruncated)",
              run.samples.back().time);
  std::printf("solve per 30 ms sample: max %.1f ms, median %.1f ms; over 30 ms %d of %zu\n", s.max_solve_ms,
              s.median_solve_ms, s.overruns, run.samples.size());
  std::printf("base point height %.3f..%.3f m\n", s.min_height, s.max_height);
  if (run.fell()) std::printf("the robot FELL at %.2f s\n", run.fell_at);
  const std::string numeral = humanoid::motion_numeral(stem);
  if (!numeral.empty()) {
    const humanoid::PhysicalCheck check = humanoid::check_motion(numeral, motion, run);
    std::printf("physical check of motion %s: %s: %s\n", numeral.c_str(), check.passed ? "PASSED" : "FAILED",
                check.verdict.c_str());
  }
  if (out.empty()) out = "ioc-" + stem + "-" + humanoid::name_of(config.mpc);
  std::string error;
  if (!humanoid::write_run(out, stem + ", learned weights, " + humanoid::name_of(config.mpc) + " MPC", motion, run,
                           8, error)) {
    return fail(error, 1);
  }
  std::printf("wrote %s/trajectory.csv, filmstrip.png, base.png\n", out.c_str());
  return run.fell() ? kFellStatus : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return cli::exit_status(cli::ParseOutcome::kError, kProgram, "a command is required", usage);
  const std::string command = argv[1];
  if (command == "-h" || command == "--help") return cli::exit_status(cli::ParseOutcome::kHelp, kProgram, "", usage);
  if (command != "demos" && command != "learn" && command != "generate") {
    return cli::exit_status(cli::ParseOutcome::kError, kProgram, "unknown command '" + command + "'", usage);
  }
  std::string motion_name, out, demos_path, weights_path;
  int count = 4, iterations = 200;
  bool runs = false, no_truncate = false;
  humanoid::ClosedLoopConfig config;
  const auto required = [](const char* option, std::string& target) {
    return [option, &target](const std::string& v) {
      target = v;
      return v.empty() ? std::string(option) + " needs a value" : std::string();
    };
  };
  cli::OptionParser parser;
  parser.text("--motion", required("--motion", motion_name));
  parser.text("--out", required("--out", out));
  parser.integer("--threads", 1, 64, config.threads);
  if (command != "learn") parser.number("--duration", 0.03, 60.0, "seconds in 0.03..60", config.duration);
  if (command == "demos") {
    parser.integer("--count", 1, 200, count);
    parser.text("--from", [&runs](const std::string& v) {
      runs = v == "runs";
      return v == "plans" || v == "runs" ? std::string() : cli::bad_value("--from", "plans or runs", v);
    });
  } else if (command == "learn") {
    parser.text("--demos", required("--demos", demos_path));
    parser.integer("--iterations", 1, 1000, iterations);
  } else {
    parser.text("--weights", required("--weights", weights_path));
    parser.text("--mpc", [&config](const std::string& v) {
      return humanoid::parse_mpc_kind(v, config.mpc) ? std::string()
                                                     : cli::bad_value("--mpc", "fine, coarse or coarse-fast", v);
    });
    parser.flag("--no-truncate", no_truncate);
  }
  std::string error;
  auto outcome = parser.parse(argc - 1, argv + 1, error);
  if (outcome == cli::ParseOutcome::kRun) {
    const char* missing = motion_name.empty()                                        ? "--motion is required"
                          : command != "generate" && out.empty()                     ? "--out is required"
                          : command == "learn" && demos_path.empty()                 ? "--demos is required"
                          : command == "generate" && weights_path.empty()            ? "--weights is required"
                                                                                     : nullptr;
    if (missing != nullptr) {
      outcome = cli::ParseOutcome::kError;
      error = missing;
    }
  }
  if (outcome != cli::ParseOutcome::kRun) return cli::exit_status(outcome, kProgram, error, usage);
  config.truncate = !no_truncate;

  try {
    const humanoid::Motion motion = load(motion_name);
    if (command == "demos") return demos(motion, count, !runs, config, out);
    if (command == "learn") return learn(motion, demos_path, iterations, config.threads, out);
    return generate(motion, stem_of(motion_name), weights_path, config, out);
  } catch (const humanoid::MotionFileError& e) {
    return fail(e.what(), 2);
  } catch (const IocFileError& e) {
    return fail(e.what(), 2);
  } catch (const std::invalid_argument& e) {
    return fail(e.what(), 2);
  }
}
