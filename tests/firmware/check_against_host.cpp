// Host side of the Cortex-M solver test: runs the firmware image under QEMU (the command is
// this program's arguments), recomputes the same runs natively from the same source, and
// compares results. Prints the instructions per MPC update the image measured.
//
// usage: check_against_host <qemu command ...> <image.elf>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>
#include <sys/wait.h>

#include "sec24_runs.hpp"

#ifndef HMPC_SCALAR
#define HMPC_SCALAR double
#endif
using Scalar = HMPC_SCALAR;

namespace {

// Agreement required between the target and the host. Both run the same code with
// -ffp-contract=off and no vectorisation; only libm (newlib vs glibc cos/sin) differs,
// by an ulp at most, which the closed loop may amplify slightly.
constexpr double kRelativeTolerance = sizeof(Scalar) == 8 ? 1e-9 : 1e-4;

// Core clock for the time estimate: STM32H743 (Cortex-M7) at 480 MHz; STM32G474 (M4) 170 MHz.
constexpr int kClockMHz = sizeof(Scalar) == 8 ? 480 : 170;

struct NoTiming {
  void before_update(int) {}
  template <class Vector, class Mpc>
  void after_update(int, const Vector&, const Vector&, const Mpc&) {}
};

struct HostReport {
  std::map<std::string, double> values;        // "method quantity" -> value
  std::map<std::string, std::int64_t> counts;  // "method iterations" -> n
  template <class Outcome>
  void method(const char* name, const Outcome& o, const hmpc::sec24::check::Totals& t) {
    const std::string m(name);
    values[m + " final_y"] = static_cast<double>(o.final_state(0));
    values[m + " final_z"] = static_cast<double>(o.final_state(1));
    values[m + " cost"] = static_cast<double>(o.accumulated_cost);
    counts[m + " iterations"] = t.iterations;
  }
};

double from_bits(const std::string& hex) {
  const std::uint64_t raw = std::stoull(hex, nullptr, 16);
  if (sizeof(Scalar) == 8) {
    double d;
    std::memcpy(&d, &raw, 8);
    return d;
  }
  const std::uint32_t raw32 = static_cast<std::uint32_t>(raw);
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
  hmpc::sec24::check::run_all<Scalar>(timing, host);

  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    std::perror("popen");
    return 2;
  }
  std::map<std::string, double> target;
  std::map<std::string, std::string> target_bits;
  std::map<std::string, std::int64_t> target_counts;
  std::map<std::string, std::string> instructions;
  bool self_check = false;
  std::array<char, 512> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) {
    std::fputs(buffer.data(), stdout);
    std::istringstream line(buffer.data());
    std::string kind, method, quantity, value;
    line >> kind >> method;
    if (kind == "result" && line >> quantity >> value) {
      target[method + " " + quantity] = from_bits(value);
      target_bits[method + " " + quantity] = value;
    } else if (kind == "count" && line >> quantity >> value) {
      target_counts[method + " " + quantity] = std::stoll(value);
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

  bool ok = exit_code == 0 && self_check;
  if (!ok) std::printf("FAIL: image exit status %d, self-check %s\n", exit_code, self_check ? "ok" : "missing/failed");
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
  for (const auto& [key, n] : host.counts) {
    const auto it = target_counts.find(key);
    const std::int64_t t = it == target_counts.end() ? -1 : it->second;
    std::printf("%-26s %22lld %22lld\n", key.c_str(), static_cast<long long>(n),
                static_cast<long long>(t));
  }
  std::printf("%d of %zu results bit-identical to the host (tolerance %.0e relative)\n",
              identical, host.values.size(), kRelativeTolerance);
  for (const auto& [method, text] : instructions) {
    std::printf("instructions per MPC update on the target, %s:%s\n", method.c_str(), text.c_str());
    std::istringstream fields(text);
    std::string label, median_label;
    std::uint64_t max = 0, median = 0;
    fields >> label >> label >> max >> median_label >> median;
    // An estimate, not a measurement: QEMU counts instructions, not cycles.
    std::printf("  at %d MHz and 1 cycle per instruction: max %.0f us, median %.0f us per update "
                "(sampling period 1000 us)\n", kClockMHz, max / double(kClockMHz),
                median / double(kClockMHz));
  }
  std::printf("%s\n", ok ? "target agrees with host" : "target DISAGREES with host");
  return ok ? 0 : 1;
}
