// hmpc-ioc: inverse optimal control for the humanoid (thesis Ch. 4).
//   demos     demonstrations: by the robot's own Coarse MPC under a motion's weights, or by
//             the human demonstrator through retargeting (Sec. 4.2.1)
//   learn     demonstrations -> the 13 weights of Eq. 4.31 (local IOC, Sec. 4.2.2), written to a
//             file and, with --publish-domain, published over DDS to the humanoid controller
//   generate  a motion with learned weights through the Coarse-Fast MPC (Sec. 4.2.3)
//   compare   generation with the initial and the learned weights against the targets
//             (Figs. 4.3-4.5)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/dds/cost_weights.hpp"
#include "hmpc/dds/participant.hpp"
#include "hmpc/humanoid/physical_checks.hpp"
#include "hmpc/humanoid/viewing.hpp"
#include "hmpc/ioc/demonstrations.hpp"
#include "hmpc/ioc/files.hpp"
#include "hmpc/ioc/learn.hpp"
#include "hmpc/ioc/retargeting.hpp"
#include "hmpc/ioc/viewing.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;

constexpr int kFellStatus = 3;
constexpr const char* kProgram = "hmpc-ioc";

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-ioc COMMAND [options]\n"
      "  hmpc-ioc demos --motion NAME|FILE --out FILE [--count D] [--from plans|optima|runs]\n"
      "                 [--duration S] [--threads T]\n"
      "      D demonstrations (1..200, default 4) by the robot's own Coarse MPC (untruncated)\n"
      "      under the motion's weights: 'plans' (default) writes the plan the MPC made at\n"
      "      every sample, 'optima' each of them re-solved towards its local optimum (50\n"
      "      iterations), 'runs' the executed trajectories\n"
      "  hmpc-ioc demos --from human --demonstrator NAME|FILE --motion NAME|FILE --out FILE\n"
      "                 --reference FILE [--count D] [--seed N] [--warping froude|feasibility]\n"
      "                 [--threads T]\n"
      "      D captures of the human demonstrator (NAME: jumping or squatting, in\n"
      "      " HMPC_IOC_DEMONSTRATORS
      "), retargeted to the robot and tracked by its Coarse\n"
      "      MPC (the motion gives the tracking weights); writes the demonstrations and, to\n"
      "      --reference, the demonstrated behaviour as a motion file for learn/generate/compare;\n"
      "      time is scaled by Froude similarity, and with --warping feasibility then bent by\n"
      "      the motion feasibility index (Sec. 4.2.1)\n"
      "  hmpc-ioc learn --motion NAME|FILE --demos FILE --out FILE [--iterations N] [--threads T]\n"
      "      [--estimator likelihood|excess-cost]\n"
      "      [--publish-domain D [--dds-loopback] [--publish-timeout S]]\n"
      "      learns the 13 weights of Eq. 4.31 (N: L-BFGS iterations, 1..1000, default 200);\n"
      "      the motion gives the targets and the weights that are not learned; 'likelihood'\n"
      "      maximises Eq. 4.10, 'excess-cost' (default: it recovers hidden weights and\n"
      "      regenerates the demonstrated motions better, README) then takes the weights'\n"
      "      ratios from the demonstrations' least excess cost over their local optima\n"
      "  hmpc-ioc generate --motion NAME|FILE --weights FILE [--out DIR] [--mpc KIND]\n"
      "                    [--no-truncate] [--duration S] [--threads T]\n"
      "      runs the motion with the learned weights (default Coarse-Fast MPC in real time)\n"
      "      and writes trajectory.csv, filmstrip.png and base.png to DIR\n"
      "  hmpc-ioc compare --motion NAME|FILE --weights FILE [--demonstrator NAME|FILE] [--out "
      "DIR]\n"
      "                   [--mpc KIND] [--no-truncate] [--duration S] [--threads T]\n"
      "      generates the motion with the initial weights (Sec. 4.3.1) and with FILE's, prints\n"
      "      both runs' errors against the motion's targets, and the demonstrator's hidden "
      "weights\n"
      "      if given; writes DIR/weights.png, DIR/compare.png and each run to DIR/initial and\n"
      "      DIR/learned (default DIR: ioc-compare)\n"
      "  S: simulated seconds, 0.03..60 (default: the motion file's)\n"
      "  NAME: a motion shipped in " HMPC_HUMANOID_MOTIONS
      " (e.g. V-low-jump)\n"
      "exit status: 0 done, 2 bad arguments or input file, 1 an output could not be written,\n"
      "%d (generate, compare) the robot fell with the learned weights\n",
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

