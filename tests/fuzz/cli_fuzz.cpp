// Fuzz target for the command lines of the board and the plant node (their parse_options over
// hmpc::cli::OptionParser, which every Linux program uses). The input's first byte picks the
// program; the rest, split at NUL bytes, is argv. Properties: a parse ends in run, help or an
// error with a message; on run every option holds a value inside its declared range, and the
// options that need each other (--emulate-target and --wait-host need --lockstep) agree.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "firmware/boards/linux/forearm_options.hpp"
#include "hil/forearm/plant_node/options.hpp"

namespace {

[[noreturn]] void fail(const char* program, const char* what) {
  std::fprintf(stderr, "CLI fuzz (%s): %s\n", program, what);
  std::abort();
}

bool within(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

template <class Options, class Check>
void parse(const char* program, std::vector<std::string>& words,
           hmpc::cli::ParseOutcome (*parse_options)(int, char**, Options&, std::string&),
           Check&& check) {
  std::vector<char*> argv{const_cast<char*>(program)};
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  Options options;
  std::string error;
  switch (parse_options(int(argv.size() - 1), argv.data(), options, error)) {
    case hmpc::cli::ParseOutcome::kError:
      if (error.empty()) fail(program, "an error without a message");
      break;
    case hmpc::cli::ParseOutcome::kHelp: break;
    case hmpc::cli::ParseOutcome::kRun: check(options); break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<std::string> words(1);
  for (std::size_t i = 1; i < size && words.size() <= 32; ++i) {
    if (data[i] == 0) {
      words.emplace_back();
    } else {
      words.back().push_back(char(data[i]));
    }
  }
  if (data[0] % 2 == 0) {
    namespace board = hmpc::linux_board;
    parse<board::Options>(
        "hmpc-forearm-board", words, board::parse_options, [](const board::Options& o) {
          if (o.board.node > hmpc::forearm_protocol::kMaxNodeId) {
            fail("board", "node out of range");
          }
          if (o.board.interface.empty() || o.board.interface.size() >= IFNAMSIZ)
            fail("board", "bad interface name");
          if (o.w_v != 0 && !within(o.w_v, 1e-6, 1)) fail("board", "--w-v out of range");
          if (o.board.duration_s != 0 && !within(o.board.duration_s, 1e-3, board::kMaxDurationS)) {
            fail("board", "--duration out of range");
          }
          if (o.emulate_cortex_m7 && !o.board.lockstep)
            fail("board", "--emulate-target without --lockstep");
        });
  } else {
    namespace plant = hmpc::hil::plant_node;
    parse<plant::Options>(
        "hmpc-forearm-plant", words, plant::parse_options, [](const plant::Options& o) {
          if (o.node > hmpc::forearm_protocol::kMaxNodeId) fail("plant", "node out of range");
          if (!within(o.theta0, -1.2, 1.6)) fail("plant", "--theta0 out of range");
          if (!within(o.mismatch.mass_scale, 0.5, 2) ||
              !within(o.mismatch.friction_scale, 0.5, 2) ||
              !within(o.mismatch.pam_time_constant_scale, 0.5, 2)) {
            fail("plant", "a mismatch factor out of range");
          }
          if (!within(o.noise_scale, 0, 10)) fail("plant", "--noise out of range");
          if (o.sensor_delay_ms < 0 || o.sensor_delay_ms > plant::kMaxSensorDelayMs) {
            fail("plant", "--sensor-delay-ms out of range");
          }
          if (!within(o.sensor_faults.drop_fraction, 0, 1) ||
              !within(o.sensor_faults.corrupt_fraction, 0, 1) || !o.sensor_faults.check().empty()) {
            fail("plant", "a fault fraction out of range");
          }
          if (!within(o.host_timeout_s, 0.01, 600)) fail("plant", "--host-timeout out of range");
          if (o.wait_host && !o.lockstep) fail("plant", "--wait-host without --lockstep");
        });
  }
  return 0;
}

#ifdef HMPC_FUZZ_REPLAY
#include "fuzz_replay.hpp"

// Seeds: the command lines the HIL runs use, and each option with a bad value.
int main(int argc, char** argv) {
  using hmpc::fuzz::Bytes;
  const auto line = [](std::uint8_t program, const std::vector<std::string>& words) {
    Bytes b{program};
    for (std::size_t i = 0; i < words.size(); ++i) {
      if (i > 0) b.push_back(0);
      b.insert(b.end(), words[i].begin(), words[i].end());
    }
    return b;
  };
  const std::vector<Bytes> seeds{
      line(0, {"--lockstep", "--emulate-target", "cortex-m7", "--node", "3", "--log", "b.csv"}),
      line(0, {"--interface", "can0", "--w-v", "0.02", "--duration", "3"}),
      line(0, {"--node", "16"}),
      line(0, {"--w-v", "nan", "--duration", "1e400"}),
      line(1, {"--lockstep", "--wait-host", "--duration", "1.5", "--noise", "1", "--seed", "7",
               "--mass-scale", "1.05", "--friction-scale", "1.2", "--pam-time-scale", "1.1"}),
      line(1, {"--drop-percent", "5", "--corrupt-percent", "5", "--silence-at", "0.8",
               "--silence-ms", "100", "--sensor-delay-ms", "4", "--host-timeout", "0.3"}),
      line(1, {"--theta0", "2", "--mass-scale", "inf", "--noise", "-1"}),
      line(1, {"--help"}),
  };
  return hmpc::fuzz::replay(argc, argv, "cli_fuzz_replay", seeds, 500, 500);
}
#endif
