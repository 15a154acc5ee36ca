// Host side of a Cortex-M solver test: runs the firmware image under QEMU (the command is
// this program's arguments), recomputes the same runs natively from the same source
// (HMPC_RUNS_HEADER), and compares results. Prints the instructions per MPC update the image
// measured, fits instructions against the solver's work counters (the compute-time model of
// hmpc/mpc/compute_model.hpp), and checks a compiled-in model against the measurement.
//
// usage: check_against_host <qemu command ...> <image.elf>
#include <sys/wait.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include HMPC_RUNS_HEADER

#ifndef HMPC_SCALAR
#define HMPC_SCALAR double
#endif
using Scalar = HMPC_SCALAR;

namespace {

// Agreement required between the target and the host. Both run the same code with
// -ffp-contract=off and no vectorisation; only libm (newlib vs glibc) differs, by an ulp at
// most, which iterative solves may amplify slightly. Float runs are compared more loosely.
constexpr double kRelativeTolerance = sizeof(Scalar) == 8 ? 1e-9 : 1e-4;
// Core clock for the time estimate: our STM32H743 board (Cortex-M7) 400 MHz; STM32G474 (M4)
// 170 MHz.
constexpr int kClockMHz = sizeof(Scalar) == 8 ? 400 : 170;
// A compiled-in compute model must predict each run's total instructions this closely.
constexpr double kComputeModelTolerance = 0.15;

struct NoTiming {
  void before_update(int) {}
  template <class State, class Control, class Mpc>
  void after_update(int, const State&, const Control&, const Mpc&) {}
};

struct HostReport {
  std::map<std::string, double> values;  // "method quantity" -> value
  std::map<std::string, std::int64_t> iterations;
  template <class State>
  void method(const char* name, const State& x, Scalar cost,
              const hmpc::closed_loop_check::Totals& t) {
    const std::string m(name);
    for (int i = 0; i < x.size(); ++i) values[m + " x" + std::to_string(i)] = double(x(i));
    values[m + " cost"] = double(cost);
    iterations[m] = t.iterations;
  }
};

struct Update {
  double instructions;
  hmpc::LayerWork work;
};

double from_bits(const std::string& hex) {
  const std::uint64_t raw = std::stoull(hex, nullptr, 16);
  if (sizeof(Scalar) == 8) {
    double d;
    std::memcpy(&d, &raw, 8);
    return d;
  }
  const auto raw32 = static_cast<std::uint32_t>(raw);
  float f;
  std::memcpy(&f, &raw32, 4);
  return f;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <qemu command ...> <image.elf>\n", argv[0]);
    return 2;
  }
  std::string command;
  for (int i = 1; i < argc; ++i) command += quote(argv[i]) + " ";