bool save_demonstrations(const std::string& path,
                         const std::vector<Demonstration>& demonstrations) {
  std::ofstream file(path);
  write_demonstrations(file, demonstrations);
  return static_cast<bool>(file.flush());
}

int demos(const humanoid::Motion& motion, int count, const std::string& from,
          const humanoid::ClosedLoopConfig& run_config, const std::string& out) {
  const int threads = run_config.threads;
  humanoid::ThreadPool pool(threads);
  std::vector<Demonstration> demonstrations;
  for (int i = 0; i < count; ++i) {
    humanoid::ClosedLoopConfig config = run_config;
    config.mpc = humanoid::MpcKind::kCoarse;
    config.truncate = false;
    config.initial_velocity = demonstration_start_velocity(i, count);
    const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(motion, config);
    if (run.fell()) {
      std::printf("demonstration %d: the robot fell at %.2f s; left out\n", i, run.fell_at);
      continue;
    }
    if (from != "runs") {
      const std::vector<Demonstration> made =
          from == "optima" ? coarse_mpc_plans(motion, run, config.problem, &pool, optimum_solver())
                           : coarse_mpc_plans(motion, run, config.problem, &pool);
      demonstrations.insert(demonstrations.end(), made.begin(), made.end());
    } else {
      demonstrations.push_back(demonstration_of(run));
    }
    std::printf("demonstration %d: start velocity (%.3f, %.3f, %.3f) m/s, %zu samples\n", i,
                config.initial_velocity.x(), config.initial_velocity.y(),
                config.initial_velocity.z(), run.samples.size());
  }
  if (demonstrations.empty()) return fail("no demonstration: the robot fell in every run", 1);
  if (!save_demonstrations(out, demonstrations)) return fail("cannot write " + out, 1);
  std::printf("wrote %s: %zu demonstrations\n", out.c_str(), demonstrations.size());
  return 0;
}

// Where learn publishes its weights over DDS (CostWeights on kHumanoidCostWeightsTopic, for
// the humanoid's controller); domain < 0: it does not.
struct Publish {
  long domain = -1;
  bool loopback = false;
  double timeout_s = 10;
};

