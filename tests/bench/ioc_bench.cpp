// Inverse optimal control figures, measured side by side in one run:
//   - linearising the demonstrations' windows (LocalIoc's constructor), 1 thread against 2;
//   - one evaluation of log p(D | w) (Eq. 4.10) with its gradient (the backward and forward
//     passes of local_ioc.hpp) against the value alone, and against the alternative gradient,
//     central differences of the value in each of the 13 weights (26 values), with how far the
//     two gradients differ;
//   - learning (learn_weights: L-BFGS from the initial weights of Sec. 4.3.1), 1 thread against
//     2: wall time, iterations and likelihood evaluations.
// Demonstrations: by default the robot's own Coarse MPC plans along an untruncated Coarse run of
// V-low-jump and of squatting (coarse_mpc_plans, one window a sample), so that the benchmark
// needs nothing but the motion files; with --demos FILE --reference FILE.motion, that file's
// (e.g. written by hmpc-ioc demos --from human, 40 captures, as in the thesis).
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/ioc/demonstrations.hpp"
#include "hmpc/ioc/files.hpp"
#include "hmpc/ioc/learn.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;
using Clock = std::chrono::steady_clock;

struct Task {
  std::string name;
  humanoid::Motion motion;
  std::vector<Demonstration> demonstrations;
};

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: ioc_bench [--demos FILE --reference FILE.motion]\n"
               "  without options: the robot's own Coarse MPC plans on V-low-jump and squatting\n");
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Mean seconds per call of `f`, over at least 0.5 s and 3 calls.
template <typename F>
double seconds_per_call(F&& f) {
  const auto start = Clock::now();
  int calls = 0;
  do {
    f();
    ++calls;
  } while (calls < 3 || seconds_since(start) < 0.5);
  return seconds_since(start) / calls;
}

Task own_plans(const std::string& name) {
  Task task{
      name, humanoid::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/" + name + ".motion"), {}};
  humanoid::ClosedLoopConfig config;
  config.mpc = humanoid::MpcKind::kCoarse;
  config.truncate = false;
  const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(task.motion, config);
  humanoid::ThreadPool pool(config.threads);
  task.demonstrations = coarse_mpc_plans(task.motion, run, config.problem, &pool);
  return task;
}

// Central differences of log p in each weight, step 1e-3 relative: on some jump windows the
// value's round-off is ~1e-5 of it, so smaller steps measure the noise (measured on 40 jump
// captures: 1.4e-3 of the gradient off at 1e-3, 1.2e-2 at 1e-4, 7e-2 at 1e-5).
Weights difference_gradient(const LocalIoc& ioc, const Weights& w) {
  Weights gradient;
  for (int k = 0; k < kWeightCount; ++k) {
    const double h = 1e-3 * w[k];
    Weights up = w, down = w;
    up[k] += h;
    down[k] -= h;
    gradient[k] = (ioc.log_likelihood(up) - ioc.log_likelihood(down)) / (2.0 * h);
  }
  return gradient;
}

void measure(const Task& task) {
  const Weights w = initial_weights();
  double linearise[2], evaluate[2], value_only = 0.0, differences = 0.0, learn_seconds[2],
                                    gradient_difference = 0.0;
  LearnResult learned[2];
  int windows = 0;
  for (int threads = 1; threads <= 2; ++threads) {
    humanoid::ThreadPool pool(threads);
    auto start = Clock::now();
    const LocalIoc ioc(task.motion, task.demonstrations, &pool);
    linearise[threads - 1] = seconds_since(start);
    windows = ioc.window_count();
    Weights gradient;
    evaluate[threads - 1] = seconds_per_call([&] { ioc.log_likelihood(w, &gradient); });
    if (threads == 2) {
      value_only = seconds_per_call([&] { ioc.log_likelihood(w); });
      Weights by_differences;
      differences = seconds_per_call([&] { by_differences = difference_gradient(ioc, w); });
      gradient_difference =
          (by_differences - gradient).cwiseAbs().maxCoeff() / gradient.cwiseAbs().maxCoeff();
    }
    start = Clock::now();
    learned[threads - 1] = learn_weights(ioc, LearnConfig{});
    learn_seconds[threads - 1] = seconds_since(start);
  }
  std::printf("\n%s: %zu demonstrations, %d windows of N = %d coarse steps\n", task.name.c_str(),
              task.demonstrations.size(), windows, kWindowSteps);
  std::printf("                                        1 thread    2 threads   speed-up\n");
  std::printf("  linearising the windows             %9.3f s  %9.3f s  %8.2fx\n", linearise[0],
              linearise[1], linearise[0] / linearise[1]);
  std::printf("  log p and its gradient              %9.2f ms %9.2f ms %8.2fx\n", evaluate[0] * 1e3,
              evaluate[1] * 1e3, evaluate[0] / evaluate[1]);
  std::printf("  learning (L-BFGS)                   %9.2f s  %9.2f s  %8.2fx\n", learn_seconds[0],
              learn_seconds[1], learn_seconds[0] / learn_seconds[1]);
  std::printf(
      "  learning: %d iterations, %d evaluations (%s) on 1 thread; %d, %d (%s) on 2; log p %.6e / "
      "%.6e; "
      "cosine similarity to the motion file's weights %.4f\n",
      learned[0].iterations, learned[0].evaluations, learned[0].stop.c_str(), learned[1].iterations,
      learned[1].evaluations, learned[1].stop.c_str(), learned[0].log_likelihood,
      learned[1].log_likelihood,
      cosine_similarity(learned[1].weights, weights_of(task.motion.weights)));
  std::printf(
      "  2 threads: value alone %.2f ms; gradient by the forward pass %.2f ms, by central "
      "differences "
      "(26 values) %.2f ms: %.1fx; largest difference between them %.1e of the gradient\n",
      value_only * 1e3, evaluate[1] * 1e3, differences * 1e3, differences / evaluate[1],
      gradient_difference);
  std::printf(
      "%s: learning from %d windows in %.2f s on 2 threads (1 thread: %.2f s), speed-up %.2fx\n",
      task.name.c_str(), windows, learn_seconds[1] + linearise[1], learn_seconds[0] + linearise[0],
      (learn_seconds[0] + linearise[0]) / (learn_seconds[1] + linearise[1]));
}

}  // namespace

int main(int argc, char** argv) {
  std::string demos, reference;
  cli::OptionParser parser;
  parser.text("--demos", [&](const std::string& v) {
    demos = v;
    return v.empty() ? std::string("--demos needs a file") : std::string();
  });
  parser.text("--reference", [&](const std::string& v) {
    reference = v;
    return v.empty() ? std::string("--reference needs a motion file") : std::string();
  });
  std::string error;
  const auto outcome = parser.parse(argc, argv, error);
  if (outcome == cli::ParseOutcome::kRun && demos.empty() != reference.empty()) {
    error = "--demos and --reference go together";
  }
  if (outcome != cli::ParseOutcome::kRun || !error.empty()) {
    return cli::exit_status(error.empty() ? outcome : cli::ParseOutcome::kError, "ioc_bench", error,
                            usage);
  }
  try {
    std::vector<Task> tasks;
    if (demos.empty()) {
      for (const char* name : {"V-low-jump", "squatting"}) tasks.push_back(own_plans(name));
    } else {
      tasks.push_back({demos, humanoid::load_motion(reference), load_demonstrations(demos)});
    }
    for (const Task& task : tasks) measure(task);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ioc_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