  NoTiming timing;
  HostReport host;
  hmpc::closed_loop_check::run_all<Scalar>(timing, host);

  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    std::perror("popen");
    return 2;
  }
  std::map<std::string, double> target;
  std::map<std::string, std::int64_t> target_iterations;
  std::map<std::string, std::string> instructions;
  std::map<std::string, std::vector<Update>> updates;
  std::vector<Update> pending;
  bool self_check = false;
  int update_lines = 0;
  std::array<char, 512> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) {
    std::istringstream line(buffer.data());
    std::string kind;
    line >> kind;
    if (kind == "update") {  // per-update lines are many: keep them out of the log
      Update u{};
      line >> u.instructions >> u.work.upper.rollout_steps >> u.work.upper.derivative_steps >>
          u.work.fast.rollout_steps >> u.work.fast.derivative_steps;
      pending.push_back(u);
      ++update_lines;
      continue;
    }
    std::fputs(buffer.data(), stdout);
    std::string method, quantity, value;
    line >> method;
    if (kind == "result" && line >> quantity >> value) {
      target[method + " " + quantity] = from_bits(value);
    } else if (kind == "count" && line >> quantity >> value) {
      target_iterations[method] = std::stoll(value);
      updates[method] = pending;
      pending.clear();
    } else if (kind == "instructions") {
      std::string rest;
      std::getline(line, rest);
      instructions[method] = rest;
    } else if (kind == "self-check") {
      self_check = method == "ok";
    }
  }
  const int status = pclose(pipe);
  const int exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::printf("(%d per-update lines read)\n", update_lines);

  bool ok = exit_code == 0 && self_check;
  if (!ok)
    std::printf("FAIL: image exit status %d, self-check %s\n", exit_code,
                self_check ? "ok" : "missing/failed");
  int identical = 0;
  std::printf("\n%-26s %22s %22s %10s\n", "quantity", "host", "target", "rel. diff");
  for (const auto& [key, expected] : host.values) {
    const auto it = target.find(key);
    if (it == target.end()) {
      std::printf("FAIL: the image did not report '%s'\n", key.c_str());
      ok = false;
      continue;
    }
    const double diff = std::abs(it->second - expected) / std::max(1.0, std::abs(expected));
    identical += it->second == expected;
    std::printf("%-26s %22.15g %22.15g %10.2e%s\n", key.c_str(), expected, it->second, diff,
                diff <= kRelativeTolerance ? "" : "  <-- FAIL");
    ok = ok && diff <= kRelativeTolerance;
  }
  for (const auto& [method, n] : host.iterations)
    std::printf("%-26s %22lld %22lld\n", (method + " iterations").c_str(),
                static_cast<long long>(n), static_cast<long long>(target_iterations[method]));
  std::printf("%d of %zu results bit-identical to the host (tolerance %.0e relative)\n", identical,
              host.values.size(), kRelativeTolerance);

  for (const auto& [method, text] : instructions) {
    std::printf(
        "instructions per update (an MPC step, or a board's control period) on the target, %s:%s\n",
        method.c_str(), text.c_str());
    std::istringstream fields(text);
    std::string label;
    double max = 0, median = 0;
    fields >> label >> label >> max >> label >> median;
    // An estimate, not a measurement: QEMU counts instructions, not cycles.
    std::printf("  at %d MHz and 1 cycle per instruction: max %.0f us, median %.0f us\n", kClockMHz,
                max / kClockMHz, median / kClockMHz);
  }

  // Least-squares fit of the compute model (hmpc/mpc/compute_model.hpp): instructions =
  // c0 + per-layer costs of rollout and derivative steps. The fast layer starts every update
  // from nu = 0 with the same iteration pattern, so its rollout and derivative steps are
  // collinear: it gets one cost for a step of either kind. Without a two-layer MPC in the
  // runs it is left out.
  std::vector<Update> all;
  for (const auto& [method, list] : updates) all.insert(all.end(), list.begin(), list.end());
  bool any_fast = false, any_work = false;
  for (const Update& u : all) {
    any_fast = any_fast || u.work.fast.rollout_steps > 0;
    any_work = any_work || u.work.upper.rollout_steps > 0;
  }
  const int columns = any_fast ? 4 : 3;
  if (any_work && static_cast<int>(all.size()) >= columns) {  // no solver, no model to fit
    Eigen::MatrixXd A(all.size(), columns);
    Eigen::VectorXd b(all.size());
    for (size_t i = 0; i < all.size(); ++i) {
      const hmpc::LayerWork& w = all[i].work;
      A(i, 0) = 1.0;
      A(i, 1) = w.upper.rollout_steps;
      A(i, 2) = w.upper.derivative_steps;
      if (any_fast) A(i, 3) = w.fast.rollout_steps + w.fast.derivative_steps;
      b(i) = all[i].instructions;
    }
    const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
    const double r2 = 1.0 - (b - A * c).squaredNorm() / (b.array() - b.mean()).square().sum();
    std::printf(
        "compute model fit over %zu updates (R^2 %.4f): per update %.0f; upper layer "
        "%.1f/rollout step, %.1f/derivative step",
        all.size(), r2, c(0), c(1), c(2));
    if (any_fast) std::printf("; fast layer %.1f/step of either kind", c(3));
    std::printf(" instructions\n");
  }

  if (const hmpc::ComputeCostModel* model =
          hmpc::closed_loop_check::compute_model_to_verify<Scalar>()) {
    for (const auto& [method, list] : updates) {
      double measured = 0, predicted = 0;
      for (const Update& u : list) {
        measured += u.instructions;
        predicted += model->instructions(u.work);
      }
      const double error = predicted / measured - 1.0;
      std::printf("compute model vs measured, %s: %+.1f %%%s\n", method.c_str(), 100 * error,
                  std::abs(error) <= kComputeModelTolerance ? "" : "  <-- FAIL (update the model)");
      ok = ok && std::abs(error) <= kComputeModelTolerance;
    }
  }
  std::printf("%s\n", ok ? "target agrees with host" : "target DISAGREES with host");
  return ok ? 0 : 1;
}