int learn(const humanoid::Motion& motion, const std::string& demos_path, const LearnConfig& config,
          int threads, const std::string& out, const Publish& publish) {
  const std::vector<Demonstration> demonstrations = load_demonstrations(demos_path);
  humanoid::ThreadPool pool(threads);
  const auto start = std::chrono::steady_clock::now();
  const LocalIoc ioc(motion, demonstrations, &pool);
  std::printf("%zu demonstrations, %d windows of %d steps\n", demonstrations.size(),
              ioc.window_count(), kWindowSteps);
  if (ioc.window_count() == 0) return fail("no demonstration is a whole window long", 2);
  std::printf("iteration   0  log p %.6e (initial weights, Sec. 4.3.1)\n",
              ioc.log_likelihood(config.initial));
  const LearnResult result = learn_weights(ioc, config, [](int i, const Weights&, double value) {
    std::printf("iteration %3d  log p %.6e\n", i, value);
    std::fflush(stdout);
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s after %d iterations (%d likelihood evaluations), %.1f s on %d threads\n",
              result.stop.c_str(), result.iterations, result.evaluations, seconds, threads);
  const Weights file_weights = weights_of(motion.weights);
  std::printf("%-9s %12s %12s\n", "weight", "learned", "motion file");
  for (int k = 0; k < kWeightCount; ++k) {
    std::printf("%-9s %12.5g %12.5g\n", kWeightNames[k], result.weights[k], file_weights[k]);
  }
  std::printf("cosine similarity to the motion file's weights: %.4f\n",
              cosine_similarity(result.weights, file_weights));
  std::ostringstream comment;
  comment << "learned by hmpc-ioc from " << demos_path << ": " << ioc.window_count() << " windows, "
          << result.iterations << " L-BFGS iterations (" << result.stop << "), "
          << (config.estimator == Estimator::kLeastExcessCost ? "least excess cost, " : "")
          << "log p " << result.log_likelihood;
  std::ofstream file(out);
  write_weights(file, result.weights, comment.str());
  if (!file.flush()) return fail("cannot write " + out, 1);
  std::printf("wrote %s\n", out.c_str());
  if (publish.domain < 0) return 0;
  std::vector<std::pair<std::string, double>> named;
  named.reserve(kWeightCount);
  for (int k = 0; k < kWeightCount; ++k) named.emplace_back(kWeightNames[k], result.weights[k]);
  std::string error;
  if (!dds::publish_cost_weights(
          std::uint32_t(publish.domain), publish.loopback ? dds::loopback_config() : std::string(),
          dds::kHumanoidCostWeightsTopic, std::move(named), publish.timeout_s, error)) {
    return fail("publishing the weights: " + error + " (they are in " + out + ")", 1);
  }
  std::printf("published the weights on %s, DDS domain %ld\n", dds::kHumanoidCostWeightsTopic,
              publish.domain);
  return 0;
}

int generate(humanoid::Motion motion, const std::string& stem, const std::string& weights_path,
             const humanoid::ClosedLoopConfig& config, std::string out) {
  motion.weights = with_weights(motion.weights, load_weights(weights_path));
  if (motion.reach.active) return fail("generate runs the biped's motions, not reaching", 2);
  const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(motion, config);
  const humanoid::ClosedLoopSummary s = humanoid::summarise(run);
  std::printf("motion %s with the weights of %s, %s MPC%s: %.2f s simulated\n", stem.c_str(),
              weights_path.c_str(), humanoid::name_of(config.mpc),
              config.truncate ? " in real time" : " (untruncated)", run.samples.back().time);
  std::printf("solve per 30 ms sample: max %.1f ms, median %.1f ms; over 30 ms %d of %zu\n",
              s.max_solve_ms, s.median_solve_ms, s.overruns, run.samples.size());
  std::printf("base point height %.3f..%.3f m\n", s.min_height, s.max_height);
  if (run.fell()) std::printf("the robot FELL at %.2f s\n", run.fell_at);
  const std::string numeral = humanoid::motion_numeral(stem);
  if (!numeral.empty()) {
    const humanoid::PhysicalCheck check = humanoid::check_motion(numeral, motion, run);
    std::printf("physical check of motion %s: %s: %s\n", numeral.c_str(),
                check.passed ? "PASSED" : "FAILED", check.verdict.c_str());
  }
  if (out.empty()) out = "ioc-" + stem + "-" + humanoid::name_of(config.mpc);
  std::string error;
  if (!humanoid::write_run(out,
                           stem + ", learned weights, " + humanoid::name_of(config.mpc) + " MPC",
                           motion, run, 8, error)) {
    return fail(error, 1);
  }
  std::printf("wrote %s/trajectory.csv, filmstrip.png, base.png\n", out.c_str());
  return run.fell() ? kFellStatus : 0;
}

// Step 2c's figures: the feasibility index of the mean aligned capture on the Froude timeline
// and on the one played, and the speed factors' range and the duration they give.
void print_warping(const WarpedCaptures& r) {
  if (r.nominal_index.empty()) return;
  const auto rms = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (const double x : v) sum += x * x;
    return std::sqrt(sum / static_cast<double>(v.size()));
  };
  const auto largest = [](const std::vector<double>& v) {
    return *std::max_element(v.begin(), v.end());
  };
  const auto [slowest, fastest] = std::minmax_element(r.speeds.begin(), r.speeds.end());
  std::printf(
      "feasibility index (body weights): Froude timeline RMS %.3f, largest %.3f; played "
      "RMS %.3f, largest %.3f; speed factors %.2f..%.2f, %.2f s\n",
      rms(r.nominal_index), largest(r.nominal_index), rms(r.warped_index), largest(r.warped_index),
      *slowest, *fastest, (r.states.front().size() - 1) * humanoid::kCoarseStep);
}

int human_demos(const humanoid::Motion& task, const std::string& task_name,
                const std::string& demonstrator_name, int count, int seed, TimeWarping warping,
                int threads, const std::string& out, const std::string& reference_out) {
  const humanoid::Motion demonstrator =
      humanoid::load_motion(humanoid::motion_path(demonstrator_name, HMPC_IOC_DEMONSTRATORS));
  const auto start = std::chrono::steady_clock::now();
  CaptureConfig capture;
  capture.count = count;
  capture.seed = static_cast<std::uint64_t>(seed);
  capture.threads = threads;
  const std::vector<Capture> captures =
      capture_demonstrations(demonstrator, capture, [](int i, const humanoid::ClosedLoopRun& run) {
        if (run.fell()) {
          std::printf("capture %2d: the demonstrator fell at %.2f s; left out\n", i, run.fell_at);
        } else {
          std::printf("capture %2d: %.2f s\n", i, run.samples.back().time);
        }
        std::fflush(stdout);
      });
  if (captures.empty()) return fail("no capture: the demonstrator fell in every performance", 1);
  RetargetConfig config;
  config.threads = threads;
  config.warping = warping;
  const Retargeted r = retarget(captures, task, config, [](int i, const TrackedDemonstration& t) {
    std::printf(
        "tracking %2d: RMS errors joints %.3f rad, height %.3f m, attitude %.3f rad; apex %.3f m, "
        "flight %.0f ms%s\n",
        i, t.errors.joints, t.errors.height, t.errors.attitude, t.apex, 1e3 * t.flight,
        t.fell ? "; the robot FELL, left out" : "");
    std::fflush(stdout);
  });
  std::vector<Demonstration> demonstrations;
  for (const TrackedDemonstration& t : r.tracked) {
    if (!t.fell) demonstrations.push_back(t.demonstration);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%zu captures, time scale %.3f (Froude), %zu demonstrations in %.1f s\n",
              captures.size(), r.warping.time_scale, demonstrations.size(), seconds);
  print_warping(r.warping);
  if (demonstrations.empty())
    return fail("no demonstration: the robot fell in every tracking run", 1);
  if (!save_demonstrations(out, demonstrations)) return fail("cannot write " + out, 1);
  std::ofstream reference(reference_out);
  humanoid::write_motion(reference, r.reference,
                         "The demonstrated behaviour (hmpc-ioc demos --from human): the mean of " +
                             std::to_string(captures.size()) + " retargeted captures of " +
                             demonstrator_name + ",\none phase per 30 ms; the weights are " +
                             task_name + "'s.");
  if (!reference.flush()) return fail("cannot write " + reference_out, 1);
  std::printf("wrote %s: %zu demonstrations; %s: the targets\n", out.c_str(), demonstrations.size(),
              reference_out.c_str());
  return 0;
}

int compare(const humanoid::Motion& motion, const std::string& stem,
            const std::string& weights_path, const std::string& demonstrator,
            const humanoid::ClosedLoopConfig& config, std::string out) {
  const Weights learned = load_weights(weights_path);
  if (out.empty()) out = "ioc-compare";
  const Weights sets[2] = {initial_weights(), learned};
  const char* const names[2] = {"initial", "learned"};
  MotionErrors errors[2];
  bool fell[2];
  for (int k = 0; k < 2; ++k) {
    humanoid::Motion m = motion;
    m.weights = with_weights(motion.weights, sets[k]);
    const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(m, config);
    const humanoid::ClosedLoopSummary s = humanoid::summarise(run);
    errors[k] = motion_errors(motion, run);
    fell[k] = run.fell();
    std::printf(
        "%s weights, %s MPC: max solve %.1f ms, over 30 ms %d of %zu; apex %.3f m, lowest %.3f m, "
        "longest flight %.0f ms%s\n",
        names[k], humanoid::name_of(config.mpc), s.max_solve_ms, s.overruns, run.samples.size(),
        humanoid::apex_height(run), humanoid::lowest_height(run),
        1e3 * humanoid::longest_flight(run),
        fell[k] ? (", FELL at " + std::to_string(run.fell_at) + " s").c_str() : "");
    std::string error;
    if (!humanoid::write_run(out + "/" + names[k], stem + ", " + names[k] + " weights", m, run, 8,
                             error)) {
      return fail(error, 1);
    }
  }
  const HeightRange targets = target_heights(motion);
  std::printf("targets: base height %.3f..%.3f m\n", targets.lowest, targets.highest);
  std::printf("%-28s %10s %10s\n", "RMS error against targets", "initial", "learned");
  std::printf("%-28s %10.4f %10.4f\n", "base height [m]", errors[0].height, errors[1].height);
  std::printf("%-28s %10.4f %10.4f\n", "attitude [rad]", errors[0].attitude, errors[1].attitude);
  std::printf("%-28s %10.4f %10.4f\n", "base velocity [m/s]", errors[0].velocity,
              errors[1].velocity);
  std::vector<WeightSet> pictured = {{names[0], sets[0], true}, {names[1], sets[1], true}};
  if (!demonstrator.empty()) {
    const Weights hidden = weights_of(
        humanoid::load_motion(humanoid::motion_path(demonstrator, HMPC_IOC_DEMONSTRATORS)).weights);
    pictured.push_back({"demonstrator (hidden)", hidden, false});
    // Up to a common scale (IOC's weights have no absolute scale), fixed on the torque weights.
    const double scale = hidden.head<kControlWeights>().array().log().mean() -
                         sets[1].head<kControlWeights>().array().log().mean();
    std::printf("%-9s %12s %12s %12s %22s\n", "weight", "initial", "learned", "hidden",
                "learned/hidden, scaled");
    for (int k = 0; k < kWeightCount; ++k) {
      std::printf("%-9s %12.5g %12.5g %12.5g %22.3f\n", kWeightNames[k], sets[0][k], sets[1][k],
                  hidden[k], std::exp(std::log(sets[1][k] / hidden[k]) + scale));
    }
    std::printf("cosine similarity to the hidden weights: learned %.4f, initial %.4f\n",
                cosine_similarity(sets[1], hidden), cosine_similarity(sets[0], hidden));
  } else {
    std::printf("%-9s %12s %12s\n", "weight", "initial", "learned");
    for (int k = 0; k < kWeightCount; ++k)
      std::printf("%-9s %12.5g %12.5g\n", kWeightNames[k], sets[0][k], sets[1][k]);
  }
  std::string error;
  if (!write_comparison(out, stem, pictured, error)) return fail(error, 1);
  std::printf("wrote %s/weights.png, %s/compare.png, and each run to %s/initial and %s/learned\n",
              out.c_str(), out.c_str(), out.c_str(), out.c_str());
  return fell[1] ? kFellStatus : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2)
    return cli::exit_status(cli::ParseOutcome::kError, kProgram, "a command is required", usage);
  const std::string command = argv[1];
  if (command == "-h" || command == "--help")
    return cli::exit_status(cli::ParseOutcome::kHelp, kProgram, "", usage);
  if (command != "demos" && command != "learn" && command != "generate" && command != "compare") {
    return cli::exit_status(cli::ParseOutcome::kError, kProgram,
                            "unknown command '" + command + "'", usage);
  }
  std::string motion_name, out, demos_path, weights_path, demonstrator, reference;
  int count = 4, seed = 1;
  TimeWarping warping = TimeWarping::kFroude;
  bool warping_given = false;
  LearnConfig learning;
  learning.estimator = Estimator::kLeastExcessCost;
  learning.lbfgs.max_iterations = 200;
  std::string from = "plans";
  bool no_truncate = false;
  Publish publish;
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
  if (command != "learn")
    parser.number("--duration", 0.03, 60.0, "seconds in 0.03..60", config.duration);
  if (command == "demos") {
    parser.integer("--count", 1, 200, count);
    parser.text("--from", [&from](const std::string& v) {
      from = v;
      return v == "plans" || v == "optima" || v == "runs" || v == "human"
                 ? std::string()
                 : cli::bad_value("--from", "plans, optima, runs or human", v);
    });
    parser.text("--demonstrator", required("--demonstrator", demonstrator));
    parser.text("--reference", required("--reference", reference));
    parser.integer("--seed", 0, 1000000, seed);
    parser.text("--warping", [&warping, &warping_given](const std::string& v) {
      warping_given = true;
      if (v == "froude") {
        warping = TimeWarping::kFroude;
      } else if (v == "feasibility") {
        warping = TimeWarping::kFeasibility;
      } else {
        return cli::bad_value("--warping", "froude or feasibility", v);
      }
      return std::string();
    });
  } else if (command == "learn") {
    parser.text("--demos", required("--demos", demos_path));
    parser.integer("--iterations", 1, 1000, learning.lbfgs.max_iterations);
    parser.text("--estimator", [&learning](const std::string& v) {
      if (v == "likelihood") {
        learning.estimator = Estimator::kMaximumLikelihood;
      } else if (v == "excess-cost") {
        learning.estimator = Estimator::kLeastExcessCost;
      } else {
        return cli::bad_value("--estimator", "likelihood or excess-cost", v);
      }
      return std::string();
    });
    // Cyclone maps domain ids to UDP ports 7400 + 250 d + ...: 232 is the last that fits.
    parser.integer("--publish-domain", 0, 232, publish.domain);
    parser.flag("--dds-loopback", publish.loopback);
    parser.number("--publish-timeout", 0.1, 3600, "seconds in 0.1..3600", publish.timeout_s);
  } else {
    parser.text("--weights", required("--weights", weights_path));
    if (command == "compare")
      parser.text("--demonstrator", required("--demonstrator", demonstrator));
    parser.text("--mpc", [&config](const std::string& v) {
      return humanoid::parse_mpc_kind(v, config.mpc)
                 ? std::string()
                 : cli::bad_value("--mpc", "fine, coarse or coarse-fast", v);
    });
    parser.flag("--no-truncate", no_truncate);
  }
  std::string error;
  auto outcome = parser.parse(argc - 1, argv + 1, error);
  if (outcome == cli::ParseOutcome::kRun) {
    const char* missing =
        motion_name.empty()                                                ? "--motion is required"
        : (command == "demos" || command == "learn") && out.empty()        ? "--out is required"
        : command == "learn" && demos_path.empty()                         ? "--demos is required"
        : command != "demos" && command != "learn" && weights_path.empty() ? "--weights is required"
        : from == "human" && demonstrator.empty() ? "--from human needs --demonstrator"
        : from == "human" && reference.empty()    ? "--from human needs --reference"
        : command == "demos" && from != "human" &&
                !(demonstrator.empty() && reference.empty() && !warping_given)
            ? "--demonstrator, --reference and --warping go with --from human"
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
    if (command == "demos" && from == "human") {
      return human_demos(motion, stem_of(motion_name), demonstrator, count, seed, warping,
                         config.threads, out, reference);
    }
    if (command == "demos") return demos(motion, count, from, config, out);
    if (command == "learn")
      return learn(motion, demos_path, learning, config.threads, out, publish);
    if (command == "compare")
      return compare(motion, stem_of(motion_name), weights_path, demonstrator, config, out);
    return generate(motion, stem_of(motion_name), weights_path, config, out);
  } catch (const humanoid::MotionFileError& e) {
    return fail(e.what(), 2);
  } catch (const IocFileError& e) {
    return fail(e.what(), 2);
  } catch (const std::invalid_argument& e) {
    return fail(e.what(), 2);
  }
}
